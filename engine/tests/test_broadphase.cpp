// Every broad-phase variant against brute force, frame by frame: coherent and jumping motion,
// duplicates, zero-size and exactly touching boxes, boxes added and removed mid-run.
#include <gtest/gtest.h>
#include <rtp/broadphase.h>

#include <algorithm>
#include <random>
#include <set>

namespace {

constexpr rtp::BroadPhaseKind kKinds[] = {rtp::BroadPhaseKind::SeedSap,
                                          rtp::BroadPhaseKind::IncrementalSap,
                                          rtp::BroadPhaseKind::BoxPruning};

std::string kind_name(const testing::TestParamInfo<rtp::BroadPhaseKind>& info) {
  std::string name(rtp::name_of(info.param));
  std::replace(name.begin(), name.end(), '-', '_');
  return name;
}

// Boxes on a quarter-metre grid in a small world, so exact ties (touching faces, equal
// endpoints, duplicates) happen all the time; sizes include zero.
class GridWorld {
 public:
  explicit GridWorld(unsigned seed) : random_(seed) {}

  rtp::Aabb random_box() {
    std::uniform_int_distribution<int> cell(0, 24), size(0, 4);
    rtp::Aabb b;
    for (int k = 0; k < 3; ++k) {
      b.min[k] = 0.25f * float(cell(random_));
      b.max[k] = b.min[k] + 0.25f * float(size(random_));
    }
    return b;
  }
  // a step of at most one grid cell per axis (coherent), or, with probability jump, anywhere
  rtp::Aabb moved(const rtp::Aabb& b, double jump) {
    if (std::bernoulli_distribution(jump)(random_)) return random_box();
    std::uniform_int_distribution<int> step(-1, 1);
    rtp::Aabb m = b;
    for (int k = 0; k < 3; ++k) {
      const float d = 0.25f * float(step(random_));
      m.min[k] += d;
      m.max[k] += d;
    }
    return m;
  }
  std::mt19937& random() { return random_; }

 private:
  std::mt19937 random_;
};

std::vector<rtp::ProxyPair> sorted_pairs(const rtp::BroadPhase& phase) {
  std::vector<rtp::ProxyPair> pairs = phase.pairs();
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

class BroadPhaseVariant : public testing::TestWithParam<rtp::BroadPhaseKind> {};

// thousands of frames, each checked for exact equality with brute force
TEST_P(BroadPhaseVariant, MatchesBruteForceEveryFrameWithAddsAndRemovals) {
  for (double jump : {0.0, 0.05, 1.0}) {  // coherent, mostly coherent, reshuffled
    GridWorld world(7 + unsigned(jump * 100));
    auto phase = rtp::make_broad_phase(GetParam());
    std::vector<rtp::Aabb> boxes;  // by handle
    std::vector<bool> alive;
    auto add = [&](const rtp::Aabb& b) {
      const rtp::ProxyId id = phase->add(b);
      if (id >= boxes.size()) {
        boxes.resize(id + 1);
        alive.resize(id + 1, false);
      }
      boxes[id] = b;
      alive[id] = true;
    };
    for (int i = 0; i < 60; ++i) add(world.random_box());
    // a duplicate of box 0 at the same position
    add(boxes[0]);
    for (int frame = 0; frame < 1000; ++frame) {
      for (std::size_t id = 0; id < boxes.size(); ++id)
        if (alive[id]) {
          boxes[id] = world.moved(boxes[id], jump);
          phase->move(rtp::ProxyId(id), boxes[id]);
        }
      // now and then: a removal, an addition, or both in one frame
      std::uniform_int_distribution<int> dice(0, 9);
      const int roll = dice(world.random());
      if (roll <= 1) {
        std::vector<std::size_t> live;
        for (std::size_t id = 0; id < alive.size(); ++id)
          if (alive[id]) live.push_back(id);
        const std::size_t victim = live[world.random()() % live.size()];
        phase->remove(rtp::ProxyId(victim));
        alive[victim] = false;
      }
      if (roll == 1 || roll == 2) add(world.random_box());
      phase->update();
      ASSERT_EQ(sorted_pairs(*phase), rtp::brute_force_pairs(boxes, alive))
          << rtp::name_of(GetParam()) << ", jump " << jump << ", frame " << frame;
    }
  }
}

// n random boxes added to the phase, by handle
std::vector<rtp::Aabb> add_random_boxes(GridWorld& world, rtp::BroadPhase& phase, int n) {
  std::vector<rtp::Aabb> boxes;
  for (int i = 0; i < n; ++i) {
    boxes.push_back(world.random_box());
    phase.add(boxes.back());
  }
  return boxes;
}

// frames of update, exact equality with brute force, then every box moved by step(id, frame, box)
template <typename Step>
void check_frames(rtp::BroadPhase& phase, std::vector<rtp::Aabb>& boxes, int frames, Step step) {
  for (int frame = 0; frame < frames; ++frame) {
    phase.update();
    ASSERT_EQ(sorted_pairs(phase), rtp::brute_force_pairs(boxes)) << "frame " << frame;
    for (std::size_t id = 0; id < boxes.size(); ++id) {
      boxes[id] = step(id, frame, boxes[id]);
      phase.move(rtp::ProxyId(id), boxes[id]);
    }
  }
}

// a batch large enough to be sorted from scratch, then coherent frames
TEST_P(BroadPhaseVariant, BatchBuildThenCoherentFramesMatchBruteForce) {
  GridWorld world(3);
  auto phase = rtp::make_broad_phase(GetParam());
  std::vector<rtp::Aabb> boxes = add_random_boxes(world, *phase, 800);
  check_frames(*phase, boxes, 20,
               [&](std::size_t, int, const rtp::Aabb& b) { return world.moved(b, 0.0); });
}

// every box carried upwards a little each frame (past any layout of y kept from an earlier frame,
// so boxes sit above it until it is laid out again), some faster than others, and then squeezed
// into a thin layer: the pair set stays exact through all of it
TEST_P(BroadPhaseVariant, BoxesDriftingOutOfAKeptLayoutMatchBruteForce) {
  GridWorld world(4);
  auto phase = rtp::make_broad_phase(GetParam());
  std::vector<rtp::Aabb> boxes = add_random_boxes(world, *phase, 600);
  check_frames(*phase, boxes, 80, [&](std::size_t id, int frame, rtp::Aabb b) {
    if (frame < 60) {
      const float rise = 0.25f * float(1 + id % 3);  // some boxes overtake others
      b.min[1] += rise;
      b.max[1] += rise;
    } else {  // every box's bottom into a layer a quarter of a box high
      const float height = b.max[1] - b.min[1];
      b.min[1] = 0.25f * float(id % 2);
      b.max[1] = b.min[1] + height;
    }
    return world.moved(b, 0.0);
  });
}

// a world wide in x and z and low in y (box pruning lays its slabs across z there: many-pyramids'
// layout), every box drifting a little each frame; then drawn up into a tall column over some
// frames, so that a kept layout across z meets boxes spread in y and is laid out again (across
// y), and spread back out: the pair set stays exact through all of it
TEST_P(BroadPhaseVariant, AWorldWideInZAndLowInYMatchesBruteForceAsItChangesShape) {
  std::mt19937 random(11);
  std::uniform_real_distribution<float> across(0.0f, 40.0f), deep(0.0f, 150.0f), up(0.0f, 3.0f),
      size(0.5f, 1.0f), step(-0.05f, 0.05f);
  auto phase = rtp::make_broad_phase(GetParam());
  std::vector<rtp::Aabb> boxes(1500);
  for (rtp::Aabb& b : boxes) {
    b.min = {across(random), up(random), deep(random)};
    b.max = {b.min[0] + size(random), b.min[1] + size(random), b.min[2] + size(random)};
    phase->add(b);
  }
  check_frames(*phase, boxes, 50, [&](std::size_t id, int frame, rtp::Aabb b) {
    // frames 10 to 29: each box's z drawn towards 0 (to a third) and its y out to up to 150 m;
    // frames 30 on: its y back down (to an eighth) and its z out again (to 2.7 times)
    float dy = 0.0f, dz = 0.0f;
    if (frame >= 10 && frame < 30) {
      dz = -0.05f * b.min[2];
      dy = 0.05f * 150.0f * float(id) / float(boxes.size());
    } else if (frame >= 30) {
      dz = 0.05f * b.min[2];
      dy = -0.1f * b.min[1];
    }
    for (int k = 0; k < 3; ++k) {
      const float d = step(random) + (k == 1 ? dy : k == 2 ? dz : 0.0f);
      b.min[k] += d;
      b.max[k] += d;
    }
    return b;
  });
}

// a tall world of 5,000 boxes (dozens of box pruning's slabs, enough entries for its sweep to go
// to threads): on two threads the same pairs in the same order as on one, and those exact
TEST_P(BroadPhaseVariant, TwoThreadsFindThePairsOneFinds) {
  std::mt19937 random(7);
  std::uniform_real_distribution<float> across(0.0f, 20.0f), up(0.0f, 100.0f), size(0.25f, 1.0f),
      step(-0.05f, 0.05f);
  auto one = rtp::make_broad_phase(GetParam()), two = rtp::make_broad_phase(GetParam());
  two->set_threads(2);
  std::vector<rtp::Aabb> boxes(5000);
  for (rtp::Aabb& b : boxes) {
    b.min = {across(random), up(random), across(random)};
    b.max = {b.min[0] + size(random), b.min[1] + size(random), b.min[2] + size(random)};
    one->add(b);
    two->add(b);
  }
  for (int frame = 0; frame < 4; ++frame) {
    one->update();
    two->update();
    ASSERT_EQ(two->pairs(), one->pairs()) << "frame " << frame;
    ASSERT_EQ(sorted_pairs(*two), rtp::brute_force_pairs(boxes)) << "frame " << frame;
    for (std::size_t id = 0; id < boxes.size(); ++id) {
      for (int k = 0; k < 3; ++k) {
        const float d = step(random);
        boxes[id].min[k] += d;
        boxes[id].max[k] += d;
      }
      one->move(rtp::ProxyId(id), boxes[id]);
      two->move(rtp::ProxyId(id), boxes[id]);
    }
  }
}

TEST_P(BroadPhaseVariant, TouchingBoxesOverlapAndSeparatedOnesDoNot) {
  auto phase = rtp::make_broad_phase(GetParam());
  const rtp::Aabb unit{{0, 0, 0}, {1, 1, 1}};
  const rtp::ProxyId a = phase->add(unit);
  const rtp::ProxyId face = phase->add({{1, 0, 0}, {2, 1, 1}});         // shares x = 1
  const rtp::ProxyId corner = phase->add({{-1, -1, -1}, {0, 0, 0}});    // shares a corner
  const rtp::ProxyId apart = phase->add({{0, 1.0001f, 0}, {1, 2, 1}});  // 0.1 mm above
  const rtp::ProxyId point = phase->add({{0.5f, 0.5f, 0.5f}, {0.5f, 0.5f, 0.5f}});  // zero size
  phase->update();
  const std::set<rtp::ProxyPair> pairs(phase->pairs().begin(), phase->pairs().end());
  EXPECT_TRUE(pairs.count({a, face}));
  EXPECT_TRUE(pairs.count({a, corner}));
  EXPECT_TRUE(pairs.count({a, point}));
  EXPECT_FALSE(pairs.count({a, apart}));
  EXPECT_FALSE(pairs.count({face, corner}));
}

TEST_P(BroadPhaseVariant, PairsAreOrderedAndUnique) {
  GridWorld world(11);
  auto phase = rtp::make_broad_phase(GetParam());
  for (int i = 0; i < 200; ++i) phase->add(world.random_box());
  phase->update();
  std::set<rtp::ProxyPair> seen;
  for (const rtp::ProxyPair& p : phase->pairs()) {
    EXPECT_LT(p.a, p.b);
    EXPECT_TRUE(seen.insert(p).second) << p.a << "-" << p.b << " listed twice";
  }
  EXPECT_FALSE(seen.empty());
}

TEST_P(BroadPhaseVariant, UnknownHandleIsAnError) {
  auto phase = rtp::make_broad_phase(GetParam());
  const rtp::ProxyId id = phase->add({{0, 0, 0}, {1, 1, 1}});
  EXPECT_THROW(phase->move(id + 1, {}), std::out_of_range);
  phase->remove(id);
  EXPECT_THROW(phase->remove(id), std::out_of_range);
}

INSTANTIATE_TEST_SUITE_P(AllVariants, BroadPhaseVariant, testing::ValuesIn(kKinds), kind_name);

TEST(SeedSap, RefusesMoreBoxesThanItsPairTableHolds) {
  auto phase = rtp::make_broad_phase(rtp::BroadPhaseKind::SeedSap);
  for (std::size_t i = 0; i < rtp::kSeedSapMaxProxies; ++i) phase->add({});
  try {
    phase->add({});
    FAIL() << "expected a length_error";
  } catch (const std::length_error& e) {
    EXPECT_NE(std::string(e.what()).find("pair table"), std::string::npos) << e.what();
  }
}

TEST(Bounds, BoxBoundsAreTheTightBoundsOfItsCorners) {
  std::mt19937 random(5);
  std::normal_distribution<double> normal;
  const rtp::Vec3 half(0.5, 1.0, 2.0);
  std::vector<rtp::Vec3> corners;
  for (int c = 0; c < 8; ++c)
    corners.push_back(half.cwiseProduct(rtp::Vec3(c & 1 ? 1 : -1, c & 2 ? 1 : -1, c & 4 ? 1 : -1)));
  for (int trial = 0; trial < 100; ++trial) {
    const rtp::Quat q =
        rtp::Quat(normal(random), normal(random), normal(random), normal(random)).normalized();
    const rtp::Vec3 p(normal(random), normal(random), normal(random));
    const rtp::Aabb from_box = rtp::bounds_of_box(half, p, q);
    const rtp::Aabb from_corners = rtp::bounds_of_points(corners, p, q);
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(from_box.min[k], from_corners.min[k], 1e-5);
      EXPECT_NEAR(from_box.max[k], from_corners.max[k], 1e-5);
    }
  }
  const rtp::Aabb sphere = rtp::bounds_of_sphere(rtp::Vec3(1, 2, 3), 0.5);
  EXPECT_FLOAT_EQ(sphere.min[1], 1.5f);
  EXPECT_FLOAT_EQ(sphere.max[2], 3.5f);
}

}  // namespace
