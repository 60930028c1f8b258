// The machine's own two-thread ceiling: eight independent multiply-add chains held in registers
// (no memory traffic, nothing shared), one thread running two chunks of them against two threads
// running one chunk each, in turns. A kernel cannot gain more from a second thread than this
// does; these 2-vCPU VMs give 1.5–2.4x, varying within minutes. Counter speedup_2t; the
// benchmark's time is one turn's. A team of fewer than two threads fails the run.
//
// And the cache line's round trip between the two threads of a team: what each barrier between
// two colours of a pass, and each body one thread writes and the other reads, costs at least.
// Counter round_trip_ns.
#pragma once

#include <benchmark/benchmark.h>

#include <atomic>
#include <chrono>

#if defined(_OPENMP)
#include <omp.h>
#endif

// a hint to the core that this thread spins on a flag (the engine has its own, spin_pause() in
// engine/src/threads.h, which is private to it)
inline void spin_wait() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#endif
}

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

// A flag handed back and forth between the two threads of an OpenMP team (each waits, spinning,
// for the other's write and answers it): the time a cache line takes to go to the other core and
// back, in ns, over `trips` round trips (0 without a team of two). On these 2-vCPU VMs it reads
// about 60 ns while the two vCPUs share a core complex and about 320 ns while they do not, and the
// hypervisor moves them from one to the other within seconds. The contact solve's threads meet
// at each colour's barrier and read bodies the other wrote, each such line a round trip, and
// `ThreadScaling` reads 1.8–1.9 in the first spells and 1.4–1.55 in the second
// (docs/runs/2026-12-07-issue-42-targets.md).
inline double round_trip_ns(int trips) {
  using Clock = std::chrono::steady_clock;
  alignas(64) std::atomic<int> flag{0};
  int team = 1;
  const auto start = Clock::now();
#if defined(_OPENMP)
#pragma omp parallel num_threads(2)
  {
    // (a team of one would wait for itself: it hands nothing, and the caller is told)
    const int size = omp_get_num_threads(), index = omp_get_thread_num();
#pragma omp single
    team = size;
    if (size == 2)
      for (int i = 0; i < trips; ++i) {
        // thread 0 writes the odd values and waits for the even ones; thread 1 answers
        if (index == 0) {
          flag.store(2 * i + 1, std::memory_order_release);
          while (flag.load(std::memory_order_acquire) != 2 * i + 2) spin_wait();
        } else {
          while (flag.load(std::memory_order_acquire) != 2 * i + 1) spin_wait();
          flag.store(2 * i + 2, std::memory_order_release);
        }
      }
  }
#endif
  const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return team < 2 || trips <= 0 ? 0.0 : 1e9 * seconds / double(trips);
}

// round_trip_ns() as a benchmark: 100,000 round trips a measure, the benchmark's time one
// measure's; counter round_trip_ns
inline void RoundTrip(benchmark::State& state) {
  constexpr int kTrips = 100'000;
  double sum = 0.0;
  long measures = 0;
  for (auto _ : state) {
    const double ns = round_trip_ns(kTrips);
    if (ns == 0.0) {
      state.SkipWithError("no team of two threads: no round trip to measure");
      return;
    }
    sum += ns;
    ++measures;
  }
  state.counters["round_trip_ns"] = measures > 0 ? sum / double(measures) : 0.0;
}
