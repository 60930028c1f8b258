// rtp's step with contacts on the pyramid scenes (docs/solver.md): ms per step at bases 10, 20,
// 50 and 100 (55 … 5,050 boxes) on one and two threads, with the step's stages as shares and the
// solver alone as ns per contact point per pass. The scene is the scenario's own
// (validation/src/contact_scenarios.cpp), built into a world by the adapter's make_rtp_world.
//
//   build/bench/bench/contacts_bench --benchmark_out=contacts.json --benchmark_out_format=json
//   build/bench/bench/contacts_bench --benchmark_filter='Pyramid/base:100/'
//   build/bench/bench/contacts_bench --benchmark_filter=ThreadScaling   (one thread against two)
// The triad (triad.h) runs first and last, on one thread and two: the machine's memory bandwidth
// beside the times, so that a slow spell shows in the run itself (Triad/threads:N/at:0 and at:1;
// with --benchmark_enable_random_interleaving they run among the others instead); and with it the
// machine's two-thread ceiling (ceiling.h, Ceiling/at:0 and at:1), what ThreadScaling's speedup
// is read against, and the cache line's round trip between the two threads' cores (RoundTrip/at:0
// and at:1; ThreadScaling's round_trip_before_ns and round_trip_after_ns), which tells the
// spells apart in which two threads scale well or not.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <tuple>

#include "physbench/rtp_world.h"
#include "physbench/scenarios.h"
#include "ceiling.h"
#include "triad.h"

namespace {

// steps before timing: the pyramid settles and every contact carries a warm start
constexpr int kSettleSteps = 30;

rtp::ContactSettings settings_for(int threads) {
  rtp::ContactSettings settings;  // the default soft step
  settings.threads = threads;
  return settings;
}

// base 0 stands for many-pyramids (Box3D's many_pyramids: 196 walls of base 10, 10,780 boxes)
constexpr int kManyPyramids = 0;
physbench::Scene scene_of(int base) {
  return base == kManyPyramids ? physbench::many_pyramids_scene(14, 10)
                               : physbench::pyramid_scene(base);
}

// one settled world per (base, threads), kept across Google Benchmark's calls, so it meets
// each repetition as the last one left it and the settling is paid once
rtp::World& settled_world(int base, int threads) {
  static std::map<std::pair<int, int>, std::unique_ptr<rtp::World>> worlds;
  auto& world = worlds[{base, threads}];
  if (!world) {
    const physbench::Scene scene = scene_of(base);
    world = std::make_unique<rtp::World>(physbench::make_rtp_world(
        scene, rtp::Integrator::SemiImplicitEuler, settings_for(threads)));
    for (int i = 0; i < kSettleSteps; ++i) world->step(scene.dt);
  }
  return *world;
}

void Pyramid(benchmark::State& state) {
  const int base = int(state.range(0)), threads = int(state.range(1));
  rtp::World& world = settled_world(base, threads);
  const double dt = 1.0 / 60.0;
  std::array<double, rtp::StepProfile::kStageNames.size()> sum{};
  double total = 0.0, relax_passes = 0.0;
  std::size_t steps = 0, held = 0, touching = 0, reordered = 0;
  for (auto _ : state) {
    world.step(dt);
    const rtp::StepProfile& p = world.profile();
    held += p.held_contacts;
    reordered += p.reordered_contacts;
    touching += p.contact_pairs;
    const auto stages = p.stage_seconds();
    for (std::size_t i = 0; i < sum.size(); ++i) sum[i] += stages[i];
    total += p.total;
    relax_passes += double(p.relax_passes);
    ++steps;
  }
  const rtp::StepProfile& last = world.profile();
  const rtp::ContactSettings& c = world.contact_settings();
  const double bodies = double(world.body_count() - 1);
  state.SetItemsProcessed(std::int64_t(steps * bodies));  // body-steps/s
  state.counters["bodies"] = bodies;
  state.counters["contact_pairs"] = double(last.contact_pairs);
  state.counters["contact_points"] = double(last.contact_points);
  state.counters["reused_pairs"] = double(last.reused_pairs);
  state.counters["reused_manifolds"] = double(last.reused_manifolds);
  // the share of the contacts held in last step's solver blocks, none built
  // (ContactSettings::contact_hold_distance)
  state.counters["held_contacts"] = touching > 0 ? double(held) / double(touching) : 0.0;
  // the held contacts moved between lanes a step, to keep each colour in class order
  state.counters["reordered_per_step"] = double(reordered) / double(steps);
  state.counters["ms_per_step"] = 1e3 * total / double(steps);
  // the solve's passes over every point in a step: per substep one biased, and the relax passes
  // (as many as the step took: more while a pass still changes a velocity past the tolerance)
  const double passes = double(c.substeps) + relax_passes / double(steps);
  state.counters["relax_passes_per_step"] = relax_passes / double(steps);
  const auto& names = rtp::StepProfile::kStageNames;
  auto seconds_of = [&](std::string_view name) {
    return sum[std::size_t(std::find(names.begin(), names.end(), name) - names.begin())];
  };
  state.counters["solver_ns_per_point_pass"] =
      1e9 * (seconds_of("solve") + seconds_of("relax")) /
      (double(steps) * passes * double(last.contact_points));
  state.counters["ns_per_contact_pair"] = 1e9 * total / (double(steps) * last.contact_pairs);
  for (std::size_t i = 0; i < names.size(); ++i)
    state.counters[std::string("share_") + names[i]] = sum[i] / total;
}

// One thread against two, paired: two worlds of the same pyramid, one on each thread count,
// stepped in turn, so both run the same steps (the same relax passes: the step's cost varies
// with them) in the same moments of the machine (whose speed drifts by up to 2x within
// minutes). Reports each world's ms a step over the run and the speedup as the ratio of the two
// totals; the runs are bit-identical (a difference in the final poses fails the benchmark).
// Each world steps `run` steps a turn. A turn of one step has each world start every step in
// caches the other has just filled, which a world stepped on its own never does; a turn of
// several pays that on its first step only, and that step's time is reported apart
// (first_ms_*, rest_ms_*)
void ThreadScaling(benchmark::State& state) {
  const int base = int(state.range(0));
  const int run = int(state.range(1));
  const physbench::Scene scene = scene_of(base);
  std::array<std::unique_ptr<rtp::World>, 2> worlds;
  for (int k = 0; k < 2; ++k) {
    worlds[std::size_t(k)] = std::make_unique<rtp::World>(physbench::make_rtp_world(
        scene, rtp::Integrator::SemiImplicitEuler, settings_for(k + 1)));
    for (int i = 0; i < kSettleSteps; ++i) worlds[std::size_t(k)]->step(scene.dt);
  }
  std::array<double, 2> total{}, first{};  // each world's time, and its turns' first steps'
  std::size_t steps = 0, turns = 0;
  std::size_t on_team = 0;  // the steps the two-thread world ran on its team
  // the cores' round trip (ceiling.h) before the turns and after them: which spell the run met
  const double round_trip_before = round_trip_ns(20'000);
  for (auto _ : state) {
    for (int k = 0; k < 2; ++k) {
      for (int r = 0; r < run; ++r) {
        worlds[std::size_t(k)]->step(scene.dt);
        total[std::size_t(k)] += worlds[std::size_t(k)]->profile().total;
        if (r == 0) first[std::size_t(k)] += worlds[std::size_t(k)]->profile().total;
        if (k == 1) on_team += worlds[1]->profile().threads > 1 ? 1 : 0;
      }
    }
    steps += std::size_t(run);
    ++turns;
  }
  for (rtp::BodyId body = 0; body < worlds[0]->body_count(); ++body) {
    const rtp::BodyState& one = worlds[0]->state(body);
    const rtp::BodyState& two = worlds[1]->state(body);
    if (one.position != two.position || one.orientation.coeffs() != two.orientation.coeffs()) {
      state.SkipWithError("two threads did not give one thread's poses");
      return;
    }
  }
  state.counters["ms_per_step_1t"] = 1e3 * total[0] / double(steps);
  state.counters["ms_per_step_2t"] = 1e3 * total[1] / double(steps);
  state.counters["speedup_2t"] = total[0] / total[1];
  if (run > 1) {
    state.counters["first_ms_1t"] = 1e3 * first[0] / double(turns);
    state.counters["first_ms_2t"] = 1e3 * first[1] / double(turns);
    state.counters["rest_ms_1t"] = 1e3 * (total[0] - first[0]) / double(steps - turns);
    state.counters["rest_ms_2t"] = 1e3 * (total[1] - first[1]) / double(steps - turns);
  }
  // the governor runs a step on one thread to probe it, or while one thread measures faster
  state.counters["team_share_2t"] = double(on_team) / double(steps);
  // both, not their mean: the spell can change during the turns (62 and 320 ns would read 191)
  state.counters["round_trip_before_ns"] = round_trip_before;
  state.counters["round_trip_after_ns"] = round_trip_ns(20'000);
}

// Held contacts against every contact built every step (ContactSettings::contact_hold_distance
// 0), paired: two worlds of the same scene, each settled, stepped in turns of ten steps over the
// same moments of the machine. Reports each one's ms a step and the ratios held/built of the
// step, of the passes (warm start, biased solve, relax) and of the narrow phase with `prepare`
void HeldAgainstBuilt(benchmark::State& state) {
  const physbench::Scene scene = scene_of(int(state.range(0)));
  constexpr int kRun = 10;
  std::array<std::unique_ptr<rtp::World>, 2> worlds;  // held, built
  for (int k = 0; k < 2; ++k) {
    rtp::ContactSettings settings = settings_for(1);
    if (k == 1) settings.contact_hold_distance = 0.0;
    worlds[std::size_t(k)] = std::make_unique<rtp::World>(
        physbench::make_rtp_world(scene, rtp::Integrator::SemiImplicitEuler, settings));
    for (int i = 0; i < kSettleSteps; ++i) worlds[std::size_t(k)]->step(scene.dt);
  }
  const auto& names = rtp::StepProfile::kStageNames;
  auto at = [&](std::string_view name) {
    return std::size_t(std::find(names.begin(), names.end(), name) - names.begin());
  };
  std::array<double, 2> total{}, passes{}, build{};
  std::size_t steps = 0, held = 0, touching = 0;
  for (auto _ : state) {
    for (std::size_t k = 0; k < 2; ++k)
      for (int r = 0; r < kRun; ++r) {
        worlds[k]->step(scene.dt);
        const rtp::StepProfile& p = worlds[k]->profile();
        const auto stages = p.stage_seconds();
        total[k] += p.total;
        passes[k] += stages[at("warm_start")] + stages[at("solve")] + stages[at("relax")];
        build[k] += stages[at("narrow_phase")] + stages[at("prepare")];
        if (k == 0) held += p.held_contacts, touching += p.contact_pairs;
      }
    steps += kRun;
  }
  state.counters["ms_per_step_held"] = 1e3 * total[0] / double(steps);
  state.counters["ms_per_step_built"] = 1e3 * total[1] / double(steps);
  state.counters["step_ratio"] = total[0] / total[1];
  state.counters["passes_ratio"] = passes[0] / passes[1];
  state.counters["narrow_prepare_ratio"] = build[0] / build[1];
  state.counters["held_contacts"] = touching > 0 ? double(held) / double(touching) : 0.0;
}

}  // namespace

int main(int argc, char** argv) {
  const rtp::ContactSettings c;
  benchmark::AddCustomContext(
      "solver", "soft step, " + std::to_string(c.substeps) + " substeps, " +
                    std::to_string(c.relax_iterations) + " to " +
                    std::to_string(c.max_relax_iterations) + " relax passes (until " +
                    std::to_string(c.relax_tolerance * 1e3).substr(0, 4) + " mm/s), " +
                    std::to_string(int(c.contact_hertz)) + " Hz; sleeping off; dt 1/60");
  benchmark::AddCustomContext("scene", "pyramid-N of the contact scenarios, settled " +
                                           std::to_string(kSettleSteps) + " steps before timing");
  // the machine's bandwidth before the steps and after them (at:0, at:1), and its two-thread
  // ceiling (ceiling.h) after the bandwidth
  auto triad = [](int at) {
    for (int threads : {1, 2})
      benchmark::RegisterBenchmark("Triad", Triad)
          ->Args({threads, at})
          ->ArgNames({"threads", "at"})
          ->Unit(benchmark::kMillisecond)
          ->UseRealTime();
    for (const auto& [name, figure, measures] :
         {std::tuple{"Ceiling", &Ceiling, 10}, std::tuple{"RoundTrip", &RoundTrip, 5}})
      benchmark::RegisterBenchmark(name, figure)
          ->Arg(at)
          ->ArgName("at")
          ->Unit(benchmark::kMillisecond)
          ->UseRealTime()
          ->Iterations(measures);
  };
  triad(0);
  for (int base : {10, 20, 50, 100})
    for (int threads : {1, 2})
      benchmark::RegisterBenchmark("Pyramid", Pyramid)
          ->Args({base, threads})
          ->ArgNames({"base", "threads"})
          ->Unit(benchmark::kMillisecond)
          ->UseRealTime()
          ->MinTime(base >= 100 ? 2.0 : 0.5);
  // many-pyramids (the many-island scene): its own names, which the report's pyramid tables skip
  for (int threads : {1, 2})
    benchmark::RegisterBenchmark("ManyPyramids", Pyramid)
        ->Args({kManyPyramids, threads})
        ->ArgNames({"scene", "threads"})
        ->Unit(benchmark::kMillisecond)
        ->UseRealTime()
        ->MinTime(2.0);
  // one thread against two, in turns of one step and of ten, over the same steps either way
  auto thread_scaling = [](const char* name, int scene, const char* scene_name, int steps) {
    for (int run : {1, 10})
      benchmark::RegisterBenchmark(name, ThreadScaling)
          ->Args({scene, run})
          ->ArgNames({scene_name, "run"})
          ->Unit(benchmark::kMillisecond)
          ->UseRealTime()
          ->Iterations(steps / run);
  };
  thread_scaling("ManyPyramidsThreadScaling", kManyPyramids, "scene", 200);
  for (int base : {50, 100})
    thread_scaling("ThreadScaling", base, "base", base >= 100 ? 300 : 600);
  benchmark::RegisterBenchmark("HeldAgainstBuilt", HeldAgainstBuilt)
      ->Arg(100)
      ->ArgName("base")
      ->Unit(benchmark::kMillisecond)
      ->UseRealTime()
      ->Iterations(30);
  benchmark::RegisterBenchmark("ManyPyramidsHeldAgainstBuilt", HeldAgainstBuilt)
      ->Arg(kManyPyramids)
      ->ArgName("scene")
      ->Unit(benchmark::kMillisecond)
      ->UseRealTime()
      ->Iterations(20);
  triad(1);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
