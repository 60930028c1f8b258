// The SIMD vocabulary's record moves (engine/src/simd.h): whichever way a build moves them —
// loads and transposes, gathers, or lane by lane — the same floats land in the same places; and
// its packs of doubles compute what their lanes do one at a time. Built
// portable, and for AVX2 and for AVX-512 where the machine runs them (engine/tests/CMakeLists.txt).
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
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

// the narrow phase's 4 and 8 doubles and the poses' 8 floats: each operation gives what its lanes
// computed one at a time give, with NaN, infinities and signed zeros among the lanes. On the x86-64
// baseline these are SSE2 halves (simd.h, Split): a half's shuffle immediate or mask bit in the
// wrong place shows here
template <typename V>
void packs_compute_as_their_lanes_do() {
  using M = simd::MaskOf<V>;
  using T = simd::LaneOf<V>;
  constexpr std::size_t N = simd::kLanesOf<V>;
  const T values[] = {T(1.5), T(-2.25), T(0.0), T(-0.0), T(3.0), std::numeric_limits<T>::infinity(),
                      std::numeric_limits<T>::quiet_NaN(), T(-7.0), std::numeric_limits<T>::min(),
                      T(2.0), T(-1.5), T(0.5)};
  constexpr std::size_t kValues = sizeof(values) / sizeof(values[0]);
  auto same = [](T a, T b) {
    return (std::isnan(a) && std::isnan(b)) || std::memcmp(&a, &b, sizeof a) == 0;
  };
  for (std::size_t shift = 0; shift < kValues; ++shift) {
    V a, b;
    for (std::size_t i = 0; i < N; ++i) {
      a[i] = values[(i + shift) % kValues];
      b[i] = values[(3 * i + 2 * shift + 1) % kValues];
    }
    const V sum = a + b, difference = a - b, product = a * b, quotient = a / b, negated = -a;
    const V scaled = a * T(2.0);
    const M less = a < b, not_equal = a != b, greater_equal = a >= b;
    const V chosen = simd::select(less, a, b), least = simd::min(a, b), largest = simd::max(a, b);
    const V magnitude = simd::abs(a), flipped = simd::flip_where(a, greater_equal);
    const unsigned bits = simd::lane_bits(less);
    for (std::size_t i = 0; i < N; ++i) {
      const T x = a[i], y = b[i];
      const std::string at = "lane " + std::to_string(i) + " of " + std::to_string(x) + ", " +
                             std::to_string(y);
      EXPECT_TRUE(same(sum[i], T(x + y))) << at;
      EXPECT_TRUE(same(difference[i], T(x - y))) << at;
      EXPECT_TRUE(same(product[i], T(x * y))) << at;
      EXPECT_TRUE(same(quotient[i], T(x / y))) << at;
      EXPECT_TRUE(same(negated[i], T(-x))) << at;
      EXPECT_TRUE(same(scaled[i], T(x * T(2.0)))) << at;
      EXPECT_EQ(less[i], x < y ? -1 : 0) << at;
      EXPECT_EQ(not_equal[i], x != y ? -1 : 0) << at;
      EXPECT_EQ(greater_equal[i], x >= y ? -1 : 0) << at;
      EXPECT_TRUE(same(chosen[i], x < y ? x : y)) << at;
      EXPECT_TRUE(same(least[i], x < y ? x : y)) << at;
      EXPECT_TRUE(same(largest[i], x > y ? x : y)) << at;
      EXPECT_TRUE(same(magnitude[i], std::fabs(x))) << at;
      EXPECT_TRUE(same(flipped[i], x >= y ? T(-x) : x)) << at;
      EXPECT_EQ((bits >> i) & 1u, x < y ? 1u : 0u) << at;
    }
    // the box test's rotate (lane 3 stays; lanes 0, 1, 2 take 1, 2, 0), its next, a transpose's
    // pick from two packs
    if constexpr (N == 4) {
      const V turned = simd::shuffle<1, 2, 0, 3>(a);
      const T first[4] = {a[1], a[2], a[0], a[3]};
      for (std::size_t i = 0; i < 4; ++i) EXPECT_TRUE(same(turned[i], first[i])) << "lane " << i;
      const V mixed = simd::shuffle<7, 0, 5, 2>(a, b);
      const V next = simd::shuffle<1, 2, 3, 0>(a);
      const T want[4] = {b[3], a[0], b[1], a[2]}, want_next[4] = {a[1], a[2], a[3], a[0]};
      for (std::size_t i = 0; i < 4; ++i) {
        EXPECT_TRUE(same(mixed[i], want[i])) << "lane " << i;
        EXPECT_TRUE(same(next[i], want_next[i])) << "lane " << i;
      }
    }
  }
}

// four floats to four doubles and back, as a scalar conversion gives them (the poses' lanes)
TEST(Simd, FourFloatsWidenAndNarrowAsTheirLanesDo) {
  if (!machine_runs_this_build()) GTEST_SKIP() << "this machine lacks the instructions";
  const simd::Pack<float, 4> four = {1.5f, -0.0f, 3.0e38f, std::numeric_limits<float>::denorm_min()};
  const simd::Double4 wide = simd::convert<simd::Double4>(four);
  const simd::Double4 back_from = {0.1, -1e-50, 1e39, -2.5};
  const simd::Pack<float, 4> narrow = simd::convert<simd::Pack<float, 4>>(back_from);
  for (std::size_t i = 0; i < 4; ++i) {
    const double w = double(four[i]), got_wide = wide[i];
    EXPECT_EQ(std::memcmp(&got_wide, &w, sizeof w), 0) << "lane " << i;
    const float n = float(back_from[i]), got_narrow = narrow[i];
    EXPECT_EQ(std::memcmp(&got_narrow, &n, sizeof n), 0) << "lane " << i;
  }
}

TEST(Simd, PacksComputeAsTheirLanesDo) {
  if (!machine_runs_this_build()) GTEST_SKIP() << "this machine lacks the instructions";
  packs_compute_as_their_lanes_do<simd::Double4>();
  packs_compute_as_their_lanes_do<simd::Double8>();
  packs_compute_as_their_lanes_do<simd::Pack<float, 8>>();
}
