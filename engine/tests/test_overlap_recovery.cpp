// rtp's recovery from overlaps on small worlds: boxes started into each other and into the
// ground, pushed apart by the soft step and, deeper than its push-out reaches in a step, moved
// apart by the recovering step's position passes (docs/solver.md, "Not while recovering").
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "contact_worlds.h"
#include "rtp/world.h"

namespace rtp {
namespace {

using namespace contact_worlds;

// Four unit boxes started 5 cm into each other and into the ground, at rest (the overlap-recovery
// scene): pushed apart, the stack gains m g Σ 5 cm · (k + 1) = 4.9 J of potential energy and
// needs no more. The relax passes of a recovering step take the push-out's speed back; with
// two of them the boxes left at up to 3 m/s and the top flew 0.3 m above its place (12.2 J
// added at the most). The stack must end separated, no box thrown, no overlap much past the
// start's.
TEST(Contacts, AStackStartedIntoItselfIsPushedApartNotThrown) {
  constexpr double kOverlap = 0.05;
  constexpr int kBoxes = 4;
  double gained = 0.0;  // the potential energy of the separated stack over the start's
  for (int k = 0; k < kBoxes; ++k) gained += 9.81 * kOverlap * (k + 1);
  for (const int passes : {ContactSettings{}.recovery_relax_iterations, 2}) {
    ContactSettings settings;
    settings.recovery_relax_iterations = passes;
    World world(kGravity, Integrator::SemiImplicitEuler, settings);
    add_ground(world, 0.6);
    std::vector<BodyId> boxes;
    for (int k = 0; k < kBoxes; ++k)
      boxes.push_back(add_box(world, {0.0, 0.5 - kOverlap + k * (1.0 - kOverlap), 0.0}, 1.0, 0.6));
    const double start = world.mechanical_energy();
    double most = 0.0, deepest = 0.0;
    for (int i = 0; i < 300; ++i) {
      world.step(kDt);
      most = std::max(most, world.mechanical_energy() - start);
      deepest = std::max(deepest, world.deepest_penetration());
    }
    if (passes == 2) {
      EXPECT_GT(most, 2.0 * gained) << "two passes threw the boxes: the setting must be what "
                                       "takes the push-out's speed back";
      continue;
    }
    EXPECT_LT(most, 1.05 * gained) << "the boxes were thrown";
    EXPECT_LT(deepest, 1.2 * kOverlap);
    for (int k = 0; k < kBoxes; ++k) {
      EXPECT_NEAR(world.state(boxes[std::size_t(k)]).position.y(), 0.5 + k, 2e-3) << "box " << k;
      EXPECT_LT(world.velocity(boxes[std::size_t(k)]).norm(), 1e-3) << "box " << k;
    }
  }
}

// 64 unit boxes spawned 0.6 m apart, each 0.4 m into its neighbours and the bottom layer 0.2 m
// into the ground, slightly turned, at rest (the overlap-heap scene). Pushed apart by velocity
// alone, at max_push_speed, the heap takes a dozen steps to come apart and some boxes turn deeper
// into their neighbours on the way; the recovering step's position passes move the poses apart
// first. The heap must never overlap deeper than it started, and without the passes it must (the
// setting is what does it); it must come apart without a throw: the energy added at the most
// within 2 % of the final, all of it the separated boxes' potential energy.
TEST(Contacts, AHeapStartedDeepIntoItselfComesApartNoDeeperThanItStarted) {
  constexpr double kSpacing = 0.6, kSunk = 0.2;
  constexpr int kSide = 4;
  for (const int passes : {ContactSettings{}.recovery_position_iterations, 0}) {
    ContactSettings settings;
    settings.recovery_position_iterations = passes;
    World world(kGravity, Integrator::SemiImplicitEuler, settings);
    add_ground(world, 0.6);
    int turned = 0;
    for (int layer = 0; layer < kSide; ++layer)
      for (int i = 0; i < kSide; ++i)
        for (int k = 0; k < kSide; ++k, ++turned) {
          const Vec3 axis = Vec3(std::sin(1.7 * turned), 1.0, std::cos(2.3 * turned)).normalized();
          add_box(world,
                  {(i - 1.5) * kSpacing, 0.5 - kSunk + layer * kSpacing, (k - 1.5) * kSpacing},
                  1.0, 0.6, 0.0, Quat(Eigen::AngleAxisd(0.1 * std::sin(turned), axis)));
        }
    const double start = world.mechanical_energy();
    world.step(kDt);
    const double at_start = world.deepest_penetration();
    double most = world.mechanical_energy() - start, deepest = at_start;
    for (int i = 1; i < 180; ++i) {
      world.step(kDt);
      most = std::max(most, world.mechanical_energy() - start);
      deepest = std::max(deepest, world.deepest_penetration());
    }
    EXPECT_GT(at_start, 0.39) << "the heap must start deep into itself";
    if (passes == 0) {
      EXPECT_GT(deepest, 1.05 * at_start) << "without position passes the heap must go deeper: "
                                             "the setting must be what keeps it from it";
      continue;
    }
    EXPECT_LE(deepest, 1.005 * at_start) << "the heap went deeper than it started";
    const double final_added = world.mechanical_energy() - start;
    EXPECT_GT(final_added, 0.0) << "the separated heap must hold more potential energy";
    EXPECT_LT(most, 1.02 * final_added) << "the boxes were thrown";
  }
}

}  // namespace
}  // namespace rtp
