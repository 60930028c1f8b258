// Held contacts (ContactSettings::contact_hold_distance, docs/solver.md): a step whose candidate
// pairs are last step's, none of whose touching pairs has moved past the hold distance in its
// bodies' frames since its contact was packed, keeps the solver's blocks and carries each point's
// separation on from the solve's. These tests hold that to what building the contacts every step
// gives, and check that a step lets go when a body moves or a new pair touches.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <vector>

#include "contact_worlds.h"
#include "rtp/world.h"

namespace rtp {
namespace {

using namespace contact_worlds;

ContactSettings soft_step(double hold, int threads = 1) {
  ContactSettings settings;
  settings.solver = ContactSolver::SoftStep;
  settings.contact_hold_distance = hold;
  settings.threads = threads;
  settings.adaptive_threads = false;  // every step on the team asked for
  return settings;
}

// a pyramid of `rows` rows of unit boxes on the ground, 5 cm apart side by side (beyond the
// speculative distance: at it, a side pair touches and parts as the boxes ring)
void add_pyramid(World& world, int rows) {
  add_ground(world, 0.6);
  for (int row = 0; row < rows; ++row)
    for (int i = 0; i < rows - row; ++i)
      add_box(world, {1.05 * (i - 0.5 * (rows - row - 1)), 0.5 + 1.0 * row, 0.0}, 1.0, 0.6);
}

// A 12-row pyramid (78 boxes) stands 4 s. Settled, its steps hold; every box must then stand
// where building the contacts every step puts it, to two tenths of a millimetre, its energy the same
// to a millijoule. A held step whose separations went on from the wrong base would sink or lift
// the pyramid by the error every step.
TEST(HeldContacts, ASettledPyramidHoldsAndStandsWhereBuiltContactsStandIt) {
  struct Run {
    std::vector<Vec3> positions;
    double energy = 0.0;
    int held = 0;  // of the last second's steps
  };
  auto run = [](double hold) {
    World world(kGravity, Integrator::SemiImplicitEuler, soft_step(hold));
    add_pyramid(world, 12);
    Run out;
    for (int i = 0; i < 240; ++i) {
      world.step(kDt);
      const StepProfile& p = world.profile();
      if (i >= 180) out.held += p.held_contacts > 0 && p.held_contacts == p.contact_pairs;
    }
    for (BodyId b = 0; b < world.body_count(); ++b)
      out.positions.push_back(world.state(b).position);
    out.energy = world.mechanical_energy();
    return out;
  };
  const Run built = run(0.0), held = run(ContactSettings{}.contact_hold_distance);
  EXPECT_EQ(built.held, 0);
  EXPECT_GE(held.held, 54) << "of 60 settled steps";
  double farthest = 0.0;
  for (std::size_t b = 0; b < built.positions.size(); ++b)
    farthest = std::max(farthest, (held.positions[b] - built.positions[b]).norm());
  // (the two lean apart by 1e-5 rad out of the pyramid's plane at most: its top, 11.5 m up,
  // 0.1 mm apart with sixteen lanes a block, 0.006 mm with four or eight; within the hold's
  // bound of 1e-4 rad)
  EXPECT_LT(farthest, 2e-4);
  EXPECT_NEAR(held.energy, built.energy, 1e-3);
}

// A settled 8-row pyramid holds while a box thrown along the ground 6 m away slides 0.5 m and
// stops: the steps of the slide hold some blocks and pack the slider's again (its contacts built
// every step), and every box must end where building every contact every step puts it
TEST(HeldContacts, ASlideBesideASettledPyramidHoldsThePyramidAndEndsAsBuiltContactsEndIt) {
  auto run = [](double hold, int& partly) {
    World world(kGravity, Integrator::SemiImplicitEuler, soft_step(hold));
    add_pyramid(world, 8);
    const BodyId thrown = add_box(world, {-6.0, 0.5, 6.0}, 1.0, 0.3);
    for (int i = 0; i < 120; ++i) world.step(kDt);
    world.apply_impulse(thrown, {2.0, 0.0, 0.0}, world.state(thrown).position);
    partly = 0;
    for (int i = 0; i < 120; ++i) {
      world.step(kDt);
      const StepProfile& p = world.profile();
      partly += p.held_contacts > 0 && p.held_contacts < p.contact_pairs;
    }
    std::vector<Vec3> positions;
    for (BodyId b = 0; b < world.body_count(); ++b) positions.push_back(world.state(b).position);
    return positions;
  };
  int partly_built = 0, partly_held = 0;
  const std::vector<Vec3> built = run(0.0, partly_built);
  const std::vector<Vec3> held = run(ContactSettings{}.contact_hold_distance, partly_held);
  EXPECT_EQ(partly_built, 0);
  EXPECT_GE(partly_held, 20) << "of the slide's 40 steps";
  // v² / 2μg, μ = √(0.3 · 0.6) (the box's and the ground's)
  EXPECT_NEAR(held.back().x(), -6.0 + 2.0 * 2.0 / (2.0 * std::sqrt(0.3 * 0.6) * 9.81), 0.02);
  double farthest = 0.0;
  for (std::size_t b = 0; b < built.size(); ++b)
    farthest = std::max(farthest, (held[b] - built[b]).norm());
  EXPECT_LT(farthest, 1e-4);
}

// A settled column of four lets go of its contacts once a box is struck, and keeps none while it
// moves (the step it is struck in may hold: its poses have not moved yet); a box dropped onto it from 0.5 m comes to rest on top, as it does with the
// contacts built every step: the step where its pair, apart the step before, first touches must
// build its contact (kept, the column's blocks would lack it and the box would fall through)
TEST(HeldContacts, AStackLetsGoWhenABoxIsStruckOrANewOneLands) {
  auto column = [](double hold) {
    auto world = std::make_unique<World>(kGravity, Integrator::SemiImplicitEuler, soft_step(hold));
    add_ground(*world, 0.6);
    for (int i = 0; i < 4; ++i) add_box(*world, {0.0, 0.5 + i, 0.0}, 1.0, 0.6);
    for (int i = 0; i < 120; ++i) world->step(kDt);
    return world;
  };
  {
    auto world = column(ContactSettings{}.contact_hold_distance);
    ASSERT_EQ(world->profile().held_contacts, 4u) << "settled, the column holds";
    world->apply_impulse(4, {0.5, 0.0, 0.0}, world->state(4).position);
    world->step(kDt);
    for (int i = 1; i < 10; ++i) {
      world->step(kDt);
      EXPECT_LT(world->profile().held_contacts, 4u) << "struck, step " << i;
    }
  }
  auto drop = [&](double hold) {
    auto world = column(hold);
    const BodyId dropped = add_box(*world, {0.0, 4.5 + 0.5, 0.0}, 1.0, 0.6);
    std::size_t pairs = world->profile().contact_pairs;
    int new_pairs_held = 0;
    for (int i = 0; i < 120; ++i) {
      world->step(kDt);
      const StepProfile& p = world->profile();
      new_pairs_held += p.held_contacts > 0 && p.contact_pairs != pairs;
      pairs = p.contact_pairs;
    }
    EXPECT_EQ(new_pairs_held, 0);
    EXPECT_EQ(pairs, 5u);
    return world->state(dropped).position;
  };
  const Vec3 built = drop(0.0), held = drop(ContactSettings{}.contact_hold_distance);
  EXPECT_NEAR(held.y(), 4.5, 0.01);
  EXPECT_LT((held - built).norm(), 1e-3);
}

// Without gravity, a box rests against a static one (a contact that holds) while a ball drifts
// at 0.3 m/s along a diagonal towards a static ball: their bounds overlap some 80 steps before
// the balls touch, so the pair is a candidate, found apart, through steps that hold. The step it
// touches must let go and build its contact (held, the step would leave it out, and the ball
// would pass into the other); the ball stops there, as it does with the contacts built every step
TEST(HeldContacts, APairApartInAHeldStepThatTouchesLetsGo) {
  auto run = [](double hold, int& held, double& nearest) {
    World world(Vec3::Zero(), Integrator::SemiImplicitEuler, soft_step(hold));
    add_box(world, {0.0, 0.0, 0.0}, 0.0, 0.6);
    add_box(world, {0.0, 1.0, 0.0}, 1.0, 0.6);
    auto add_ball = [&](const Vec3& at, double mass) {
      BodyDef ball;
      ball.position = at;
      ball.mass = mass;
      ball.principal_inertia = Vec3::Constant(0.4 * mass * 0.25);
      ball.shape.kind = BodyShape::Sphere;
      ball.shape.radius = 0.5;
      ball.friction = 0.6;
      return world.add_body(ball);
    };
    const BodyId fixed = add_ball({10.0, 0.0, 0.0}, 0.0);
    const BodyId drifting = add_ball({11.2, 1.2, 0.0}, 1.0);
    const Vec3 towards = Vec3(-1.0, -1.0, 0.0).normalized();
    world.apply_impulse(drifting, 0.3 * towards, world.state(drifting).position);
    held = 0;
    nearest = HUGE_VAL;
    for (int i = 0; i < 180; ++i) {
      world.step(kDt);
      held += world.profile().held_contacts > 0;
      nearest = std::min(nearest,
                         (world.state(drifting).position - world.state(fixed).position).norm());
    }
    return world.state(drifting).position;
  };
  int held_built = 0, held_held = 0;
  double nearest_built = 0.0, nearest_held = 0.0;
  const Vec3 built = run(0.0, held_built, nearest_built);
  const Vec3 held = run(ContactSettings{}.contact_hold_distance, held_held, nearest_held);
  EXPECT_GE(held_held, 20) << "steps held while the ball drifts and after it stops";
  EXPECT_GT(nearest_held, 0.99) << "the ball must stop where it touches";
  EXPECT_NEAR(nearest_held, nearest_built, 1e-3);
  EXPECT_LT((held - built).norm(), 1e-3);
}

// A 16-row pyramid whose boxes touch side by side, as the scenarios' pyramids do:
// the side contacts start and stop pushing as the pyramid settles, so held steps find their
// colours out of class order and move contacts between lanes (order_held_lanes()). Then the top
// box is pushed along the one below and slides to a stop: its contact, moved to another lane
// while held, must be packed again where it is now, and every box must end where building every
// contact every step puts it
TEST(HeldContacts, ContactsMovedBetweenLanesInHeldStepsEndAsBuiltContactsEndThem) {
  auto run = [](double hold, std::size_t& reordered) {
    World world(kGravity, Integrator::SemiImplicitEuler, soft_step(hold));
    add_ground(world, 0.6);
    constexpr int rows = 16;
    BodyId top = 0;
    for (int row = 0; row < rows; ++row)
      for (int i = 0; i < rows - row; ++i)
        top = add_box(world, {1.0 * (i - 0.5 * (rows - row - 1)), 0.5 + 1.0 * row, 0.0}, 1.0,
                      0.6);
    reordered = 0;
    for (int i = 0; i < 240; ++i) {
      world.step(kDt);
      reordered += world.profile().reordered_contacts;
    }
    world.apply_impulse(top, {0.0, 0.0, 1.5}, world.state(top).position);
    for (int i = 0; i < 120; ++i) world.step(kDt);
    std::vector<Vec3> positions;
    for (BodyId b = 0; b < world.body_count(); ++b) positions.push_back(world.state(b).position);
    return positions;
  };
  std::size_t reordered_built = 0, reordered_held = 0;
  const std::vector<Vec3> built = run(0.0, reordered_built);
  const std::vector<Vec3> held = run(ContactSettings{}.contact_hold_distance, reordered_held);
  EXPECT_EQ(reordered_built, 0u);
  EXPECT_GE(reordered_held, 10u) << "contacts moved between lanes in 4 s";
  // v² / 2μg, μ = 0.6
  EXPECT_NEAR(held.back().z(), 1.5 * 1.5 / (2.0 * 0.6 * 9.81), 0.02);
  // (0.11-0.21 mm apart on the three instruction sets; with a moved contact's block left as
  // it was, the slider's contact stale, 1.3-4.5 mm)
  double farthest = 0.0;
  for (std::size_t b = 0; b < built.size(); ++b)
    farthest = std::max(farthest, (held[b] - built[b]).norm());
  EXPECT_LT(farthest, 5e-4);
}

// held steps give the same bits on one thread and two: 24 × 12 columns of three boxes, each
// dropped from its own small height, settle for 4 s, the last two mostly held; the widest
// colours are packed in two parts, each put in class order on its own
TEST(HeldContacts, HeldStepsGiveTheSameBitsOnOneAndTwoThreads) {
  auto run = [](int threads, int& held, std::size_t& reordered) {
    World world(kGravity, Integrator::SemiImplicitEuler,
                soft_step(ContactSettings{}.contact_hold_distance, threads));
    reordered = 0;
    add_ground(world, 0.6);
    for (int i = 0; i < 24; ++i)
      for (int k = 0; k < 12; ++k) {
        const double drop = 0.01 * ((i * 7 + k * 13) % 11);
        for (int level = 0; level < 3; ++level)
          add_box(world, {1.2 * i, drop + 0.5 + 1.03 * level, 1.2 * k}, 1.0, 0.6);
      }
    held = 0;
    for (int i = 0; i < 240; ++i) {
      world.step(kDt);
      if (i >= 120) held += world.profile().held_contacts > 0;
      reordered += world.profile().reordered_contacts;
    }
    return state_numbers(world);
  };
  int held_one = 0, held_two = 0;
  std::size_t reordered_one = 0, reordered_two = 0;
  const std::vector<double> one = run(1, held_one, reordered_one),
                            two = run(2, held_two, reordered_two);
  EXPECT_GE(held_one, 60) << "of 120 steps";
  EXPECT_EQ(held_one, held_two);
  EXPECT_GT(reordered_one, 0u) << "held contacts moved between lanes";
  EXPECT_EQ(reordered_one, reordered_two);
  ASSERT_EQ(one.size(), two.size());
  std::size_t differ = 0;
  for (std::size_t i = 0; i < one.size(); ++i) differ += one[i] != two[i];
  EXPECT_EQ(differ, 0u) << "of " << one.size() << " numbers";
}

TEST(HeldContacts, ANegativeOrNonFiniteHoldDistanceIsRefused) {
  for (const double hold : {-1e-4, std::nan(""), HUGE_VAL}) {
    ContactSettings settings = soft_step(hold);
    EXPECT_THROW(World(kGravity, Integrator::SemiImplicitEuler, settings), std::invalid_argument)
        << hold;
  }
}

}  // namespace
}  // namespace rtp
