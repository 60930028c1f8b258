// rtp's narrow phase against Bullet's on tens of thousands of random pose pairs: the overlap
// verdict outside the tolerance band, depth and normal where both see a contact, and every rtp
// contact point on both surfaces. The tolerances are NarrowphaseTolerances' defaults, the same
// the report states.
#include <gtest/gtest.h>
#include <physbench/narrowphase.h>

#include <iostream>
#include <sstream>

namespace physbench {
namespace {

std::string describe(const NarrowphaseSet& set, const NarrowphaseAgreement& a) {
  std::ostringstream out;
  out << set.name() << ": " << a.pairs << " pairs, " << a.in_band << " in the band, verdict "
      << a.verdict_agree << "/" << a.pairs - a.in_band << ", depth " << a.depth_agree << "/"
      << a.both_deep << " (worst " << a.worst_depth_error << " m), normal " << a.normal_agree << "+"
      << a.normal_tie << " ties/" << a.both_deep << " (worst " << a.worst_normal_degrees
      << "°), peer refuted " << a.peer_refuted << ", points on both " << a.points_on_both << "/"
      << a.points;
  if (!a.disagreements.empty()) out << "; first disagreement: pair " << a.disagreements.front();
  return out.str();
}

struct Case {
  NarrowphaseShapes shapes;
  NarrowphaseRegime regime;
};

class AgainstBullet : public ::testing::TestWithParam<Case> {};

TEST_P(AgainstBullet, VerdictDepthNormalAndSurfaceAgree) {
  const std::vector<NarrowphasePeerEntry> peers = bullet_narrowphases();
  if (peers.empty()) GTEST_SKIP() << "built without Bullet";
  const NarrowphaseSet set = make_narrowphase_set(GetParam().shapes, GetParam().regime, 2000, 7);
  int compared = 0;
  for (const NarrowphasePeerEntry& peer : peers) {
    if (peer.unsupported(set)) continue;
    ++compared;
    auto engine = peer.create(set);
    const NarrowphaseAgreement a = compare_narrowphase(set, *engine);
    std::string detail;
    for (std::size_t k = 0; k < std::min<std::size_t>(3, a.disagreements.size()); ++k) {
      const std::size_t i = a.disagreements[k];
      const NarrowphasePair& p = set.pairs[i];
      rtp::Manifold m;
      const bool touching = rtp::collide(set.hulls, set.shapes[p.shape_a], p.pose_a,
                                         set.shapes[p.shape_b], p.pose_b, m);
      const PeerContact theirs = engine->collide(i);
      std::ostringstream line;
      line << "\n  pair " << i << ": rtp " << (touching ? "touching" : "apart") << " depth "
           << m.depth << " normal " << m.normal.transpose() << " (" << int(m.count)
           << " points, type " << int(m.points[0].feature.type) << "); peer "
           << (theirs.touching ? "touching" : "apart") << " depth " << theirs.depth << " normal "
           << theirs.normal.transpose();
      detail += line.str();
    }
    SCOPED_TRACE(peer.name + " " + describe(set, a) + detail);
    // every pair agrees, or the exact check shows the peer wrong
    EXPECT_TRUE(a.disagreements.empty());
    // and the peer is rarely wrong: a broken comparison would not pass quietly as "refuted"
    EXPECT_LT(a.peer_refuted, a.pairs / 10);
    EXPECT_EQ(a.points_on_both, a.points);
    // the band must not swallow the set: most pairs are compared
    EXPECT_LT(a.in_band, a.pairs / 4);
    if (GetParam().regime == NarrowphaseRegime::Deep) {
      EXPECT_GT(a.both_deep, a.pairs * 9 / 10);
    }
    if (GetParam().regime == NarrowphaseRegime::Separated) {
      EXPECT_EQ(a.points, 0u);
    }
    std::cout << peer.name << " " << describe(set, a) << "\n";
  }
  EXPECT_GT(compared, 0);
}

INSTANTIATE_TEST_SUITE_P(
    NarrowPhase, AgainstBullet,
    ::testing::Values(Case{NarrowphaseShapes::BoxBox, NarrowphaseRegime::Separated},
                      Case{NarrowphaseShapes::BoxBox, NarrowphaseRegime::Touching},
                      Case{NarrowphaseShapes::BoxBox, NarrowphaseRegime::Deep},
                      Case{NarrowphaseShapes::BoxBox, NarrowphaseRegime::NearlyParallel},
                      Case{NarrowphaseShapes::HullHull, NarrowphaseRegime::Separated},
                      Case{NarrowphaseShapes::HullHull, NarrowphaseRegime::Touching},
                      Case{NarrowphaseShapes::HullHull, NarrowphaseRegime::Deep},
                      Case{NarrowphaseShapes::SphereHull, NarrowphaseRegime::Separated},
                      Case{NarrowphaseShapes::SphereHull, NarrowphaseRegime::Touching},
                      Case{NarrowphaseShapes::SphereHull, NarrowphaseRegime::Deep},
                      Case{NarrowphaseShapes::BoxHull, NarrowphaseRegime::Touching},
                      Case{NarrowphaseShapes::BoxHull, NarrowphaseRegime::Deep}),
    [](const ::testing::TestParamInfo<Case>& info) {
      std::string name = name_of(info.param.shapes) + "_" + name_of(info.param.regime);
      for (char& c : name)
        if (c == '-') c = '_';
      return name;
    });

TEST(NarrowPhaseSets, BadRequestsAreRefusedWithTheReason) {
  try {
    make_narrowphase_set(NarrowphaseShapes::HullHull, NarrowphaseRegime::NearlyParallel, 10, 1);
    FAIL() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("box-box"), std::string::npos);
  }
}

TEST(NarrowPhaseSets, RegimesPlaceThePairsWhereTheySay) {
  // separated pairs never touch, deep ones always do, by rtp's own verdict
  rtp::Manifold m;
  for (auto shapes : {NarrowphaseShapes::BoxBox, NarrowphaseShapes::HullHull}) {
    const NarrowphaseSet apart = make_narrowphase_set(shapes, NarrowphaseRegime::Separated, 200, 3);
    const NarrowphaseSet deep = make_narrowphase_set(shapes, NarrowphaseRegime::Deep, 200, 3);
    for (const NarrowphasePair& p : apart.pairs)
      EXPECT_FALSE(rtp::collide(apart.hulls, apart.shapes[p.shape_a], p.pose_a,
                                apart.shapes[p.shape_b], p.pose_b, m));
    for (const NarrowphasePair& p : deep.pairs) {
      ASSERT_TRUE(rtp::collide(deep.hulls, deep.shapes[p.shape_a], p.pose_a,
                               deep.shapes[p.shape_b], p.pose_b, m));
      EXPECT_GT(m.depth, 0.01);
    }
  }
}

}  // namespace
}  // namespace physbench
