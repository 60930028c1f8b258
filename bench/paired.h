// Paired measurements (docs/metrics.md): two things timed in turn, round by round, so both meet
// the machine in the same state. What is compared is time summed over rounds — the ratio of the
// sums, and its spread as the least and largest ratio of sums over consecutive blocks of rounds.
#pragma once

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstddef>
#include <limits>
#include <numeric>
#include <string>
#include <vector>

namespace physbench_bench {

struct PairedRatio {
  double ratio = 0.0;  // Σ numerator / Σ denominator over every round
  double least = 0.0, largest = 0.0;  // of the same ratio over each of `blocks` blocks of rounds
  std::size_t rounds = 0, blocks = 0;
  double mean_numerator = 0.0, mean_denominator = 0.0;  // per round
};

inline double sum_of(const std::vector<double>& v, std::size_t from, std::size_t to) {
  return std::accumulate(v.begin() + std::ptrdiff_t(from), v.begin() + std::ptrdiff_t(to), 0.0);
}

// numerator[i] and denominator[i] are round i's two times
inline PairedRatio paired_ratio(const std::vector<double>& numerator,
                                const std::vector<double>& denominator, std::size_t blocks) {
  const std::size_t rounds = std::min(numerator.size(), denominator.size());
  const std::size_t block = rounds / blocks;
  PairedRatio r;
  r.rounds = rounds;
  r.blocks = block > 0 ? blocks : 0;
  r.mean_numerator = sum_of(numerator, 0, rounds) / double(rounds);
  r.mean_denominator = sum_of(denominator, 0, rounds) / double(rounds);
  r.ratio = r.mean_numerator / r.mean_denominator;
  r.least = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; block > 0 && k < blocks; ++k) {
    const std::size_t from = k * block, to = (k + 1) * block;
    const double b = sum_of(numerator, from, to) / sum_of(denominator, from, to);
    r.least = std::min(r.least, b), r.largest = std::max(r.largest, b);
  }
  return r;
}

// the ratio as counters: `name`, `name`_least_block and `name`_largest_block, with the rounds and
// the number of blocks
inline void report_paired(benchmark::State& state, const std::string& name, const PairedRatio& r) {
  state.counters["rounds"] = double(r.rounds);
  state.counters["blocks"] = double(r.blocks);
  state.counters[name] = r.ratio;
  state.counters[name + "_least_block"] = r.least;
  state.counters[name + "_largest_block"] = r.largest;
}

}  // namespace physbench_bench
