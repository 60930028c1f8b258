// The SIMD vocabulary's record moves (engine/src/simd.h): whichever way a build moves them —
// loads and transposes, gathers, or lane by lane — the same floats land in the same places. Built
// portable, and for AVX2 and for AVX-512 where the machine runs them (engine/tests/CMakeLists.txt).
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "simd.h"

namespace {

using namespace rtp;

// 64 records of 16 floats, each float its own value
std::vector<float> numbered_records() {
  std::vector<float> memory(64 * 16);
  for (std::size_t i = 0; i < memory.size(); ++i) memory[i] = 1.0f + 0.5f * float(i);
  return memory;
}

// true where this machine runs what the file was compiled for: CMake builds the AVX2 and AVX-512
// forms only on a machine that does, and this guards a build directory moved to another
bool machine_runs_this_build() {
#if defined(__AVX512F__)
  return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl");
#elif defined(__AVX2__)
  return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
#else
  return true;
#endif
}

// a record's first R floats written where a lane is set, and nothing else
template <typename V, std::size_t R>
void scatters_as_a_loop_would(std::vector<float>& memory, simd::MaskOf<V> offset) {
  constexpr std::size_t N = simd::kLanesOf<V>;
  V values[R];
  simd::MaskOf<V> where;
  for (std::size_t i = 0; i < N; ++i) {
    for (std::size_t k = 0; k < R; ++k) values[k][i] = -float(100 * R * k + i);
    where[i] = i % 3 != 0 ? -1 : 0;
  }
  const std::vector<float> before = memory;
  simd::scatter_records(memory.data(), offset, values, where);
  std::vector<float> expected = before;
  for (std::size_t i = 0; i < N; ++i)
    if (where[i])
      for (std::size_t k = 0; k < R; ++k) expected[std::size_t(offset[i]) + k] = values[k][i];
  for (std::size_t j = 0; j < memory.size(); ++j)
    EXPECT_EQ(memory[j], expected[j])
        << R << " floats: record " << j / 16 << ", float " << j % 16;
}

template <typename V>
void records_move_as_a_loop_would() {
  constexpr std::size_t N = simd::kLanesOf<V>;
  std::vector<float> memory = numbered_records();
  // distinct records out of order, the array's last among them
  simd::MaskOf<V> offset;
  for (std::size_t i = 0; i < N; ++i) offset[i] = std::int32_t(((i * 37 + 63) % 64) * 16);
  V rows[8];
  simd::gather_records(memory.data(), offset, rows);
  for (int k = 0; k < 8; ++k)
    for (std::size_t i = 0; i < N; ++i)
      EXPECT_EQ(rows[k][i], memory[std::size_t(offset[i]) + k]) << "float " << k << ", lane " << i;

  scatters_as_a_loop_would<V, 6>(memory, offset);
  scatters_as_a_loop_would<V, 8>(memory, offset);
}

TEST(Simd, RecordsGatherAndScatterAsALoopWould) {
  if (!machine_runs_this_build()) GTEST_SKIP() << "this machine lacks the instructions";
  records_move_as_a_loop_would<simd::Pack<float, 8>>();
  records_move_as_a_loop_would<simd::Pack<float, 16>>();
}

}  // namespace
