#include "physbench/overlaps.h"

#include <algorithm>
#include <limits>
#include <map>

#include "rtp/collision.h"

namespace physbench {

struct OverlapGauge::Parts {
  const Scene& scene;
  std::map<int, std::size_t> slot;  // scene body → index in a sample
  std::vector<int> bodies;          // the scene bodies measured
  std::vector<rtp::ConvexHull> hulls;
  std::vector<rtp::Shape> shapes;   // one per bodies entry

  // the least overlap of two boxes along the face normals of either (0 when one separates them)
  double face_axis_overlap(std::size_t a, std::size_t b,
                           const std::vector<rtp::Pose>& poses) const {
    const Vec3& ha = scene.bodies[bodies[a]].shape.half_extents;
    const Vec3& hb = scene.bodies[bodies[b]].shape.half_extents;
    const Vec3 between = poses[b].position - poses[a].position;
    double least = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 6; ++k) {
      const Vec3 axis = k < 3 ? Vec3(poses[a].rotation.col(k)) : Vec3(poses[b].rotation.col(k - 3));
      const double reach = (poses[a].rotation.transpose() * axis).cwiseAbs().dot(ha) +
                           (poses[b].rotation.transpose() * axis).cwiseAbs().dot(hb);
      least = std::min(least, reach - std::abs(between.dot(axis)));
    }
    return std::max(least, 0.0);
  }
};

OverlapGauge::OverlapGauge(const Scene& scene, const std::vector<int>& probed)
    : parts_(std::make_unique<Parts>(Parts{scene, {}, {}, {}, {}})) {
  Parts& p = *parts_;
  for (std::size_t i = 0; i < probed.size(); ++i)
    if (probed[i] < static_cast<int>(scene.bodies.size())) p.slot[probed[i]] = i;
  for (int i = 0; i < static_cast<int>(scene.bodies.size()); ++i) {
    const BodySpec& b = scene.bodies[i];
    if (b.mass > 0.0 && !p.slot.count(i)) continue;
    if (b.shape.kind == ShapeKind::Box) {
      p.shapes.push_back(rtp::Shape::box(std::uint32_t(p.hulls.size()), b.shape.half_extents));
      p.hulls.push_back(rtp::make_box_hull(b.shape.half_extents));
    } else if (b.shape.kind == ShapeKind::Sphere) {
      p.shapes.push_back(rtp::Shape::sphere(b.shape.radius));
    } else {
      p.shapes.push_back(rtp::Shape::plane(Vec3::UnitY(), 0.0));
    }
    p.bodies.push_back(i);
  }
}

OverlapGauge::~OverlapGauge() = default;
OverlapGauge::OverlapGauge(OverlapGauge&&) noexcept = default;

void OverlapGauge::measure(const Sample& sample, Overlaps& out) const {
  const Parts& p = *parts_;
  const Scene& scene = p.scene;
  const std::size_t n = p.bodies.size();
  out.deepest = 0.0;
  out.body_depth.assign(sample.bodies.size(), 0.0);
  out.points.clear();
  std::vector<rtp::Pose> poses(n);
  std::vector<Vec3> low(n), high(n);
  std::vector<std::size_t> solids, planes;
  constexpr std::size_t kUnprobed = ~std::size_t{0};
  std::vector<std::size_t> column(n, kUnprobed);  // measured body → its index in the sample
  for (std::size_t k = 0; k < n; ++k) {
    const BodySpec& b = scene.bodies[p.bodies[k]];
    const auto slot = p.slot.find(p.bodies[k]);
    const bool moving = b.mass > 0.0 && slot != p.slot.end();
    if (moving) column[k] = slot->second;
    const Vec3 position = moving ? sample.bodies[slot->second].position : b.position;
    const Quat orientation =
        moving ? sample.bodies[slot->second].orientation.normalized() : b.orientation;
    poses[k] = rtp::Pose(position, orientation);
    if (b.shape.kind == ShapeKind::Plane) {
      planes.push_back(k);
      continue;
    }
    const Vec3 reach = b.shape.kind == ShapeKind::Box
                           ? Vec3(poses[k].rotation.cwiseAbs() * b.shape.half_extents)
                           : Vec3::Constant(b.shape.radius);
    low[k] = position - reach;
    high[k] = position + reach;
    solids.push_back(k);
  }
  rtp::Manifold manifold;
  auto test = [&](std::size_t a, std::size_t b) {
    if (!rtp::collide(p.hulls, p.shapes[a], poses[a], p.shapes[b], poses[b], manifold)) return;
    double depth = manifold.count ? manifold.depth : 0.0;
    for (std::uint8_t k = 0; k < manifold.count; ++k)
      depth = std::max(depth, manifold.points[k].depth);
    double bound = std::numeric_limits<double>::infinity();
    if (p.shapes[a].kind == rtp::ShapeKind::Box && p.shapes[b].kind == rtp::ShapeKind::Box)
      bound = p.face_axis_overlap(a, b, poses);
    depth = std::min(depth, bound);
    out.deepest = std::max(out.deepest, depth);
    for (std::size_t k : {a, b})
      if (column[k] != kUnprobed)
        out.body_depth[column[k]] = std::max(out.body_depth[column[k]], depth);
    for (std::uint8_t k = 0; k < manifold.count; ++k)
      out.points.push_back({manifold.points[k].point, std::min(manifold.points[k].depth, bound)});
  };
  auto is_static = [&](std::size_t k) { return scene.bodies[p.bodies[k]].mass == 0.0; };
  std::sort(solids.begin(), solids.end(),
            [&](std::size_t a, std::size_t b) { return low[a].x() < low[b].x(); });
  for (std::size_t i = 0; i < solids.size(); ++i) {
    const std::size_t a = solids[i];
    for (std::size_t j = i + 1; j < solids.size() && low[solids[j]].x() <= high[a].x(); ++j) {
      const std::size_t b = solids[j];
      if (is_static(a) && is_static(b)) continue;
      if (low[b].y() > high[a].y() || low[a].y() > high[b].y() || low[b].z() > high[a].z() ||
          low[a].z() > high[b].z())
        continue;
      test(a, b);
    }
    if (!is_static(a))
      for (std::size_t plane : planes) test(a, plane);
  }
}

double OverlapGauge::deepest(const Sample& sample) const {
  Overlaps overlaps;
  measure(sample, overlaps);
  return overlaps.deepest;
}

}  // namespace physbench
