// Accuracy gates: rtp's error on gated scenarios may not rise past its baselines
// (validation/baselines/rtp.json), and the references themselves must be converged.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "physbench/scenarios.h"
#include "support.h"

namespace {

using namespace physbench;
using physbench::testing::measure;

std::optional<double> metric_value(const ErrorSummary& s, const std::string& metric) {
  auto pick = [](const std::optional<SeriesSummary>& series,
                 const std::string& part) -> std::optional<double> {
    if (!series) return std::nullopt;
    if (part == "rms") return series->rms;
    if (part == "max") return series->max;
    return series->final;
  };
  const auto cut = metric.rfind('_');
  const std::string series = metric.substr(0, cut), part = metric.substr(cut + 1);
  if (series == "position_err") return pick(s.position, part);
  if (series == "orientation_err") return pick(s.orientation, part);
  if (series == "energy_drift") return pick(s.energy, part);
  if (series == "linear_momentum_drift") return pick(s.linear_momentum, part);
  if (series == "angular_momentum_drift") return pick(s.angular_momentum, part);
  return std::nullopt;
}

// a new baseline: the measured value rounded up to three significant digits (as the baselines are
// written by hand), or exact for a gate whose factor leaves less than 1 % (rounding up would loosen
// it, rounding down fail it)
double new_baseline(double measured, double factor) {
  if (measured <= 0.0 || !std::isfinite(measured) || factor < 1.01) return measured;
  const double scale = std::pow(10.0, std::floor(std::log10(measured)) - 2.0);
  std::ostringstream text;
  text << std::setprecision(3) << std::ceil(measured / scale) * scale;
  return std::stod(text.str());
}

// the baselines file, one gate a line as it is kept by hand
void write_baselines(const nlohmann::ordered_json& baselines, const std::string& path) {
  std::ofstream out(path + ".partial");
  out << "{\n  \"about\": " << baselines.at("about").dump() << ",\n  \"gates\": [\n";
  const auto& gates = baselines.at("gates");
  for (std::size_t i = 0; i < gates.size(); ++i) {
    std::string line;
    for (const auto& [key, value] : gates[i].items())
      line += (line.empty() ? "" : ", ") + nlohmann::json(key).dump() + ": " + value.dump();
    out << "    {" << line << "}" << (i + 1 < gates.size() ? "," : "") << "\n";
  }
  out << "  ]\n}\n";
  out.close();
  std::filesystem::rename(path + ".partial", path);
}

// PHYSBENCH_REWRITE_BASELINES=1 makes the gate test set every baseline to what it measures now and
// print what changed, instead of gating: the deliberate way to move a baseline (README,
// "Accuracy gates"); the commit that does it says why
TEST(Gates, RtpStaysWithinItsAccuracyBaselines) {
  std::ifstream in(PHYSBENCH_BASELINES);
  ASSERT_TRUE(in) << "cannot open " << PHYSBENCH_BASELINES;
  nlohmann::ordered_json baselines = nlohmann::ordered_json::parse(in);
  ASSERT_FALSE(baselines.at("gates").empty());
  const char* rewrite_flag = std::getenv("PHYSBENCH_REWRITE_BASELINES");
  const bool rewrite = rewrite_flag && std::string(rewrite_flag) == "1";
  int changed = 0;
  for (auto& gate : baselines.at("gates")) {
    const std::string scenario = gate.at("scenario"), variant = gate.at("variant"),
                      metric = gate.at("metric");
    const Scenario* s = find_scenario(scenario);
    ASSERT_NE(s, nullptr) << "baseline names an unknown scenario " << scenario;
    const auto measured = metric_value(measure("rtp", variant, s->build()).summary, metric);
    ASSERT_TRUE(measured) << scenario << " does not measure " << metric;
    if (rewrite) {
      const double old = gate.at("baseline").get<double>();
      const double now = new_baseline(*measured, gate.at("factor").get<double>());
      if (now != old) {
        std::cout << std::setprecision(10) << "baseline " << scenario << "/rtp/" << variant << " " << metric << ": " << old
                  << " -> " << now << "\n";
        gate["baseline"] = now;
        ++changed;
      }
      continue;
    }
    const double limit =
        std::max(gate.at("baseline").get<double>() * gate.at("factor").get<double>(),
                 gate.at("floor").get<double>());
    EXPECT_LE(*measured, limit) << "gate " << scenario << "/rtp/" << variant << " " << metric
                                << ": measured " << *measured << ", baseline "
                                << gate.at("baseline") << ", limit " << limit;
  }
  if (rewrite) {
    if (changed) write_baselines(baselines, PHYSBENCH_BASELINES);
    std::cout << changed << " baseline(s) rewritten in " << PHYSBENCH_BASELINES << "\n";
  }
}

TEST(Gates, ProjectileRk4MatchesTheClosedForm) {
  // the trajectory is a polynomial of degree 2: RK4 is exact up to round-off
  const auto m = measure("rtp", "rk4", projectile_scene());
  EXPECT_LT(m.summary.position->max, 1e-10);
}

TEST(Gates, SemiImplicitEulerLagsByHalfGDtT) {
  // x_n = x0 + v0 t + ½ g t² + ½ g dt t: the known first-order signature, to round-off
  const Scene scene = projectile_scene();
  const auto m = measure("rtp", "euler", scene);
  const double expected = 0.5 * scene.gravity.norm() * scene.dt * scene.duration;
  EXPECT_NEAR(m.summary.position->final, expected, 1e-9);
}

TEST(Gates, TumblingBoxRk4EnergyDriftBelowEulerAndMidpoint) {
  const Scene scene = tumbling_box_scene();
  const double rk4 = measure("rtp", "rk4", scene).summary.energy->max;
  const double midpoint = measure("rtp", "midpoint", scene).summary.energy->max;
  const double euler = measure("rtp", "euler", scene).summary.energy->max;
  EXPECT_LT(rk4, 1e-6);
  EXPECT_LT(rk4, midpoint);
  EXPECT_LT(midpoint, euler);
}

TEST(References, TumblingBoxReferenceIsConvergedByHalving) {
  // the reference at dt/64 and at dt/128 agree far below any engine's error
  Scene scene = tumbling_box_scene();
  const Trajectory coarse = physbench::testing::converged_reference(scene, 64);
  const Trajectory fine = physbench::testing::converged_reference(scene, 128);
  scene.probe.metrics = {Metric::Orientation};
  const ErrorSummary difference = summarise(compare(scene, coarse, &fine));
  EXPECT_LT(difference.orientation->max, 1e-9);
}

TEST(References, DzhanibekovFlipHappens) {
  // the scene asks a real question only if the box flips: its long-axis angular velocity
  // component must reverse sign within the run
  const Scene scene = tumbling_box_scene();
  const Trajectory reference = physbench::testing::converged_reference(scene, 64);
  bool reversed = false;
  for (const Sample& s : reference.samples) {
    const Vec3 body_spin = s.bodies[0].orientation.conjugate() * s.bodies[0].angular_velocity;
    reversed |= body_spin.y() < 0.0;
  }
  EXPECT_TRUE(reversed);
}

TEST(References, SymmetricTopClosedFormAgreesWithTheConvergedRun) {
  // two independent answers to one question: Goldstein's closed form and rtp RK4 at dt/64
  Scene scene = symmetric_top_scene();
  SimulateOptions options;
  options.timing_budget = 0.0;
  const Trajectory converged = physbench::testing::converged_reference(scene, 64);
  const Trajectory closed_form = ballistic_reference(scene, converged);
  scene.probe.metrics = {Metric::Orientation};
  EXPECT_LT(summarise(compare(scene, converged, &closed_form)).orientation->max, 1e-9);
  // and the top really precesses: its symmetry axis sweeps a cone of half-angle about 0.13 rad
  const Vec3 start = closed_form.samples.front().bodies[0].orientation * Vec3::UnitY();
  double widest = 0.0;
  for (const Sample& s : closed_form.samples)
    widest = std::max(widest, (s.bodies[0].orientation * Vec3::UnitY() - start).norm());
  EXPECT_GT(widest, 0.2);
}

}  // namespace

namespace {

using namespace physbench;

ErrorSeries energy_series(std::vector<double> changes) {
  ErrorSeries s;
  s.energy_change = std::move(changes);
  return s;
}

TEST(Stability, ClassesFromTheEnergyInPlay) {
  const Scene scene = spring_oscillator_scene(0.0);
  EXPECT_EQ(stability_of(scene, energy_series({0, 0.3, -0.2, 0.3, -0.2, 0.3})), "stable");
  EXPECT_EQ(stability_of(scene, energy_series({0, 0.5, 1, 2, 4, 8})), "unstable");  // growing
  EXPECT_EQ(stability_of(scene, energy_series({0, 25, 25, 25, 25, 25})),
            "unstable");  // 26x, bounded
  EXPECT_EQ(stability_of(scene, energy_series({0, -0.3, -0.6, -0.8, -0.9, -0.95})), "over-damped");
  EXPECT_EQ(stability_of(scene, energy_series({0, 0.1, std::nan(""), 0, 0, 0})), "unstable");
  // a damped scene loses energy by design: no class
  EXPECT_EQ(stability_of(spring_oscillator_scene(2.0), energy_series({0, -0.5, -0.8, -0.9})), "");
}

TEST(Stability, StiffSpringMatchesTheKnownReferencePoints) {
  // k = 1e4 N/m, m = 1 kg, dt = 1/120 (ω dt = 0.83): midpoint blows up, semi-implicit Euler holds,
  // RK4 holds but loses energy (its amplification factor is below one there)
  Scene scene = stiff_spring_scene(1e4);
  scene.dt = 1.0 / 120.0;
  auto run_class = [&](const std::string& variant) {
    SimulateOptions options;
    options.timing_budget = 0.0;
    const RunResult r = simulate(rtp_engine_info(), variant, scene, options);
    if (r.status == Status::Exploded) return std::string("exploded");
    const Trajectory reference = analytic_reference(scene, r.trajectory);
    return stability_of(scene, compare(scene, r.trajectory, &reference));
  };
  EXPECT_EQ(run_class("euler"), "stable");
  EXPECT_NE(run_class("midpoint"), "stable");
  EXPECT_EQ(run_class("rk4"), "over-damped");
}

}  // namespace
