// The broad phase's entry: bounds of shapes, the brute-force reference, and the factory of the
// three variants (broadphase_sap.cpp, broadphase_box_pruning.cpp). The design is in
// rtp/broadphase.h.
#include <limits>
#include <stdexcept>

#include "broadphase_internal.h"

namespace rtp {

Aabb bounds_of_points(const std::vector<Vec3>& body_vertices, const Vec3& position,
                      const Quat& orientation) {
  if (body_vertices.empty()) throw std::invalid_argument("rtp: bounds of no points");
  const Mat3 rotation = orientation.toRotationMatrix();
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const Vec3& v : body_vertices) {
    const Vec3 world = position + rotation * v;
    lo = lo.cwiseMin(world);
    hi = hi.cwiseMax(world);
  }
  return {{float(lo.x()), float(lo.y()), float(lo.z())},
          {float(hi.x()), float(hi.y()), float(hi.z())}};
}

Aabb bounds_of_box(const Vec3& half_extents, const Vec3& position, const Quat& orientation) {
  // the world half extents of a rotated box: |R| h (Ericson §4.2.6)
  const Vec3 extent = orientation.toRotationMatrix().cwiseAbs() * half_extents;
  const Vec3 lo = position - extent, hi = position + extent;
  return {{float(lo.x()), float(lo.y()), float(lo.z())},
          {float(hi.x()), float(hi.y()), float(hi.z())}};
}

Aabb bounds_of_sphere(const Vec3& centre, double radius) {
  return bounds_of_box(Vec3::Constant(radius), centre, Quat::Identity());
}

std::string_view name_of(BroadPhaseKind kind) {
  switch (kind) {
    case BroadPhaseKind::SeedSap:
      return "seed-sap";
    case BroadPhaseKind::IncrementalSap:
      return "incremental-sap";
    case BroadPhaseKind::BoxPruning:
      return "box-pruning";
  }
  return "?";
}

std::vector<ProxyPair> brute_force_pairs(const std::vector<Aabb>& boxes,
                                         const std::vector<bool>& alive) {
  std::vector<ProxyPair> pairs;
  const auto live = [&](std::size_t i) { return alive.empty() || alive[i]; };
  for (std::size_t i = 0; i < boxes.size(); ++i)
    for (std::size_t j = i + 1; j < boxes.size(); ++j)
      if (live(i) && live(j) && overlaps(boxes[i], boxes[j]))
        pairs.push_back({ProxyId(i), ProxyId(j)});
  return pairs;
}

std::unique_ptr<BroadPhase> make_broad_phase(BroadPhaseKind kind) {
  switch (kind) {
    case BroadPhaseKind::SeedSap:
      return detail::make_seed_sap();
    case BroadPhaseKind::IncrementalSap:
      return detail::make_incremental_sap();
    case BroadPhaseKind::BoxPruning:
      return detail::make_box_pruning();
  }
  throw std::invalid_argument("rtp: unknown broad phase kind");
}

}  // namespace rtp
