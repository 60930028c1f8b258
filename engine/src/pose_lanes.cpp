// The positions' integration of a step with contacts, eight bodies at a time: part of the contact
// pipeline's copies (contact_stages.h), so that a baseline build integrates at the core's width
// too. Positions by the new velocities, orientations by the exponential map; the motion since the
// step's start is kept too, for the contacts' separations.
#include <cmath>
#include <cstddef>
#include <cstring>

#include "contacts.h"
#include "simd.h"
#include "threads.h"

namespace rtp {
inline namespace RTP_CONTACT_ISA_NAMESPACE {

namespace {

// A body's turn over a substep, for a lane type D (simd::Double4: four bodies at once; or
// float lanes for the solver's single-precision motion).
//
// The turn by ω over h is exp(h ω / 2) as a unit quaternion: (cos x, sin x ω/|ω|) with
// x = h|ω|/2. A body-substep's half angle is small (a box spinning at 10 rad/s turns 0.01 rad in
// a 480 Hz substep), and there sin x / x and cos x are their Taylor series, exact to double's
// round-off below 0.1 (x² < 0.01; the first term left out is under 3e-18 of the sum), with no
// square root, division or sine; past it the library's sine and cosine (a lane at a time).
template <class D>
D half_angle_squared(const D (&w)[3], double h) {
  const double half = 0.5 * h;
  return half * half * (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
}
template <class D>
void series_turn(const D (&w)[3], D x2, double h, D (&turn)[4]) {
  const D c = 1.0 + x2 * (-1.0 / 2 + x2 * (1.0 / 24 + x2 * (-1.0 / 720 + x2 * (1.0 / 40320 +
                                                                        x2 * (-1.0 / 3628800)))));
  const D sinc =
      1.0 + x2 * (-1.0 / 6 + x2 * (1.0 / 120 + x2 * (-1.0 / 5040 + x2 * (1.0 / 362880))));
  const D k = sinc * (0.5 * h);
  turn[0] = c, turn[1] = k * w[0], turn[2] = k * w[1], turn[3] = k * w[2];
}
// q ← t q, then back to unit by one Newton step for 1/|q| about 1, q (3 − |q|²) / 2 (its error
// is the square of the product's); (w, x, y, z)
template <class D>
void turn_quaternion(const D (&t)[4], D (&q)[4]) {
  const D w = t[0] * q[0] - t[1] * q[1] - t[2] * q[2] - t[3] * q[3];
  const D x = t[0] * q[1] + t[1] * q[0] + t[2] * q[3] - t[3] * q[2];
  const D y = t[0] * q[2] - t[1] * q[3] + t[2] * q[0] + t[3] * q[1];
  const D z = t[0] * q[3] + t[1] * q[2] - t[2] * q[1] + t[3] * q[0];
  using T = simd::LaneOf<D>;
  const D scale = T(0.5) * (T(3.0) - (w * w + x * x + y * y + z * z));
  q[0] = w * scale, q[1] = x * scale, q[2] = y * scale, q[3] = z * scale;
}

}  // namespace

void ContactPipeline::integrate_positions(std::span<double> pose_lanes, std::size_t count,
                                          double h) {
  std::vector<SolverBody>& bodies = bodies_;
  // Eight bodies at a time, each in a lane: their poses are the group's lanes in pose_lanes_, and
  // their velocities and motion since the step's start eight consecutive solver records, read and
  // written as records transposed (a short last group through a copy, its empty lanes computed
  // and not written). A body's result is its lane's, whatever the others hold, so it is the same
  // on any number of threads. A body at rest keeps its position and motion bit for bit (a static
  // body is always at rest in the solver: nothing writes its velocities), and one that does not
  // turn keeps its orientation
  using D = simd::Double4;
  using H = simd::Pack<float, 4>;
  using F = simd::Pack<float, 8>;
  using FM = simd::MaskOf<F>;
  constexpr std::ptrdiff_t G = kPoseGroup;
  constexpr int kRecordFloats = int(sizeof(SolverBody) / sizeof(float));
  static_assert(offsetof(SolverBody, linear_velocity) == 0 &&
                offsetof(SolverBody, angular_velocity) == 3 * sizeof(float) &&
                offsetof(SolverBody, delta_position) == 8 * sizeof(float) &&
                offsetof(SolverBody, delta_rotation) == 12 * sizeof(float) &&
                kRecordFloats == 16);
  const std::ptrdiff_t n = std::ptrdiff_t(count);
  const std::ptrdiff_t groups = (n + G - 1) / G;
  FM offsets;
  for (std::ptrdiff_t i = 0; i < G; ++i) offsets[i] = std::int32_t(i * kRecordFloats);
  parallel_for(threads_, groups, groups >= 256, [&](std::ptrdiff_t g) {
    const std::ptrdiff_t first = g * G;
    const std::ptrdiff_t in_group = std::min(G, n - first);
    // (the short group's copy is raw bytes: SolverBody's initialisers cost a pass over 512
    // bytes a group)
    alignas(64) std::byte tail[sizeof(SolverBody) * G];
    float* base = reinterpret_cast<float*>(bodies.data() + first);
    if (in_group < G) {
      std::memset(tail, 0, sizeof tail);
      std::memcpy(tail, base, sizeof(SolverBody) * std::size_t(in_group));
      base = reinterpret_cast<float*>(tail);
    }
    // floats 0–7 of each record (v, ω, the inverse mass and inertia's xx, kept as read) and 8–15
    // (Δx, padding, Δq as x, y, z, w)
    F low[8], high[8];
    simd::gather_records(base, offsets, low);
    simd::gather_records(base + 8, offsets, high);
    double* lanes = pose_lanes.data() + g * kPoseDoubles;
    F dx[3] = {high[0], high[1], high[2]}, dq[4] = {high[7], high[4], high[5], high[6]};
    const F zero_f = simd::splat<F>(0.0f);
    const FM turns_f = (low[3] != zero_f) | (low[4] != zero_f) | (low[5] != zero_f);
    const FM moves_f = turns_f | (low[0] != zero_f) | (low[1] != zero_f) | (low[2] != zero_f);
    // the doubles four lanes at a time (a register's worth where the widest is 256 bits), the
    // moves and turns gathered back into eight float lanes for the motion since the step's start
    float moved_f[3][G], turn_f[4][G];
    for (int half = 0; half < 2; ++half) {
      const std::ptrdiff_t at = 4 * half;
      auto widen = [&](const F& x) {
        H four;
        std::memcpy(&four, reinterpret_cast<const float*>(&x) + at, sizeof four);
        return simd::convert<D>(four);
      };
      D v[3], w[3], x[3], q[4], turn[4];
      for (int k = 0; k < 3; ++k) {
        v[k] = widen(low[k]);
        w[k] = widen(low[3 + k]);
        x[k] = simd::load<D>(lanes + k * G + at);
      }
      for (int k = 0; k < 4; ++k) q[k] = simd::load<D>(lanes + (3 + k) * G + at);
      const D zero = simd::splat<D>(0.0);
      const auto turns = (w[0] != zero) | (w[1] != zero) | (w[2] != zero);
      const auto moves = turns | (v[0] != zero) | (v[1] != zero) | (v[2] != zero);
      for (int k = 0; k < 3; ++k) {
        const D moved = h * v[k];
        x[k] = simd::select(moves, x[k] + moved, x[k]);
        simd::store(moved_f[k] + at, simd::convert<H>(moved));
      }
      const D x2 = half_angle_squared(w, h);
      series_turn(w, x2, h, turn);
      if (!simd::all_of(x2 < simd::splat<D>(0.01)))
        for (int i = 0; i < 4 && at + i < in_group; ++i)
          if (!(x2[i] < 0.01)) {  // past the series: the library's sine and cosine
            const double angle = std::sqrt(x2[i]), k = std::sin(angle) / angle * (0.5 * h);
            turn[0][i] = std::cos(angle);
            for (int j = 0; j < 3; ++j) turn[1 + j][i] = k * w[j][i];
          }
      D turned[4] = {q[0], q[1], q[2], q[3]};
      turn_quaternion(turn, turned);
      for (int k = 0; k < 4; ++k) {
        q[k] = simd::select(turns, turned[k], q[k]);
        simd::store(turn_f[k] + at, simd::convert<H>(turn[k]));
      }
      for (int k = 0; k < 3; ++k) simd::store(lanes + k * G + at, x[k]);
      for (int k = 0; k < 4; ++k) simd::store(lanes + (3 + k) * G + at, q[k]);
    }
    for (int k = 0; k < 3; ++k)
      dx[k] = simd::select(moves_f, dx[k] + simd::load<F>(moved_f[k]), dx[k]);
    const F turn_float[4] = {simd::load<F>(turn_f[0]), simd::load<F>(turn_f[1]),
                             simd::load<F>(turn_f[2]), simd::load<F>(turn_f[3])};
    F turned_float[4] = {dq[0], dq[1], dq[2], dq[3]};
    turn_quaternion(turn_float, turned_float);
    for (int k = 0; k < 4; ++k) dq[k] = simd::select(turns_f, turned_float[k], dq[k]);
    high[0] = dx[0], high[1] = dx[1], high[2] = dx[2];
    high[4] = dq[1], high[5] = dq[2], high[6] = dq[3], high[7] = dq[0];
    const FM all = simd::splat<F>(0.0f) == simd::splat<F>(0.0f);
    simd::scatter_records(base + 8, offsets, high, all);  // (floats 0–7 are as read)
    if (in_group < G)
      std::memcpy(static_cast<void*>(bodies.data() + first), tail,
                  sizeof(SolverBody) * std::size_t(in_group));
  });
  separations_stale_ = true;
}

}  // namespace RTP_CONTACT_ISA_NAMESPACE
}  // namespace rtp
