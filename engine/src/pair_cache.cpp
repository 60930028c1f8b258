// The pair cache (as Jolt's body pair cache; docs/solver.md, step 4): a candidate pair's pose
// when the narrow phase last tested it, how far each shape has moved in the other's frame since
// (a pair a lane), and a touching box pair's manifold moved with its bodies instead of computed.
// With the growth each pair's narrow phase gives its shapes. Part of collide_pairs() (contacts.cpp).
#include "contacts.h"

#include <algorithm>
#include <cstddef>
#include <limits>

namespace rtp {
inline namespace RTP_CONTACT_ISA_NAMESPACE {

void ContactPipeline::record_pose(BodyId a, BodyId b, float* out) const {
  // the pair's pose as an entry holds it, fifteen floats: Raᵀ(xb − xa), Rbᵀ(xa − xb), Raᵀ Rb
  // (column by column), from the rotations motion_in_lanes reads
  using RowMajor3f = Eigen::Matrix<float, 3, 3, Eigen::RowMajor>;
  const Eigen::Map<const RowMajor3f> ra(rotations_[a].data()), rb(rotations_[b].data());
  const Eigen::Vector3f d = (poses_[b].position - poses_[a].position).cast<float>();
  Eigen::Map<Eigen::Vector3f> offset_in_a(out), offset_in_b(out + 3);
  Eigen::Map<Eigen::Matrix3f> relative_rotation(out + 6);
  offset_in_a = ra.transpose() * d;
  offset_in_b = -(rb.transpose() * d);
  relative_rotation = ra.transpose() * rb;
}

void ContactPipeline::cache_pair(BodyId a, BodyId b, double growth, const Manifold* manifold,
                                 CachedPair& out) const {
  // in single precision from the rotations motion_in_lanes reads, each vector from a body's
  // centre taken in double first: the entry holds floats (written in place: it is 208 bytes)
  using RowMajor3f = Eigen::Matrix<float, 3, 3, Eigen::RowMajor>;
  const Eigen::Map<const RowMajor3f> ra(rotations_[a].data()), rb(rotations_[b].data());
  const Vec3& xa = poses_[a].position;
  const Vec3& xb = poses_[b].position;
  static_assert(offsetof(CachedPair, offset_in_b) == 3 * sizeof(float) &&
                offsetof(CachedPair, relative_rotation) == 6 * sizeof(float));
  record_pose(a, b, out.offset_in_a.data());
  out.growth = float(growth);
  out.count = 0;
  out.normal_on_b = false;
  if (manifold == nullptr) return;
  // a face's normal turns with the body whose face it is; a point is the midpoint of the two
  // surface points it joins, which are half its depth either side along the normal
  out.count = manifold->count;
  out.normal_on_b = manifold->points[0].feature.flipped != 0;
  const Eigen::Vector3f normal = manifold->normal.cast<float>();
  out.normal = (out.normal_on_b ? rb : ra).transpose() * normal;
  for (std::uint8_t j = 0; j < manifold->count; ++j) {
    const ContactPoint& p = manifold->points[j];
    const Eigen::Vector3f half = float(0.5 * p.depth) * normal;
    out.points[j].on_a = ra.transpose() * ((p.point - xa).cast<float>() + half);
    out.points[j].on_b = rb.transpose() * ((p.point - xb).cast<float>() - half);
    out.points[j].feature = p.feature;
  }
}


void ContactPipeline::motion_in_lanes(const std::uint32_t* ks, std::size_t count,
                                      std::array<std::array<float, 2>, kMotionLanes>& out) const {
  std::array<std::uint64_t, kMotionLanes> keys{};
  std::array<std::int32_t, kMotionLanes> at{};
  std::array<bool, kMotionLanes> valid{};
  constexpr int kEntryFloats = int(sizeof(CachedPair) / sizeof(float));
  for (std::size_t i = 0; i < count; ++i) {
    const std::size_t k = ks[i];
    if (!has_entry_[k]) continue;
    valid[i] = true;
    keys[i] = candidates_[k];
    at[i] = std::int32_t(candidate_slot_[k]) * kEntryFloats;
  }
  motion_since(reinterpret_cast<const float*>(cache_pool_.data()), keys, at, valid, out);
}

void ContactPipeline::held_motion_in_lanes(
    std::size_t first, std::size_t last,
    std::array<std::array<float, 2>, kMotionLanes>& out) const {
  std::array<std::uint64_t, kMotionLanes> keys{};
  std::array<std::int32_t, kMotionLanes> at{};
  std::array<bool, kMotionLanes> valid{};
  for (std::size_t i = 0; i < kMotionLanes; ++i) {
    const std::size_t c = first + i;
    if (c >= last) continue;
    valid[i] = true;
    keys[i] = contact_keys_[c];
    at[i] = std::int32_t(c * kPackedPoseFloats);
  }
  motion_since(packed_poses_.front().data(), keys, at, valid, out);
}

void ContactPipeline::motion_since(const float* entries,
                                   const std::array<std::uint64_t, kMotionLanes>& keys,
                                   const std::array<std::int32_t, kMotionLanes>& at,
                                   const std::array<bool, kMotionLanes>& valid,
                                   std::array<std::array<float, 2>, kMotionLanes>& out) const {
  // How far b's shape has moved in a's frame since the entry was made: by the offset's change,
  // and by the rotation's change at b's farthest surface point (‖ΔR‖₂ ≤ ‖ΔR‖_F); and a's in b's
  // frame likewise. A plane has no bound of its own, and its motion in the other's frame, about
  // an origin that may lie tens of metres off, says nothing of the contact (it is flat everywhere
  // and static): its side is the other's, the other shape's motion in the plane's frame. In
  // single precision, a pair a lane: the rotations and the entries' poses read as records and
  // transposed, the offset between the centres taken in double first (m; each pair's a, b)
  // (the pose recorded at entries + at[i], lane i's pair keys[i], where valid[i])
  using L = simd::Pack<float, kMotionLanes>;
  using Index = simd::MaskOf<L>;
  static_assert(sizeof(CachedPair) % sizeof(float) == 0 &&
                offsetof(CachedPair, offset_in_b) == 3 * sizeof(float) &&
                offsetof(CachedPair, relative_rotation) == 6 * sizeof(float));
  alignas(64) float offset[3][kMotionLanes] = {}, reach_a[kMotionLanes] = {},
                    reach_b[kMotionLanes] = {};
  std::array<bool, kMotionLanes> plane_a{}, plane_b{};
  Index at_a{}, at_b{}, at_entry{};
  bool any = false;
  for (std::size_t i = 0; i < kMotionLanes; ++i) {
    // a lane without an entry reads body 0 and entry 0 (there is one: some lane has an entry)
    at_a[i] = at_b[i] = at_entry[i] = 0;
    if (!valid[i]) continue;
    any = true;
    const BodyId a = BodyId(keys[i] >> 32), b = BodyId(keys[i] & 0xffffffffu);
    const Vec3 d = poses_[b].position - poses_[a].position;
    for (int j = 0; j < 3; ++j) offset[j][i] = float(d[j]);
    reach_a[i] = float(shapes_[a].reach);
    reach_b[i] = float(shapes_[b].reach);
    plane_a[i] = shapes_[a].kind == BodyShape::Plane;
    plane_b[i] = shapes_[b].kind == BodyShape::Plane;
    at_a[i] = std::int32_t(a * kRotationFloats);
    at_b[i] = std::int32_t(b * kRotationFloats);
    at_entry[i] = at[i];
  }
  if (!any) return;
  const float* rotations = rotations_.front().data();
  L a_low[8], a_high[8], b_low[8], b_high[8], e_low[8], e_high[8];
  simd::gather_records(rotations, at_a, a_low);
  simd::gather_records(rotations + 8, at_a, a_high);
  simd::gather_records(rotations, at_b, b_low);
  simd::gather_records(rotations + 8, at_b, b_high);
  simd::gather_records(entries, at_entry, e_low);
  simd::gather_records(entries + 8, at_entry, e_high);
  // R(r, c) of each body row by row; the entry's offsets, then Raᵀ Rb column by column
  auto ra = [&](int r, int c) { return 3 * r + c < 8 ? a_low[3 * r + c] : a_high[0]; };
  auto rb = [&](int r, int c) { return 3 * r + c < 8 ? b_low[3 * r + c] : b_high[0]; };
  auto entry = [&](int f) { return f < 8 ? e_low[f] : e_high[f - 8]; };
  const L d[3] = {simd::load<L>(offset[0]), simd::load<L>(offset[1]), simd::load<L>(offset[2])};
  L turned_squared = simd::splat<L>(0.0f), moved_b_squared = turned_squared,
    moved_a_squared = turned_squared;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const L m = ra(0, i) * rb(0, j) + ra(1, i) * rb(1, j) + ra(2, i) * rb(2, j);
      const L change = m - entry(6 + i + 3 * j);
      turned_squared = turned_squared + change * change;
    }
    // Raᵀ (xb − xa) and Rbᵀ (xa − xb) against the entry's
    const L in_a = ra(0, i) * d[0] + ra(1, i) * d[1] + ra(2, i) * d[2] - entry(i);
    const L in_b = simd::splat<L>(0.0f) - (rb(0, i) * d[0] + rb(1, i) * d[1] + rb(2, i) * d[2]) -
                   entry(3 + i);
    moved_b_squared = moved_b_squared + in_a * in_a;
    moved_a_squared = moved_a_squared + in_b * in_b;
  }
  const L turned = simd::sqrt(turned_squared);
  alignas(64) float moved_a[kMotionLanes], moved_b[kMotionLanes];
  simd::store(moved_a, simd::sqrt(moved_a_squared) + turned * simd::load<L>(reach_a));
  simd::store(moved_b, simd::sqrt(moved_b_squared) + turned * simd::load<L>(reach_b));
  for (std::size_t i = 0; i < kMotionLanes; ++i)
    out[i] = {plane_a[i] ? moved_b[i] : moved_a[i], plane_b[i] ? moved_a[i] : moved_b[i]};
}

void ContactPipeline::move_manifold(const CachedPair& cached, BodyId a, BodyId b, double growth,
                                    Manifold& out) const {
  // Each point's two surface points go with their bodies, and its depth is measured between
  // them along the normal, which goes with its face. A face's point that is a corner of the
  // other box (most of a resting pair's) keeps its exact depth however the boxes slide: the
  // face point stays in the face's plane. A point where an edge crosses the face's side is off
  // by the relative motion, which the reuse distance bounds. The depth is of the shapes grown as
  // when computed; the pair's growth since shifts it, so the separation the contact takes is
  // the geometry's own
  const Pose& pa = poses_[a];
  const Pose& pb = poses_[b];
  const Pose& holder = cached.normal_on_b ? pb : pa;
  out.normal = (holder.rotation * cached.normal.cast<double>()).normalized();
  out.count = cached.count;
  double deepest = -std::numeric_limits<double>::infinity();
  for (std::uint8_t j = 0; j < cached.count; ++j) {
    const Vec3 on_a = pa.position + pa.rotation * cached.points[j].on_a.cast<double>();
    const Vec3 on_b = pb.position + pb.rotation * cached.points[j].on_b.cast<double>();
    ContactPoint& p = out.points[j];
    p.point = 0.5 * (on_a + on_b);
    p.depth = out.normal.dot(on_a - on_b) + (growth - double(cached.growth));
    p.feature = cached.points[j].feature;
    deepest = std::max(deepest, p.depth);
  }
  out.depth = deepest;
  out.axes_tested = 0;
}

double ContactPipeline::pair_growth(const BodyShapeData& a, const BodyShapeData& b) const {
  const auto [growth_a, growth_b] = surface_growth(a, b);
  return growth_a + growth_b;
}

std::pair<double, double> ContactPipeline::surface_growth(const BodyShapeData& a,
                                                          const BodyShapeData& b) const {
  // as grow_pair() places the growth: a pair with a hull keeps the fixed growth on both; two
  // boxes each their own; otherwise both shapes' growth beyond the fixed goes to the one that
  // is not a box
  const double fixed = 0.5 * settings_.speculative_distance;
  if (a.kind == BodyShape::Hull || b.kind == BodyShape::Hull) return {fixed, fixed};
  if (a.kind == BodyShape::Box && b.kind == BodyShape::Box) return {a.growth, b.growth};
  const double extra = a.growth + b.growth - 2.0 * fixed;
  if (a.kind != BodyShape::Box) return {fixed + extra, fixed};
  return {fixed, fixed + extra};
}

void ContactPipeline::grow_pair(const BodyShapeData& a, const BodyShapeData& b, Shape& grown_a,
                                Shape& grown_b) const {
  // Both shapes hold the fixed growth already; the growth beyond it goes where surface_growth()
  // places it, to what the collision function reads as a size: a sphere's radius, a plane's
  // offset, a box's half extents (the box path reads those, the hull paths the fixed hulls)
  const double fixed = 0.5 * settings_.speculative_distance;
  const auto [growth_a, growth_b] = surface_growth(a, b);
  auto widen = [](BodyShape kind, Shape& shape, double extra) {
    if (extra <= 0.0) return;
    if (kind == BodyShape::Sphere) shape.radius += extra;
    else if (kind == BodyShape::Plane) shape.plane_offset += extra;
    else if (kind == BodyShape::Box) shape.half_extents.array() += extra;
  };
  widen(a.kind, grown_a, growth_a - fixed);
  widen(b.kind, grown_b, growth_b - fixed);
}

}  // namespace RTP_CONTACT_ISA_NAMESPACE
}  // namespace rtp
