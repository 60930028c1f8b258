// Contact scenes: every scene is valid data, the contact metrics measure what they say on
// synthetic trajectories, and each peer adapter runs contacts and shows a physical fact (a
// bounce against the closed form computed here, the pair rule on a slope, Box2D's skin, a MuJoCo
// buffer overflow as a failure). None of these depends on rtp's rows: rtp's contact solver is
// built elsewhere.
#include <gtest/gtest.h>

#include <cmath>

#include "physbench/metrics.h"
#include "physbench/scenarios.h"
#include "physbench/scene_json.h"
#include "support.h"
#ifdef PHYSBENCH_HAVE_MUJOCO
#include "physbench/mujoco_buffers.h"
#include "physbench/registry.h"

// the linked MuJoCo build's name ("mujoco-2.2" where MuJoCo 4, in physbench-mujoco4, is the
// mujoco row)
static const std::string kMujoco = physbench::mujoco_engine_name();
#endif

namespace {

using namespace physbench;

SimulateOptions untimed() {
  SimulateOptions options;
  options.timing_budget = 0.0;  // tests measure physics, never speed
  return options;
}

struct ContactRun {
  RunResult run;
  ErrorSummary summary;
  ContactSummary contact;
};

// what the runner computes for a row, in process
ContactRun run_contacts(const std::string& engine, const std::string& variant, const Scene& scene) {
  ContactRun r;
  r.run = simulate(physbench::testing::engine(engine), variant, scene, untimed());
  EXPECT_EQ(r.run.status, Status::Ok) << engine << "/" << variant << " on " << scene.name << ": "
                                      << r.run.message;
  if (r.run.status != Status::Ok) return r;
  const ErrorSeries series = compare(scene, r.run.trajectory, nullptr);
  r.summary = summarise(series);
  r.contact = contact_summary(scene, r.run.trajectory, series);
  return r;
}

std::vector<Scene> contact_scenes() {
  std::vector<Scene> scenes;
  for (const Scenario& s : contact_scenarios()) scenes.push_back(s.build());
  return scenes;
}

// ---- the scenes as data ----

TEST(ContactScenes, EveryOneValidatesAndSurvivesJson) {
  const auto scenes = contact_scenes();
  ASSERT_EQ(scenes.size(), 29u);
  for (const Scene& scene : scenes) {
    EXPECT_NO_THROW(validate(scene)) << scene.name;
    EXPECT_TRUE(scene.has_contacts()) << scene.name;
    // rain and overlap-heap are 3D piles; many-pyramids stands its walls side by side in z
    EXPECT_EQ(scene.planar,
              scene.name != "rain" && scene.name != "many-pyramids" && scene.name != "overlap-heap")
        << scene.name;
    const Scene back = scene_from_json(to_json(scene), scene.name);
    EXPECT_EQ(back.bodies.size(), scene.bodies.size()) << scene.name;
    EXPECT_EQ(back.probe.metrics, scene.probe.metrics) << scene.name;
    EXPECT_TRUE(find_scenario(scene.name)) << scene.name << " is not in the default suite";
  }
}

TEST(ContactScenes, NamesAndShapesAreAsSpecified) {
  EXPECT_EQ(pyramid_scene(20).bodies.size(), 211u);   // 210 boxes and the ground
  EXPECT_EQ(pyramid_scene(100).bodies.size(), 5051u);
  // Box3D's many_pyramids: 14 x 14 walls of 55 boxes, bases 1 m apart in x (11 m centre to
  // centre), rows 152/13 m apart in z, every box on the ground or on two below it
  const Scene many = many_pyramids_scene(14, 10);
  ASSERT_EQ(many.bodies.size(), 10781u);
  Vec3 lo = Vec3::Constant(1e9), hi = Vec3::Constant(-1e9);
  for (std::size_t i = 1; i < many.bodies.size(); ++i) {
    lo = lo.cwiseMin(many.bodies[i].position);
    hi = hi.cwiseMax(many.bodies[i].position);
  }
  EXPECT_NEAR(lo.x(), -76.0, 1e-12);  // the first base box's centre: −71.5 − 4.5
  EXPECT_NEAR(hi.x(), 76.0, 1e-12);
  EXPECT_NEAR(lo.z(), -76.0, 1e-12);
  EXPECT_NEAR(hi.z(), 76.0, 1e-12);
  EXPECT_NEAR(lo.y(), 0.5, 1e-12);
  EXPECT_NEAR(hi.y(), 9.5, 1e-12);
  // the last base box of wall 0 (body 10) and the first of wall 1 (body 56): 1 m between faces
  EXPECT_NEAR(many.bodies[56].position.x() - many.bodies[10].position.x(), 2.0, 1e-12);
  EXPECT_EQ(many.dt, 1.0 / 60.0);
  EXPECT_EQ(many.step_count(), 100);
  EXPECT_EQ(bounce_scene(0.5).name, "bounce-e0.5");
  EXPECT_EQ(mass_ratio_scene(1000).name, "mass-ratio-1000");
  EXPECT_EQ(tunnelling_scene(120).name, "tunnelling-120");
  EXPECT_DOUBLE_EQ(tunnelling_scene(30).dt, 1.0 / 30.0);
  EXPECT_EQ(find_scenario("pyramid-100")->build().duration, 1.0);  // short in the suite
  EXPECT_EQ(pyramid_scene(100).duration, 10.0);
  // the bounce box's bottom face starts 1 m above the ground plane
  const Scene bounce = bounce_scene(0.8);
  EXPECT_DOUBLE_EQ(bounce.bodies[1].position.y() - bounce.bodies[1].shape.half_extents.y(), 1.0);
  // pyramid rows sit half a box in from the row below
  const Scene pyramid = pyramid_scene(10);
  EXPECT_DOUBLE_EQ(pyramid.bodies[11].position.x() - pyramid.bodies[1].position.x(), 0.5);
}

// exactly touching means touching: rtp's narrow phase sees no overlap at the start, and the
// overlap scene starts 5 cm deep
TEST(ContactScenes, StartsExactlyTouchingOrAsOverlappedAsSaid) {
  for (const Scene& scene : {tower_scene(20), pyramid_scene(20), mass_ratio_scene(100),
                             overlap_recovery_scene(), incline_scene(30)}) {
    Trajectory start;
    start.bodies = scene.probed_bodies();
    Sample s;
    for (int b : start.bodies)
      s.bodies.push_back({scene.bodies[b].position, scene.bodies[b].orientation});
    start.samples.push_back(s);
    const ErrorSeries series = compare(scene, start, nullptr);
    ASSERT_EQ(series.penetration.size(), 1u);
    const double expected = scene.name == "overlap-recovery" ? 0.05 : 0.0;
    EXPECT_NEAR(series.penetration[0], expected, 1e-9) << scene.name;
  }
}

// ---- the metrics on trajectories made here ----

TEST(ContactMetrics, DriftHeightAndVerdicts) {
  const Scene scene = tower_scene(10);
  Trajectory run = physbench::testing::held_still(scene, 121);
  ErrorSeries series = compare(scene, run, nullptr);
  ContactSummary c = contact_summary(scene, run, series);
  EXPECT_EQ(c.verdict, "stands");
  EXPECT_EQ(*c.top_height_change, 0.0);
  EXPECT_EQ(*c.rest_speed_rms, 0.0);
  // the top box slides 0.3 m along z and drops 2 cm: horizontal drift is 0.3 m, not 0.3002
  run.samples.back().bodies.back().position += Vec3(0.0, -0.02, 0.3);
  series = compare(scene, run, nullptr);
  c = contact_summary(scene, run, series);
  EXPECT_NEAR(series.stack_drift.back(), 0.3, 1e-12);
  EXPECT_NEAR(*c.top_height_change, -0.02, 1e-12);
  EXPECT_EQ(c.verdict, "drifts");
  EXPECT_TRUE(verdict_is_failure(c.verdict));
  run.samples.back().bodies.back().position.x() += 1.0;
  c = contact_summary(scene, run, compare(scene, run, nullptr));
  EXPECT_EQ(c.verdict, "collapsed");
  EXPECT_NE(c.message.find("collapsed"), std::string::npos);
}

// a metric the scene does not ask for, or cannot compute, is empty, never zero
TEST(ContactMetrics, WhatCannotBeComputedIsEmpty) {
  const Scene scene = tower_scene(10);
  const Trajectory run = physbench::testing::held_still(scene, 10);  // under a second: no "last second" to judge
  const ContactSummary c = contact_summary(scene, run, compare(scene, run, nullptr));
  EXPECT_FALSE(c.rest_speed_rms);
  EXPECT_FALSE(c.apex_relative_error_max);
  EXPECT_FALSE(c.slide_acceleration);
  EXPECT_FALSE(c.exchange_error);
  EXPECT_FALSE(c.tunnelled);
  Scene free_flight = projectile_scene();
  free_flight.probe.metrics = {Metric::Energy};
  const ErrorSummary none = summarise(compare(free_flight, physbench::testing::held_still(free_flight, 3), nullptr));
  EXPECT_FALSE(none.stack_drift);
  EXPECT_FALSE(none.penetration);
}

// an ideal bouncing box, sampled every step: each apex is found within a millimetre's worth
TEST(ContactMetrics, ApexesOfAnIdealBounceMatchTheClosedForm) {
  const Scene scene = bounce_scene(0.8);
  const double g = 9.81, e = 0.8, h0 = 1.0, half = 0.5;
  Trajectory run;
  run.bodies = scene.probed_bodies();
  double height = h0, velocity = 0.0;
  for (long k = 0; k <= scene.step_count(); ++k) {
    Sample s;
    s.time = k * scene.dt;
    s.bodies.push_back({Vec3(0.0, half + height, 0.0), Quat::Identity(), Vec3(0.0, velocity, 0.0)});
    run.samples.push_back(s);
    // exact ballistic flight over the step, the impact resolved inside it
    double left = scene.dt;
    while (left > 0.0) {
      const double to_impact =
          (velocity + std::sqrt(velocity * velocity + 2.0 * g * height)) / g;
      if (to_impact > left) {
        height += velocity * left - 0.5 * g * left * left;
        velocity -= g * left;
        left = 0.0;
      } else {
        velocity = -e * (velocity - g * to_impact);
        height = 0.0;
        left -= to_impact;
        if (velocity < 1e-3) velocity = 0.0, left = 0.0;
      }
    }
  }
  const ContactSummary c = contact_summary(scene, run, compare(scene, run, nullptr));
  ASSERT_EQ(c.apex_relative_errors.size(), 5u);  // 0.64, 0.41, 0.26, 0.17, 0.11 m
  for (double err : c.apex_relative_errors) EXPECT_LT(std::abs(err), 1e-9);
  EXPECT_EQ(c.verdict, "");
}

// ---- each peer on contacts ----

// apexes read straight off the samples: the highest bottom-face clearance between two impacts,
// against e^(2n) h0 computed here, not by the metric under test
std::vector<double> apex_heights(const Scene& scene, const Trajectory& run) {
  std::vector<double> apexes;
  double best = 0.0;
  bool rising = false;
  for (std::size_t k = 1; k < run.samples.size(); ++k) {
    const SampledState& b = run.samples[k].bodies[0];
    const double clearance = b.position.y() - 0.5;
    if (b.linear_velocity.y() > 0.0) rising = true;
    if (rising) best = std::max(best, clearance);
    if (rising && b.linear_velocity.y() <= 0.0 && clearance < 0.5 * best) {
      apexes.push_back(best);
      best = 0.0;
      rising = false;
    }
  }
  (void)scene;
  return apexes;
}

void expect_bounce_follows_closed_form(const std::string& engine, const std::string& variant,
                                       double e, int apexes, double tolerance) {
  const Scene scene = bounce_scene(e);
  const ContactRun r = run_contacts(engine, variant, scene);
  const std::vector<double> measured = apex_heights(scene, r.run.trajectory);
  ASSERT_GE(static_cast<int>(measured.size()), apexes) << engine;
  for (int n = 1; n <= apexes; ++n) {
    const double expected = std::pow(e, 2 * n) * 1.0;
    EXPECT_NEAR(measured[n - 1], expected, tolerance * expected) << engine << " apex " << n;
    // the harness's metric says the same
    EXPECT_NEAR(r.contact.apex_relative_errors.at(n - 1), measured[n - 1] / expected - 1.0, 0.02)
        << engine << " apex " << n;
  }
}

// the pair rule, √(μa μb): a box of μ = 0.25 on a slope of μ = 1 is a μ = 0.5 pair, which at 30°
// slides with a = g (sin 30° − 0.5 cos 30°) = 0.657 m/s²; a product rule (0.25) would give 2.78
void expect_pair_friction_rule(const std::string& engine, const std::string& variant) {
  Scene scene = incline_scene(30);
  scene.bodies[0].friction = 1.0;
  scene.bodies[1].friction = 0.25;
  scene.duration = 2.0;
  const ContactRun r = run_contacts(engine, variant, scene);
  ASSERT_TRUE(r.contact.slide_acceleration) << engine;
  EXPECT_NEAR(*r.contact.slide_acceleration, 0.657, 0.1) << engine;
  EXPECT_EQ(r.contact.verdict, "slides") << engine;
}

// each peer runs the two scenes the harness's smoke run uses, and every contact column fills
void expect_tower_and_bounce_run(const std::string& engine, const std::string& variant) {
  const ContactRun tower = run_contacts(engine, variant, tower_scene(10));
  ASSERT_TRUE(tower.summary.stack_drift && tower.summary.penetration) << engine;
  EXPECT_TRUE(std::isfinite(tower.summary.stack_drift->max)) << engine;
  EXPECT_FALSE(tower.contact.verdict.empty()) << engine;
  EXPECT_TRUE(tower.contact.energy_added_max && tower.contact.rest_speed_rms) << engine;
  const ContactRun bounce = run_contacts(engine, variant, bounce_scene(0.5));
  ASSERT_TRUE(bounce.summary.penetration) << engine;
  EXPECT_EQ(bounce.contact.apex_relative_errors.size(), 2u) << engine;
}

#ifdef PHYSBENCH_HAVE_BULLET
TEST(ContactPeers, BulletRunsTowerAndBounce) { expect_tower_and_bounce_run("bullet", "float"); }
TEST(ContactPeers, BulletCombinesFrictionByThePairRule) {
  expect_pair_friction_rule("bullet", "float");
}
#endif

#ifdef PHYSBENCH_HAVE_ODE
TEST(ContactPeers, OdeRunsTowerAndBounce) {
  expect_tower_and_bounce_run("ode", "quickstep");
  expect_tower_and_bounce_run("ode", "quickstep-10");
}
TEST(ContactPeers, OdeCombinesFrictionByThePairRule) {
  expect_pair_friction_rule("ode", "quickstep");
}
// measured: 0.1 %–3.8 % off on the first five apexes (dt = 1/60)
TEST(ContactPeers, OdeBounceApexesFollowTheClosedForm) {
  expect_bounce_follows_closed_form("ode", "quickstep", 0.8, 5, 0.06);
}
// dWorldStep's Dantzig solver reports "LCP internal error" on a stack's redundant contacts and
// goes on with a wrong answer: the adapter makes that an error, never a result
TEST(ContactPeers, OdeSolverFailureIsAnError) {
  try {
    simulate(physbench::testing::engine("ode"), "step", tower_scene(10), untimed());
    SUCCEED() << "ODE's dWorldStep solved the tower without a message";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("not a result"), std::string::npos) << e.what();
  }
  const auto why = physbench::testing::engine("ode").unsupported(pyramid_scene(20), "step");
  ASSERT_TRUE(why);
  EXPECT_NE(why->find("O(rows³)"), std::string::npos);
}
#endif

#ifdef PHYSBENCH_HAVE_BOX2D
TEST(ContactPeers, Box2dRunsTowerAndBounce) {
  expect_tower_and_bounce_run("box2d", "default");
  expect_tower_and_bounce_run("box2d", "iterations-10");
}
TEST(ContactPeers, Box2dCombinesFrictionByThePairRule) {
  expect_pair_friction_rule("box2d", "default");
}
// measured: 7.2 % and 7.8 % low on the two apexes above 2 cm
TEST(ContactPeers, Box2dBounceApexesFollowTheClosedForm) {
  expect_bounce_follows_closed_form("box2d", "default", 0.5, 2, 0.12);
}
// the shrunk cores: exactly touching boxes start touching, not 2 cm overlapped, so nothing is
// pushed apart — unshrunk, ten 2 cm overlaps push the tower's top up and the boxes apart
TEST(ContactPeers, Box2dSkinIsCompensated) {
  Scene scene = tower_scene(10);
  scene.duration = 0.5;
  const ContactRun r = run_contacts("box2d", "default", scene);
  ASSERT_TRUE(r.contact.top_height_change);
  EXPECT_LT(*r.contact.top_height_change, 0.002);  // never pushed up
  EXPECT_GT(*r.contact.top_height_change, -0.03);  // settles by Box2D's slop per contact only
  EXPECT_LT(r.summary.penetration->max, 0.01);
}
#endif

#ifdef PHYSBENCH_HAVE_MUJOCO
TEST(ContactPeers, MujocoRunsTowerAndBounce) {
  expect_tower_and_bounce_run(kMujoco, "euler");
  expect_tower_and_bounce_run(kMujoco, "pgs-10");
}
// MuJoCo's soft contact sinks by design, and by little at its defaults: the resting 10-box tower
// ends under 5 mm deep (measured 1.5 mm) and within 1 cm of where it started (3.7 mm)
TEST(ContactPeers, MujocoTowerRestsWithinItsSoftSink) {
  const ContactRun r = run_contacts(kMujoco, "euler", tower_scene(10));
  ASSERT_TRUE(r.summary.penetration && r.summary.stack_drift);
  EXPECT_LT(r.summary.penetration->final, 0.005);
  EXPECT_LT(r.summary.stack_drift->max, 0.01);
  EXPECT_EQ(r.contact.verdict, "stands");
}
TEST(ContactPeers, MujocoBuffersAreSizedFromTheScene) {
  const MujocoBuffers tower = mujoco_buffers(tower_scene(10));
  // ten box pairs (nine box-box, one box-ground) at 4 points each, and room to spare
  EXPECT_GE(tower.nconmax, 40);
  EXPECT_EQ(tower.njmax, 4 * tower.nconmax);
  EXPECT_EQ(mujoco_buffers(projectile_scene()).nconmax, 0);
  // 5,050 boxes need an njmax x njmax matrix MuJoCo 2.2.2 cannot hold here: unsupported, why
  const auto why = physbench::testing::engine(kMujoco).unsupported(pyramid_scene(100), "euler");
  ASSERT_TRUE(why);
  EXPECT_NE(why->find("efc_AR"), std::string::npos);
}
// 48 balls dropped apart into a pit make contacts the starting neighbourhood did not have (the
// buffers count each ball with the floor only): the buffer overflows, and that ends the run as a
// failure instead of a result with lost contacts
TEST(ContactPeers, MujocoOverflowIsAFailure) {
  Scene scene = tower_scene(0);
  scene.name = "pit";
  scene.planar = false;
  scene.duration = 3.0;
  for (int side = 0; side < 4; ++side) {
    BodySpec wall;
    wall.name = "wall" + std::to_string(side);
    wall.mass = 0.0;
    wall.friction = scene.bodies[0].friction;
    const double at = side % 2 ? 1.35 : -1.35;
    wall.shape.half_extents = side < 2 ? Vec3(0.05, 1.0, 1.4) : Vec3(1.4, 1.0, 0.05);
    wall.position = side < 2 ? Vec3(at, 1.0, 0.0) : Vec3(0.0, 1.0, at);
    scene.bodies.push_back(wall);
  }
  for (int i = 0; i < 48; ++i) {
    BodySpec ball;
    ball.name = "ball" + std::to_string(i);
    ball.shape.kind = ShapeKind::Sphere;
    ball.shape.radius = 0.25;
    ball.friction = scene.bodies[0].friction;
    // each layer offset by half a spacing, so the balls fall into each other's gaps
    const double offset = (i / 16) % 2 ? 0.3 : 0.0;
    ball.position = Vec3(-0.9 + offset + 0.6 * (i % 4), 1.5 + 0.6 * (i / 16),
                         -0.9 + offset + 0.6 * ((i / 4) % 4));
    scene.bodies.push_back(ball);
  }
  ASSERT_NO_THROW(validate(scene));
  try {
    simulate(physbench::testing::engine(kMujoco), "euler", scene, untimed());
    FAIL() << "the pit fitted the buffer sized for its start: make it fuller";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("overflowed"), std::string::npos) << e.what();
  }
}
TEST(ContactPeers, MujocoRefusesMaterialsItCannotCombine) {
  Scene scene = incline_scene(30);
  scene.bodies[0].friction = 1.0;
  const auto why = physbench::testing::engine(kMujoco).unsupported(scene, "euler");
  ASSERT_TRUE(why);
  EXPECT_NE(why->find("max"), std::string::npos);
}
#endif

// the equal-iteration variants only run where there are contacts to solve
// every C++ engine counts the contact points its solver held, a step at a time: a box at rest on a
// slope has at least one and at most a face's four (a Box2D polygon's edge: two) on every step;
// rtp's manifold keeps the face's four; a scene without contacts has no count at all
TEST(ContactPeers, EachEngineCountsTheContactPointsOfABoxAtRest) {
  Scene slope = incline_scene(25);
  slope.duration = 1.0;
  const long steps = slope.step_count();
  for (const auto& [engine, variant] : std::vector<std::pair<std::string, std::string>>{
           {"rtp", "soft-step"}, {"bullet", "float"}, {"ode", "quickstep"}, {"box2d", "default"}
#ifdef PHYSBENCH_HAVE_MUJOCO
           , {kMujoco, "euler"}
#endif
       }) {
    const EngineInfo* info = find_linked_engine(engine);
    if (!info) continue;
    const RunResult run = simulate(*info, variant, slope, untimed());
    ASSERT_EQ(run.status, Status::Ok) << engine << ": " << run.message;
    EXPECT_EQ(run.contacts.steps, steps) << engine << ": a count for every step";
    const double per_step = run.contacts.points / double(run.contacts.steps);
    const double most = engine == "box2d" ? 2.0 : 4.0;
    EXPECT_GE(per_step, 1.0) << engine;
    EXPECT_LE(per_step, most) << engine;
    if (engine == "rtp") {
      EXPECT_EQ(per_step, 4.0);
    }
    const RunResult free = simulate(*info, info->variants.front(), projectile_scene(), untimed());
    EXPECT_EQ(free.contacts.steps, 0) << engine << ": no contacts, no count";
  }
}

TEST(ContactPeers, IterationVariantsApplyOnlyToContacts) {
  for (const auto& [engine, variant] : std::vector<std::pair<std::string, std::string>>{
           {"ode", "quickstep-10"}, {"box2d", "iterations-10"}, {kMujoco, "pgs-10"}}) {
    const EngineInfo* info = find_linked_engine(engine);
    if (!info) continue;
    EXPECT_FALSE(info->applies(projectile_planar_scene(), variant)) << engine;
    EXPECT_TRUE(info->applies(tower_scene(10), variant)) << engine;
  }
}

}  // namespace
