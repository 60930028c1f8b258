// The machine's memory bandwidth, as a STREAM-style triad a = b + s c over 3 × 256 MiB / 3 of
// doubles split across the given threads: the figure beside a benchmark's times that says whether
// they were taken in a slow spell (these VMs' bandwidth drifts up to 2× within minutes). Its
// bytes/s is the run's bytes_per_second; counter `threads`.
#pragma once

#include <benchmark/benchmark.h>

#include <cstddef>
#include <cstdint>
#include <vector>

inline void Triad(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  const std::size_t n = (256u << 20) / sizeof(double) / 3;
  std::vector<double> a(n), b(n, 1.0), c(n, 2.0);
  const double s = 3.0;
  for (auto _ : state) {
#pragma omp parallel for num_threads(threads) schedule(static)
    for (std::size_t i = 0; i < n; ++i) a[i] = b[i] + s * c[i];
    benchmark::DoNotOptimize(a.data());
    benchmark::ClobberMemory();
  }
  const double bytes = 3.0 * sizeof(double) * static_cast<double>(n);
  state.SetBytesProcessed(static_cast<int64_t>(bytes * static_cast<double>(state.iterations())));
  state.counters["threads"] = threads;
}
