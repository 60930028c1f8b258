// The particle update against the memory roofline, in one run: a STREAM-style triad measures
// what one core (and both) can move, then the seed's attractor mode is timed at 10^4 … 4·10^6
// particles. Counters: particle-steps/s (items), bytes/s of particle state moved, and the
// fraction of the triad's bandwidth that is (roofline_fraction, same thread count). ThreadsPaired
// steps a one-thread and a two-thread system in turn for the two-core speedup.
//
//   build/bench/bench/particles_bench --benchmark_out=particles.json --benchmark_out_format=json
#include <benchmark/benchmark.h>
#include <rtp/particles.h>

#include <chrono>
#include <map>
#include <vector>

#include "paired.h"
#include "triad.h"
#include "physbench/particle_driver.h"
#include "physbench/scenarios.h"

namespace {

// bytes/s measured by the triad, per thread count, filled before the particle benchmarks run
std::map<int, double> triad_bandwidth;

// the particles-attractors scene (validation/src/scenarios.cpp), as rtp's definition
rtp::ParticleSystemDef attractor_mode(std::size_t count, int threads) {
  rtp::ParticleSystemDef def =
      physbench::particle_system_def(physbench::particles_attractors_scene(long(count)));
  def.integrator = rtp::ParticleIntegrator::Midpoint;
  def.threads = threads;
  return def;
}

void ParticleUpdate(benchmark::State& state) {
  const auto count = static_cast<std::size_t>(state.range(0));
  const int threads = static_cast<int>(state.range(1));
  rtp::ParticleSystem particles(attractor_mode(count, threads));
  // two simulated seconds outside the timed loop at every count: the particles have reached the
  // planes and the attractors, so each count is timed in the same, steady, phase
  for (int i = 0; i < 120; ++i) particles.step(1.0 / 60.0);
  for (auto _ : state) particles.step(1.0 / 60.0);
  const double steps = static_cast<double>(state.iterations()) * static_cast<double>(count);
  const double bytes = steps * static_cast<double>(particles.bytes_per_particle_step());
  state.SetItemsProcessed(static_cast<int64_t>(steps));
  state.SetBytesProcessed(static_cast<int64_t>(bytes));
  state.counters["bytes_per_particle_step"] =
      static_cast<double>(particles.bytes_per_particle_step());
  if (triad_bandwidth.count(threads))
    state.counters["roofline_fraction"] =
        benchmark::Counter(bytes / triad_bandwidth[threads], benchmark::Counter::kIsRate);
}

// one thread against two on the same count, stepped in turn: each round times a step of a
// one-thread system and then of a two-thread one, so both see the same state of the machine (its
// speed drifts by up to 2x over minutes) and the ratio of their summed times is free of it. The
// spread is the least and largest ratio over kBlocks consecutive blocks of rounds.
constexpr int kPairedRounds = 40, kBlocks = 5;
void ThreadsPaired(benchmark::State& state) {
  const auto count = static_cast<std::size_t>(state.range(0));
  rtp::ParticleSystem one(attractor_mode(count, 1)), two(attractor_mode(count, 2));
  for (int i = 0; i < 120; ++i) one.step(1.0 / 60.0), two.step(1.0 / 60.0);
  using Clock = std::chrono::steady_clock;
  std::vector<double> one_ms, two_ms;
  one_ms.reserve(kPairedRounds), two_ms.reserve(kPairedRounds);
  for (auto _ : state) {
    const auto t0 = Clock::now();
    one.step(1.0 / 60.0);
    const auto t1 = Clock::now();
    two.step(1.0 / 60.0);
    const auto t2 = Clock::now();
    one_ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
    two_ms.push_back(std::chrono::duration<double, std::milli>(t2 - t1).count());
    state.SetIterationTime((one_ms.back() + two_ms.back()) * 1e-3);
  }
  const physbench_bench::PairedRatio r = physbench_bench::paired_ratio(one_ms, two_ms, kBlocks);
  state.counters["particles"] = double(count);
  state.counters["one_thread_ms"] = r.mean_numerator;
  state.counters["two_threads_ms"] = r.mean_denominator;
  physbench_bench::report_paired(state, "speedup", r);
}

// records the triad's bytes/s so the particle benchmarks can state their fraction of it
class TriadCapture : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const Run& run : runs)
      if (run.benchmark_name().rfind("Triad", 0) == 0 && run.run_type == Run::RT_Iteration)
        triad_bandwidth[static_cast<int>(run.counters.at("threads").value)] =
            run.counters.at("bytes_per_second").value;
    ConsoleReporter::ReportRuns(runs);
  }
};

}  // namespace

BENCHMARK(Triad)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(ParticleUpdate)
    ->ArgsProduct({{10000, 100000, 1000000, 4000000}, {1, 2}})
    ->ArgNames({"particles", "threads"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(ThreadsPaired)
    ->Arg(1000000)
    ->Arg(4000000)
    ->ArgNames({"particles"})
    ->Iterations(kPairedRounds)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::AddCustomContext("particle_integrator", "midpoint");
  benchmark::AddCustomContext("particle_kernels",
                              rtp::ParticleSystem(attractor_mode(16, 1)).kernels());
  benchmark::AddCustomContext("scene", "particles-attractors (3 attractors, 3 planes, drag)");
  // the triad first, on its own, so its bandwidth is known when the particle runs report
  TriadCapture console;
  benchmark::RunSpecifiedBenchmarks(&console);
  benchmark::Shutdown();
  return 0;
}
