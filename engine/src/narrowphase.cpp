// The narrow phase's entry: the shapes, and collide(), which picks one stateless collision function
// from a table indexed by the two kinds (as MuJoCo's mjCOLLISIONFUNC does). The families are one
// file each (narrowphase_internal.h lists them); the design is in rtp/collision.h.
#include <cstdint>
#include <span>

#include "narrowphase_internal.h"

namespace rtp {
using namespace detail;
namespace {

// the table holds each pair once in the order written; the mirrored entries swap the shapes
// and turn the normal round
template <CollideFunction function>
bool mirrored(std::span<const ConvexHull> hulls, const Shape& a, const Pose& pose_a,
              const Shape& b, const Pose& pose_b, Manifold& out) {
  const bool touching = function(hulls, b, pose_b, a, pose_a, out);
  out.normal = -out.normal;
  for (std::uint8_t i = 0; i < out.count; ++i) out.points[i].feature.flipped ^= 1;
  return touching;
}

bool never(std::span<const ConvexHull>, const Shape&, const Pose&, const Shape&, const Pose&,
           Manifold& out) {
  return no_contact(out);
}

// sphere, box, hull, plane; a box against a hull or a plane is a hull
constexpr CollideFunction kCollide[kShapeKinds][kShapeKinds] = {
    {collide_spheres, collide_sphere_box, collide_sphere_hull, collide_sphere_plane},
    {mirrored<collide_sphere_box>, collide_boxes, collide_hulls, collide_hull_plane},
    {mirrored<collide_sphere_hull>, collide_hulls, collide_hulls, collide_hull_plane},
    {mirrored<collide_sphere_plane>, mirrored<collide_hull_plane>, mirrored<collide_hull_plane>,
     never},
};

}  // namespace

Shape Shape::sphere(double radius) {
  Shape s;
  s.kind = ShapeKind::Sphere;
  s.radius = radius;
  return s;
}

Shape Shape::box(std::uint32_t box_hull, const Vec3& half_extents) {
  Shape s;
  s.kind = ShapeKind::Box;
  s.half_extents = half_extents;
  s.hull = box_hull;
  return s;
}

Shape Shape::convex(std::uint32_t hull) {
  Shape s;
  s.kind = ShapeKind::Hull;
  s.hull = hull;
  return s;
}

Shape Shape::plane(const Vec3& normal, double offset) {
  Shape s;
  s.kind = ShapeKind::Plane;
  s.plane_normal = normal.normalized();
  s.plane_offset = offset;
  return s;
}

bool collide(std::span<const ConvexHull> hulls, const Shape& a, const Pose& pose_a, const Shape& b,
             const Pose& pose_b, Manifold& out) {
  out.axes_tested = 0;
  return kCollide[std::size_t(a.kind)][std::size_t(b.kind)](hulls, a, pose_a, b, pose_b, out);
}

}  // namespace rtp
