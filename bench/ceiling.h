// The machine's own two-thread ceiling: eight independent multiply-add chains held in registers
// (no memory traffic, nothing shared), one thread running two chunks of them against two threads
// running one chunk each, in turns. A kernel cannot gain more from a second thread than this
// does; these 2-vCPU VMs give 1.5–2.4x, varying within minutes. Counter speedup_2t; the
// benchmark's time is one turn's. A team of fewer than two threads fails the run.
#pragma once

#include <benchmark/benchmark.h>

#include <chrono>

// (not inlined, and the multiplier read from a volatile: the compiler cannot fold the chains)
[[gnu::noinline]] inline double multiply_add_chains(long n) {
  volatile double source = 0.999999999;
  const double m = source, c = 1e-9;
  double a0 = 1, a1 = 1, a2 = 1, a3 = 1, a4 = 1, a5 = 1, a6 = 1, a7 = 1;
  for (long i = 0; i < n; ++i) {
    a0 = a0 * m + c, a1 = a1 * m + c, a2 = a2 * m + c, a3 = a3 * m + c;
    a4 = a4 * m + c, a5 = a5 * m + c, a6 = a6 * m + c, a7 = a7 * m + c;
  }
  return a0 + a1 + a2 + a3 + a4 + a5 + a6 + a7;
}

inline void Ceiling(benchmark::State& state) {
  constexpr long kChunk = 20'000'000;  // about 30 ms on one core here
  using Clock = std::chrono::steady_clock;
  double one = 0.0, two = 0.0, sum = 0.0;
  for (auto _ : state) {
    const auto start = Clock::now();
    sum += multiply_add_chains(kChunk);
    sum += multiply_add_chains(kChunk);
    const auto middle = Clock::now();
    int team = 0;
#pragma omp parallel num_threads(2) reduction(+ : sum, team)
    {
      sum += multiply_add_chains(kChunk);
      team += 1;
    }
    const auto end = Clock::now();
    if (team < 2) {
      state.SkipWithError("the parallel region ran on one thread: no ceiling to measure");
      return;
    }
    one += std::chrono::duration<double>(middle - start).count();
    two += std::chrono::duration<double>(end - middle).count();
  }
  benchmark::DoNotOptimize(sum);
  state.counters["speedup_2t"] = two > 0.0 ? one / two : 0.0;
}
