// What the contact solver's stages share: the lane helpers (three lanes as a vector, a block's
// inverse inertias, its lanes' bodies read from the body array and written back, a point's normal
// row) that contact_prepare.cpp (the step's constants) and contact_solver.cpp (the passes) both
// compute with. The blocks themselves are in contact_lanes.h.
//
// Everything here has internal linkage (an unnamed namespace), so each file gets its own copy, as
// it had when the two were one file: with FMA contraction on (GCC's default), which products fuse
// into a multiply-add depends on what is inlined where (narrowphase_internal.h keeps its helpers
// the same way). The kernels call these in their hot loops: defined here, they stay inlinable.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "contacts.h"
#include "simd.h"

namespace rtp {

namespace {

constexpr std::size_t W = kBlockLanes;

Lane splat(float x) { return simd::splat<Lane>(x); }

// a vector of three lanes: W vectors at once
struct V3 {
  Lane x, y, z;
  friend V3 operator+(const V3& a, const V3& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
  friend V3 operator-(const V3& a, const V3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
  friend V3 operator*(Lane s, const V3& a) { return {s * a.x, s * a.y, s * a.z}; }
};
Lane dot(const V3& a, const V3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
V3 cross(const V3& a, const V3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
V3 load3(const Lane (&v)[3]) { return {v[0], v[1], v[2]}; }

// a symmetric 3×3 in six lanes (xx, yy, zz, xy, xz, yz) times a vector
V3 times(const Lane (&m)[6], const V3& v) {
  return {m[0] * v.x + m[3] * v.y + m[4] * v.z, m[3] * v.x + m[1] * v.y + m[5] * v.z,
          m[4] * v.x + m[5] * v.y + m[2] * v.z};
}

// where each of a body's numbers is among its 16 floats (Eigen stores a quaternion x, y, z, w)
constexpr int kBodyFloats = sizeof(SolverBody) / sizeof(float);
constexpr int kLinearVelocity = 0, kAngularVelocity = 3, kInverseMass = 6, kInverseInertia = 7,
              kDeltaPosition = 8, kDeltaRotation = 12;
static_assert(offsetof(SolverBody, angular_velocity) == kAngularVelocity * sizeof(float) &&
              offsetof(SolverBody, inverse_mass) == kInverseMass * sizeof(float) &&
              offsetof(SolverBody, inverse_inertia_xx) == kInverseInertia * sizeof(float) &&
              offsetof(SolverBody, delta_position) == kDeltaPosition * sizeof(float) &&
              offsetof(SolverBody, delta_rotation) == kDeltaRotation * sizeof(float));

using LaneIndex = LaneMask;  // 32-bit integer lanes

// each lane's body as the offset of its first float in the body array
LaneIndex body_offsets(const std::array<std::uint32_t, W>& bodies) {
  LaneIndex index;
  for (std::size_t i = 0; i < W; ++i) index[i] = std::int32_t(bodies[i] * kBodyFloats);
  return index;
}

// a manifold's tangents (ContactBlock::tangent_scale): computed from the normal as read, the
// narrow phase's basis (contacts.cpp, tangent_basis), t0 × t1 = n
struct Tangents {
  V3 t0, t1;
};
Tangents tangents_of(const ContactBlock& c, const V3& n) {
  const Lane s = c.tangent_scale, zero = splat(0.0f);
  const LaneMask along_x = s > zero;
  const V3 t0{s * simd::select(along_x, n.y, zero), (zero - s) * simd::select(along_x, n.x, n.z),
              s * simd::select(along_x, zero, n.y)};
  return {t0, cross(n, t0)};
}

// a block's offset from each point's anchor from a to its anchor from b, in the manifold's frame:
// the point is the same for both bodies, so it is x_a − x_b, and the centres' difference (prepare()
// takes both centres from the same points)
struct FrameOffset {
  Lane d[3];
  explicit FrameOffset(const ContactBlock& c)
      : d{c.centre_b[0] - c.centre_a[0], c.centre_b[1] - c.centre_a[1],
          c.centre_b[2] - c.centre_a[2]} {}
};

// a point's normal row: the angular parts r × n on each body (their response I⁻¹ (r × n) is
// computed where an impulse is applied). For r = α t0 + β t1 + γ n in the manifold's frame
// (t0 × t1 = n), r × n = β t0 − α t1. Computed where read rather than kept in the block: the
// solve at a large pyramid is bound by the bytes it streams, and these lanes a point cost more to
// load than to compute
struct NormalRow {
  V3 angular_a, angular_b;

  NormalRow(const ContactBlock::Point& p, const V3& t0, const V3& t1, const FrameOffset& offset)
      : angular_a(p.anchor[1] * t0 - p.anchor[0] * t1),
        angular_b((p.anchor[1] + offset.d[1]) * t0 - (p.anchor[0] + offset.d[0]) * t1) {}
};

// a block's two world inverse inertias as six lanes each (xx yy zz xy xz yz), xx from the bodies'
// records (LanePair) and the rest from the block's rest; on an isotropic block
// (ContactLanes::isotropic: every lane's c·1) only the first, c, is read and used
struct BlockInertia {
  Lane a[6], b[6];
};

// the two bodies of each lane, read from the body array, and written back
struct LanePair {
  V3 va, wa, vb, wb;
  Lane inverse_mass_a, inverse_mass_b;
  // each body's world inverse inertia, xx (the rest is in ContactBlockRest; on an isotropic block,
  // ContactLanes::isotropic, this is the whole of it, c in c·1)
  Lane inertia_a, inertia_b;
  LaneIndex a, b;  // each lane's bodies as offsets into the body array's floats

  // each body's velocities, inverse mass and inertia's xx are its first eight floats: read as
  // records and transposed, rather than gathered a float at a time (simd::gather_records)
  [[gnu::always_inline]] LanePair(const std::vector<SolverBody>& bodies, const ContactBlock& block)
      : a(body_offsets(block.body_a)), b(body_offsets(block.body_b)) {
    static_assert(kLinearVelocity == 0 && kAngularVelocity == 3 && kInverseMass == 6 &&
                  kInverseInertia == 7);
    const float* base = reinterpret_cast<const float*>(bodies.data());
    Lane rows[8];
    simd::gather_records(base, a, rows);
    va = {rows[0], rows[1], rows[2]}, wa = {rows[3], rows[4], rows[5]};
    inverse_mass_a = rows[6], inertia_a = rows[7];
    simd::gather_records(base, b, rows);
    vb = {rows[0], rows[1], rows[2]}, wb = {rows[3], rows[4], rows[5]};
    inverse_mass_b = rows[6], inertia_b = rows[7];
  }
  // static bodies and the body at rest are never written: colours share them, and their
  // threads may not write the same memory (a colour's dynamic bodies are each in one lane)
  [[gnu::always_inline]] void store(std::vector<SolverBody>& bodies) const {
    float* base = reinterpret_cast<float*>(bodies.data());
    const Lane zero = splat(0.0f);
    const Lane rows_a[6] = {va.x, va.y, va.z, wa.x, wa.y, wa.z};
    const Lane rows_b[6] = {vb.x, vb.y, vb.z, wb.x, wb.y, wb.z};
    simd::scatter_records(base, a, rows_a, inverse_mass_a > zero);
    simd::scatter_records(base, b, rows_b, inverse_mass_b > zero);
  }
  // the relative velocity along the normal, by the point's row
  Lane normal_velocity(const V3& n, const NormalRow& row) const {
    return dot(n, vb - va) + dot(wb, row.angular_b) - dot(wa, row.angular_a);
  }
  // an impulse λ n on b at its anchor, and its opposite on a, by the point's row
  void apply_normal(const BlockInertia& m, const NormalRow& row, const V3& n, Lane impulse) {
    va = va - (inverse_mass_a * impulse) * n;
    wa = wa - impulse * times(m.a, row.angular_a);
    vb = vb + (inverse_mass_b * impulse) * n;
    wb = wb + impulse * times(m.b, row.angular_b);
  }
  // an impulse P on b at its anchor rb, and −P on a at ra
  void apply(const BlockInertia& m, const V3& ra, const V3& rb, const V3& impulse) {
    va = va - inverse_mass_a * impulse;
    wa = wa - times(m.a, cross(ra, impulse));
    vb = vb + inverse_mass_b * impulse;
    wb = wb + times(m.b, cross(rb, impulse));
  }
  // an angular impulse L n on b, and its opposite on a
  void apply_twist(const BlockInertia& m, const V3& n, Lane impulse) {
    wa = wa - impulse * times(m.a, n);
    wb = wb + impulse * times(m.b, n);
  }
  // the relative velocity at the anchors ra, rb
  V3 relative_velocity(const V3& ra, const V3& rb) const {
    return (vb + cross(wb, rb)) - (va + cross(wa, ra));
  }
};

template <bool kIsotropic>
BlockInertia inertia_of(const LanePair& pair, const ContactBlockRest& r) {
  BlockInertia m{};
  m.a[0] = pair.inertia_a, m.b[0] = pair.inertia_b;
  if constexpr (!kIsotropic)
    for (int k = 0; k < 5; ++k) {
      m.a[1 + k] = r.inverse_inertia_a[k];
      m.b[1 + k] = r.inverse_inertia_b[k];
    }
  return m;
}

}  // namespace

}  // namespace rtp
