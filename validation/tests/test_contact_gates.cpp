// rtp's contact gates (collision response, seed lab 5): the scenarios' own scenes run through
// the harness path (simulate, then the metrics a results row holds), on rtp's default solver at
// its default cost. Unit boxes, μ = 0.6, dt = 1/60, sleeping off, unless a scene says otherwise.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <vector>

#include "physbench/metrics.h"
#include "physbench/scenarios.h"
#include "support.h"

namespace {

using namespace physbench;

struct ContactRun {
  RunResult run;
  ErrorSummary summary;
  ContactSummary contact;
};

ContactRun run_rtp(const std::string& variant, const Scene& scene) {
  SimulateOptions options;
  options.timing_budget = 0.0;  // tests measure physics, never speed
  ContactRun r;
  r.run = simulate(physbench::testing::engine("rtp"), variant, scene, options);
  EXPECT_EQ(r.run.status, Status::Ok) << variant << " on " << scene.name << ": " << r.run.message;
  if (r.run.status != Status::Ok) return r;
  const ErrorSeries series = compare(scene, r.run.trajectory, nullptr);
  r.summary = summarise(series);
  r.contact = contact_summary(scene, r.run.trajectory, series);
  return r;
}

double drift_of(const ContactRun& r) { return r.summary.stack_drift.value_or(SeriesSummary{}).max; }
double penetration_of(const ContactRun& r) {
  return r.summary.penetration.value_or(SeriesSummary{}).max;
}

// a 20-box tower and a 210-box pyramid stand: every box's horizontal drift, the top box's height
// change and the deepest penetration (rtp's narrow phase on the sampled poses) all under 1 cm;
// the seed's lab 5 on the same scenes collapses, as the seed says its stacks do
TEST(ContactGates, TowerAndPyramidStandWhereTheSeedCollapses) {
  for (const Scene& scene : {tower_scene(20), pyramid_scene(20)}) {
    const ContactRun r = run_rtp("soft-step", scene);
    ASSERT_TRUE(r.summary.stack_drift && r.summary.penetration && r.contact.top_height_change)
        << scene.name;
    EXPECT_LT(drift_of(r), 0.01) << scene.name;
    EXPECT_LT(std::abs(*r.contact.top_height_change), 0.01) << scene.name;
    EXPECT_LT(penetration_of(r), 0.01) << scene.name;
    EXPECT_EQ(r.contact.verdict, "stands") << scene.name;
    const ContactRun seed = run_rtp("seed", scene);
    std::printf("%s: soft-step drift %.3g m, top %.3g m, penetration %.3g m; seed drift %.3g m, "
                "top %.3g m, penetration %.3g m (%s)\n",
                scene.name.c_str(), drift_of(r), *r.contact.top_height_change, penetration_of(r),
                drift_of(seed), seed.contact.top_height_change.value_or(0.0),
                penetration_of(seed), seed.contact.verdict.c_str());
    EXPECT_GT(drift_of(seed), 100.0 * drift_of(r)) << scene.name;
  }
}

// a box dropped flat: every apex the metric judges (the closed form's above 2 cm, at most five)
// follows e^(2n) h0 within 1 % (the scene's closed form gives h0). Restitution reverses the speed
// at the positions' instant, not the solve's velocity half a substep behind them: with that lag
// each bounce lost about 1.5 %, and the fifth apex at e = 0.8 was 8 % low
TEST(ContactGates, BounceApexesFollowTheRestitution) {
  for (double e : {0.2, 0.5, 0.8}) {
    const ContactRun r = run_rtp("soft-step", bounce_scene(e));
    ASSERT_FALSE(r.contact.apex_relative_errors.empty()) << "e = " << e;
    for (std::size_t n = 0; n < r.contact.apex_relative_errors.size(); ++n)
      EXPECT_LT(std::abs(r.contact.apex_relative_errors[n]), 0.01)
          << "e = " << e << ", apex " << n + 1;
  }
}

// e = 1, dropped from 1 m: a box and a sphere reach the release height on each of 20 bounces
// within 2 %, on the soft step (Box2D's settings too) and on sequential impulses
TEST(ContactGates, ElasticBouncesKeepTheirHeightOverTwentyBounces) {
  for (const char* variant : {"soft-step", "soft-step-4", "sequential-impulse"})
    for (ShapeKind shape : {ShapeKind::Box, ShapeKind::Sphere}) {
      const Scene scene = elastic_bounce_scene(shape);
      const ContactRun r = run_rtp(variant, scene);
      EXPECT_EQ(r.contact.apex_relative_errors.size(), 20u) << variant << " " << scene.name;
      ASSERT_TRUE(r.contact.apex_relative_error_max) << variant << " " << scene.name;
      EXPECT_LT(*r.contact.apex_relative_error_max, 0.02) << variant << " " << scene.name;
      EXPECT_EQ(r.contact.verdict, "keeps height") << variant << " " << scene.name;
    }
}

// a solid sphere launched sliding at v0 without spin rolls at 5/7 v0 (closed form) within
// 0.5 %, and one launched rolling keeps its speed within 0.5 %: friction acts at the true
// contact, not between the shapes grown by the step's motion (there a sphere at 5 m/s took
// friction 4 cm inside itself and rolled 7 % slow)
TEST(ContactGates, SphereLaunchedSlidingRollsAtFiveSeventhsOfItsSpeed) {
  for (const char* variant : {"soft-step", "soft-step-4", "sequential-impulse", "seed"}) {
    const ContactRun slides = run_rtp(variant, rolling_scene(true));
    ASSERT_TRUE(slides.contact.roll_speed_error) << variant;
    EXPECT_LT(std::abs(*slides.contact.roll_speed_error), 0.005) << variant;
    EXPECT_EQ(slides.contact.verdict, "rolls") << variant;
    // the time rolling starts, as sampled every step (1/60 s of 0.485 s is 3.4 %)
    ASSERT_TRUE(slides.contact.roll_time_error) << variant;
    EXPECT_LT(std::abs(*slides.contact.roll_time_error), 0.05) << variant;
    const ContactRun rolls = run_rtp(variant, rolling_scene(false));
    ASSERT_TRUE(rolls.contact.roll_speed_error) << variant;
    EXPECT_LT(std::abs(*rolls.contact.roll_speed_error), 0.005) << variant;
  }
}

// a row of four touching balls struck by a fifth, e = 1: momentum kept to round-off, the
// energy never above its start by more than 10⁻⁶ of it at any sample, and the simultaneous
// answer (the row leaves together at 0.4 v0, the striker rebounds at −0.6 v0). Box2D's settings
// (one relax pass) keep it within 1 %: the soft push that undoes the impact's overlap is not
// fully relaxed in a chain
TEST(ContactGates, StruckRowOfBallsKeepsMomentumAndNeverGainsEnergy) {
  const Scene scene = cradle_scene(5);
  for (const char* variant : {"soft-step", "sequential-impulse", "soft-step-4"}) {
    const ContactRun r = run_rtp(variant, scene);
    const ErrorSeries series = compare(scene, r.run.trajectory, nullptr);
    ASSERT_FALSE(series.energy_change.empty()) << variant;
    const double gained =
        *std::max_element(series.energy_change.begin(), series.energy_change.end());
    EXPECT_LE(gained, std::string(variant) == "soft-step-4" ? 0.01 : 1e-6) << variant;
    ASSERT_TRUE(r.summary.linear_momentum) << variant;
    EXPECT_LT(r.summary.linear_momentum->max, 1e-5) << variant;  // of 2 kg m/s
    EXPECT_EQ(r.contact.cradle_answer, "simultaneous") << variant;
    EXPECT_EQ(r.contact.verdict, "elastic") << variant;
  }
}

// a box turned 45° strikes another off its centre, edge on face, e = 1, μ = 0: the closed form
// of one impulse J = 2 v / (2 + 0.2² · 6) along x at 0.2 m off the struck box's centre gives the
// struck box 1.786 m/s and 2.143 rad/s about z, the striker 0.214 m/s; energy kept to 10⁻⁴
TEST(ContactGates, OffCentreElasticImpactFollowsTheClosedForm) {
  const Scene scene = offcentre_impact_scene();
  const double impulse = 2.0 * 2.0 / (2.0 + 0.2 * 0.2 * 6.0);
  for (const char* variant : {"soft-step", "sequential-impulse"}) {
    const ContactRun r = run_rtp(variant, scene);
    ASSERT_FALSE(r.run.trajectory.samples.empty()) << variant;
    const Sample& last = r.run.trajectory.samples.back();
    EXPECT_NEAR(last.bodies[0].linear_velocity.x(), 2.0 - impulse, 0.01 * impulse) << variant;
    EXPECT_NEAR(last.bodies[1].linear_velocity.x(), impulse, 0.01 * impulse) << variant;
    EXPECT_NEAR(last.bodies[1].angular_velocity.z(), 6.0 * 0.2 * impulse, 0.01 * 1.2 * impulse)
        << variant;
    EXPECT_EQ(r.contact.verdict, "elastic") << variant;
    ASSERT_TRUE(r.summary.energy) << variant;
    EXPECT_LT(r.summary.energy->max, 1e-4) << variant;
  }
}

// μ = 0.5: at 25° the block holds (under 1 mm), at 30° it slides with g (sin θ − μ cos θ) ± 3 %
TEST(ContactGates, SlopeHoldsAt25DegreesAndSlidesAt30) {
  const ContactRun holds = run_rtp("soft-step", incline_scene(25.0));
  ASSERT_TRUE(holds.contact.slide_distance);
  EXPECT_LT(std::abs(*holds.contact.slide_distance), 1e-3);
  EXPECT_EQ(holds.contact.verdict, "stays");
  const ContactRun slides = run_rtp("soft-step", incline_scene(30.0));
  ASSERT_TRUE(slides.contact.slide_acceleration_error);
  EXPECT_LT(std::abs(*slides.contact.slide_acceleration_error), 0.03);
}

// a closed stack gains no energy, and a box at rest neither bounces nor jitters
TEST(ContactGates, RestingStackGainsNoEnergyAndStaysStill) {
  const ContactRun r = run_rtp("soft-step", tower_scene(10));
  ASSERT_TRUE(r.contact.energy_added_max && r.contact.rest_speed_rms);
  EXPECT_LE(*r.contact.energy_added_max, 1e-9);
  EXPECT_LT(*r.contact.rest_speed_rms, 1e-3);  // m/s over the last second
}

// two equal boxes head-on, e = 1, no gravity: velocities exchange within 1 %, and the momentum
// is kept to round-off (the solver's single precision: about 1e-7 of it)
TEST(ContactGates, HeadOnBoxesExchangeVelocities) {
  const ContactRun r = run_rtp("soft-step", head_on_scene());
  ASSERT_TRUE(r.contact.exchange_error);
  EXPECT_LT(*r.contact.exchange_error, 0.01);
  const Trajectory& t = r.run.trajectory;
  ASSERT_GE(t.samples.size(), 2u);
  Vec3 start = Vec3::Zero(), end = Vec3::Zero();
  for (const auto& s : t.samples.front().bodies) start += s.linear_velocity;
  for (const auto& s : t.samples.back().bodies) end += s.linear_velocity;  // equal masses
  EXPECT_LT((end - start).norm(), 1e-6 * start.norm());
}

// heavy on light: 10:1 holds (under 1 cm); 100:1 and 1000:1 are measured and printed
TEST(ContactGates, HeavyOnLightHoldsAtTenToOne) {
  const ContactRun r = run_rtp("soft-step", mass_ratio_scene(10));
  ASSERT_TRUE(r.contact.top_height_change);
  EXPECT_LT(drift_of(r), 0.01);
  EXPECT_LT(std::abs(*r.contact.top_height_change), 0.01);
  for (double ratio : {100.0, 1000.0}) {
    const ContactRun heavier = run_rtp("soft-step", mass_ratio_scene(ratio));
    std::printf("mass-ratio-%g: drift %.3g m, top %.3g m, penetration %.3g m (%s)\n", ratio,
                drift_of(heavier), heavier.contact.top_height_change.value_or(0.0),
                penetration_of(heavier), heavier.contact.verdict.c_str());
  }
}

// a pyramid leans toward no side: its top box stays over its start while the pyramid takes its
// load. The colouring greedy in pair order laid its colours across the pyramid from the low body
// indices to the high, and the 5,050-box pyramid swayed that way, its top 8.5 mm to the left by
// 0.4 s (docs/solver.md, "The lean"); each contact's search for a colour starting at a hashed one
// keeps it within 0.7 mm
TEST(ContactGates, ALargePyramidDoesNotSwayTowardItsLowIndices) {
  Scene scene = pyramid_scene(100);
  scene.duration = 0.5;         // the sway's first swing peaked at 0.4 s
  scene.probe.interval = 0.05;  // every third step
  const ContactRun r = run_rtp("soft-step", scene);
  const auto& samples = r.run.trajectory.samples;
  ASSERT_GE(samples.size(), 10u);
  const int top = int(scene.bodies.size()) - 1;  // the last row's one box
  // its place among the probed bodies (the dynamic ones: the ground is not sampled)
  const std::vector<int>& probed = r.run.trajectory.bodies;
  const auto found = std::find(probed.begin(), probed.end(), top);
  ASSERT_NE(found, probed.end());
  const std::size_t slot = std::size_t(found - probed.begin());
  double sway = 0.0;
  for (const auto& sample : samples) {
    ASSERT_EQ(sample.bodies.size(), probed.size());
    sway = std::max(sway, std::abs(sample.bodies[slot].position.x() -
                                   scene.bodies[std::size_t(top)].position.x()));
  }
  std::printf("pyramid-100: the top box's largest sideways move in 0.5 s %.3g m\n", sway);
  EXPECT_LT(sway, 0.003);
}

// the same scene twice gives bit-identical states, and so does the two-thread variant: a
// colour's contacts share no dynamic body, so the threads cannot change the order of any sum
TEST(ContactGates, RunsAreBitIdenticalAtAnyThreadCount) {
  // 1,275 boxes: enough contacts per colour (and candidates) for the threads to share the work;
  // a quarter of a second of it
  Scene scene = pyramid_scene(50);
  scene.duration = 0.25;
  const ContactRun first = run_rtp("soft-step", scene), again = run_rtp("soft-step", scene),
                   threaded = run_rtp("soft-step-2t", scene);
  const auto& a = first.run.trajectory.samples;
  for (const ContactRun* other : {&again, &threaded}) {
    const auto& b = other->run.trajectory.samples;
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i)
      for (std::size_t k = 0; k < a[i].bodies.size(); ++k) {
        ASSERT_EQ(a[i].bodies[k].position, b[i].bodies[k].position) << "sample " << i;
        ASSERT_EQ(a[i].bodies[k].orientation.coeffs(), b[i].bodies[k].orientation.coeffs());
      }
  }
}

}  // namespace

namespace {

// a two-sample run of the scene's dynamic bodies: at rest where they start, then the given
// velocities at the end
Trajectory two_samples(const Scene& scene, const std::vector<Vec3>& linear,
                       const std::vector<Vec3>& angular) {
  Trajectory run;
  for (int i = 0; i < static_cast<int>(scene.bodies.size()); ++i)
    if (scene.bodies[i].mass > 0.0) run.bodies.push_back(i);
  for (int k = 0; k < 2; ++k) {
    Sample s;
    s.time = k * scene.duration;
    for (std::size_t j = 0; j < run.bodies.size(); ++j) {
      const BodySpec& b = scene.bodies[run.bodies[j]];
      SampledState x;
      x.position = b.position;
      x.orientation = b.orientation;
      x.linear_velocity = k == 0 ? b.linear_velocity : linear[j];
      x.angular_velocity = k == 0 ? b.angular_velocity : angular[j];
      s.bodies.push_back(x);
    }
    run.samples.push_back(s);
  }
  return run;
}

}  // namespace

// the cradle's two classical answers, from the velocities alone: the last ball leaving at v0 is
// sequential, the row leaving together at 2 v0 / 5 with the striker at −3 v0 / 5 simultaneous,
// and anything else other
TEST(ContactMetrics, CradleAnswerIsNamedFromTheFinalVelocities) {
  const Scene scene = cradle_scene(5);
  const std::vector<Vec3> still(5, Vec3::Zero());
  auto answer = [&](std::vector<double> vx) {
    std::vector<Vec3> v;
    for (double x : vx) v.emplace_back(x, 0.0, 0.0);
    const Trajectory run = two_samples(scene, v, still);
    return contact_summary(scene, run, compare(scene, run, nullptr)).cradle_answer;
  };
  EXPECT_EQ(answer({0.0, 0.0, 0.0, 0.0, 2.0}), "sequential");
  EXPECT_EQ(answer({-1.2, 0.8, 0.8, 0.8, 0.8}), "simultaneous");
  EXPECT_EQ(answer({0.0, 0.0, 0.0, 1.0, 1.0}), "other");
}

// a sphere launched at 5 m/s that ends rolling 5 % under 5/7 of it reads "rolls slow", one that
// ends at 5/7 of it but still slipping reads "slips"
TEST(ContactMetrics, RollingSpeedAndSlipAreJudgedAgainstTheClosedForm) {
  const Scene scene = rolling_scene(true);
  const double r = scene.bodies.back().shape.radius, v_roll = 5.0 * 5.0 / 7.0;
  auto judged = [&](double v, double w) {
    const Trajectory run = two_samples(scene, {Vec3(v, 0.0, 0.0)}, {Vec3(0.0, 0.0, -w)});
    return contact_summary(scene, run, compare(scene, run, nullptr));
  };
  const ContactSummary slow = judged(0.95 * v_roll, 0.95 * v_roll / r);
  ASSERT_TRUE(slow.roll_speed_error);
  EXPECT_NEAR(*slow.roll_speed_error, -0.05, 1e-12);
  EXPECT_EQ(slow.verdict, "rolls slow");
  EXPECT_TRUE(verdict_is_failure(slow.verdict));
  EXPECT_EQ(judged(v_roll, 0.9 * v_roll / r).verdict, "slips");
  EXPECT_EQ(judged(v_roll, v_roll / r).verdict, "rolls");
}

// a planar stack's drift apart in the plane and out of it: the top box moved 0.3 m along x and
// 0.4 m along z drifts 0.5 m, 0.3 of it in the plane and 0.4 out of it
TEST(ContactMetrics, PlanarDriftIsSplitIntoInAndOutOfThePlane) {
  const Scene scene = tower_scene(2);
  Trajectory run = two_samples(scene, {Vec3::Zero(), Vec3::Zero()}, {Vec3::Zero(), Vec3::Zero()});
  run.samples.back().bodies[1].position += Vec3(0.3, 0.0, 0.4);
  const ErrorSeries series = compare(scene, run, nullptr);
  const ContactSummary c = contact_summary(scene, run, series);
  ASSERT_TRUE(c.drift_in_plane && c.drift_out_of_plane);
  EXPECT_NEAR(*c.drift_in_plane, 0.3, 1e-12);
  EXPECT_NEAR(*c.drift_out_of_plane, 0.4, 1e-12);
  EXPECT_NEAR(summarise(series).stack_drift->max, 0.5, 1e-12);
}

// the collapse rule scales with the stack: a 10-box tower whose every contact sank 6 cm dropped
// its top 0.6 m without a box falling (it sinks); a top box that slid 1 m off collapsed (slid);
// one turned on its side collapsed (toppled)
TEST(ContactMetrics, SinkingSlidingAndTopplingAreToldApart) {
  const Scene scene = tower_scene(10);
  const std::vector<Vec3> still(10, Vec3::Zero());
  auto verdict = [&](const std::function<void(std::vector<SampledState>&)>& move) {
    Trajectory run = two_samples(scene, still, still);
    move(run.samples.back().bodies);
    const ContactSummary c = contact_summary(scene, run, compare(scene, run, nullptr));
    return c.verdict + " | " + c.message;
  };
  const std::string sunk = verdict([](std::vector<SampledState>& boxes) {
    for (std::size_t i = 0; i < boxes.size(); ++i) boxes[i].position.y() -= 0.06 * double(i + 1);
  });
  EXPECT_EQ(sunk.substr(0, 5), "sinks") << sunk;
  const std::string slid = verdict(
      [](std::vector<SampledState>& boxes) { boxes.back().position.x() += 1.0; });
  EXPECT_EQ(slid.substr(0, 17), "collapsed | colla") << slid;
  EXPECT_NE(slid.find("(slid)"), std::string::npos) << slid;
  const std::string toppled = verdict([](std::vector<SampledState>& boxes) {
    boxes.back().position += Vec3(1.0, -0.5, 0.0);
    boxes.back().orientation = Quat(Eigen::AngleAxisd(M_PI / 2.0, Vec3::UnitZ()));
  });
  EXPECT_NE(toppled.find("(toppled)"), std::string::npos) << toppled;
}
