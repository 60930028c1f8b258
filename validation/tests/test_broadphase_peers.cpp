// Every engine's broad phase on the broadphase scene, every motion: never a missing pair; rtp's
// variants report exactly the exact set (the peers' fattened boxes may add pairs, which the
// benchmark counts).
#include <gtest/gtest.h>
#include <physbench/broadphase.h>

#include <set>

namespace {

using physbench::BroadphaseMotion;

TEST(BroadphaseScene, ExactPairsAgreeWithBruteForce) {
  for (BroadphaseMotion motion : {BroadphaseMotion::Coherent, BroadphaseMotion::Reshuffled,
                                  BroadphaseMotion::Line, BroadphaseMotion::AllOverlapping}) {
    physbench::BroadphaseScene scene;
    scene.count = 400;
    scene.motion = motion;
    physbench::BroadphaseFrames frames(scene);
    for (int f = 0; f < 5; ++f, frames.advance())
      EXPECT_EQ(physbench::exact_pairs(frames.boxes()), rtp::brute_force_pairs(frames.boxes()))
          << physbench::name_of(motion) << " frame " << f;
  }
}

TEST(BroadphaseScene, MeanOverlapSizesTheCube) {
  // about one partner per box at the default overlap: far from none and from all
  physbench::BroadphaseScene scene;
  scene.count = 5000;
  const physbench::BroadphaseFrames frames(scene);
  const double partners = 2.0 * double(physbench::exact_pairs(frames.boxes()).size()) / 5000.0;
  EXPECT_GT(partners, 0.5);
  EXPECT_LT(partners, 1.5);
}

TEST(BroadphaseScene, MotionsAreNamedBothWays) {
  EXPECT_EQ(physbench::broadphase_motion_named("line"), BroadphaseMotion::Line);
  EXPECT_FALSE(physbench::broadphase_motion_named("sideways").has_value());
}

TEST(BroadphasePeers, NoEngineMissesAPairAndRtpAddsNone) {
  const auto entries = physbench::broadphase_engines();
  ASSERT_GE(entries.size(), 3u);  // rtp's three variants at least
  for (bool planar : {false, true})
    for (BroadphaseMotion motion : {BroadphaseMotion::Coherent, BroadphaseMotion::Reshuffled,
                                    BroadphaseMotion::Line, BroadphaseMotion::AllOverlapping}) {
      physbench::BroadphaseScene scene;
      scene.count = 300;
      scene.motion = motion;
      scene.planar = planar;
      for (const auto& entry : entries) {
        if (entry.unsupported(scene)) continue;
        physbench::BroadphaseFrames frames(scene);
        auto engine = entry.create();
        engine->build(frames.boxes());
        for (int f = 0; f < 8; ++f) {
          frames.advance();
          const std::size_t reported = engine->update(frames.boxes());
          const auto agreement =
              physbench::compare_pairs(engine->pairs(), physbench::exact_pairs(frames.boxes()));
          const std::string where = entry.name + " on " + physbench::name_of(motion) +
                                    (planar ? " (planar)" : "") + ", frame " + std::to_string(f);
          EXPECT_EQ(agreement.missing, 0u) << where;
          EXPECT_EQ(reported, agreement.reported) << where;
          if (entry.engine == "rtp") {
            EXPECT_EQ(agreement.extra, 0u) << where;
          }
        }
      }
    }
}

TEST(BroadphasePeers, EveryEngineOfThisBuildIsListed) {
  std::set<std::string> engines;
  for (const auto& e : physbench::broadphase_engines()) engines.insert(e.engine);
  EXPECT_TRUE(engines.count("rtp"));
#ifdef PHYSBENCH_HAVE_BULLET
  EXPECT_TRUE(engines.count("bullet"));
#endif
#ifdef PHYSBENCH_HAVE_ODE
  EXPECT_TRUE(engines.count("ode"));
#endif
#ifdef PHYSBENCH_HAVE_BOX2D
  EXPECT_TRUE(engines.count("box2d"));
#endif
}

TEST(BroadphasePeers, SeedSapSaysWhyItCannotHoldALargeScene) {
  physbench::BroadphaseScene scene;
  scene.count = 100000;
  for (const auto& e : physbench::broadphase_engines())
    if (e.name == "rtp/seed-sap") {
      const auto why = e.unsupported(scene);
      ASSERT_TRUE(why.has_value());
      EXPECT_NE(why->find("n²/2"), std::string::npos) << *why;
    }
}

}  // namespace
