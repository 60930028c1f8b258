// The round shapes and the planes: sphere against sphere, box, hull and plane, and a hull (or box)
// against a plane. Each is one point but the last, which keeps up to four vertices below the plane.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "narrowphase_internal.h"

namespace rtp {
using namespace detail;

// the vertices of a hull below a plane (hull against plane)
constexpr std::size_t kPlaneContacts = kMaxHullVertices;

namespace {

// the contact of a sphere (the first shape) with a solid whose surface point closest to the
// sphere's centre, the outward normal there and the centre's signed distance from it are known in
// the solid's frame; the manifold's normal runs from the sphere to the solid
bool sphere_contact(double radius, const Pose& sphere_pose, const Pose& solid_pose,
                    const Vec3& normal_in_solid, const Vec3& surface_in_solid, double distance,
                    Manifold& out) {
  const Vec3 normal = -(solid_pose.rotation * normal_in_solid);
  const Vec3 surface_b = solid_pose.position + solid_pose.rotation * surface_in_solid;
  const Vec3 surface_a = sphere_pose.position + radius * normal;
  return single_contact(normal, radius - distance, 0.5 * (surface_a + surface_b), out);
}

}  // namespace

bool collide_spheres(std::span<const ConvexHull>, const Shape& a, const Pose& pose_a,
                     const Shape& b, const Pose& pose_b, Manifold& out) {
  const Vec3 d = pose_b.position - pose_a.position;
  const double distance = d.norm(), reach = a.radius + b.radius;
  if (distance > reach) return no_contact(out);
  // concentric spheres: any direction will do, up is as good as any
  const Vec3 normal = distance > 0.0 ? Vec3(d / distance) : Vec3::UnitY();
  const Vec3 surface_a = pose_a.position + a.radius * normal;
  const Vec3 surface_b = pose_b.position - b.radius * normal;
  return single_contact(normal, reach - distance, 0.5 * (surface_a + surface_b), out);
}

bool collide_sphere_box(std::span<const ConvexHull>, const Shape& a, const Pose& pose_a,
                        const Shape& b, const Pose& pose_b, Manifold& out) {
  // the sphere's centre in the box frame, and the closest point of the box to it
  const Vec3 centre = pose_b.rotation.transpose() * (pose_a.position - pose_b.position);
  const Vec3 closest = centre.cwiseMax(-b.half_extents).cwiseMin(b.half_extents);
  const Vec3 gap = centre - closest;
  const double distance_squared = gap.squaredNorm();
  if (distance_squared > a.radius * a.radius) return no_contact(out);
  Vec3 normal_in_box;  // from the box towards the sphere
  double distance;     // signed: negative when the centre is inside the box
  Vec3 surface_in_box;
  if (distance_squared > 0.0) {
    distance = std::sqrt(distance_squared);
    normal_in_box = gap / distance;
    surface_in_box = closest;
  } else {
    // the centre is inside: leave through the nearest face
    const Vec3 depth_to_face = b.half_extents - centre.cwiseAbs();
    int axis;
    depth_to_face.minCoeff(&axis);
    normal_in_box = Vec3::Zero();
    normal_in_box[axis] = centre[axis] >= 0.0 ? 1.0 : -1.0;
    distance = -depth_to_face[axis];
    surface_in_box = centre;
    surface_in_box[axis] = normal_in_box[axis] * b.half_extents[axis];
  }
  return sphere_contact(a.radius, pose_a, pose_b, normal_in_box, surface_in_box, distance, out);
}

bool collide_sphere_hull(std::span<const ConvexHull> hulls, const Shape& a, const Pose& pose_a,
                         const Shape& b, const Pose& pose_b, Manifold& out) {
  const ConvexHull& hull = hull_of(b, hulls);
  const Vec3 centre = pose_b.rotation.transpose() * (pose_a.position - pose_b.position);
  // the face plane farthest from the centre: beyond the radius, separated
  double largest = -std::numeric_limits<double>::infinity();
  std::uint32_t largest_face = 0;
  for (std::uint32_t f = 0; f < hull.faces.size(); ++f) {
    const double d = hull.faces[f].normal.dot(centre) - hull.faces[f].offset;
    if (d > largest) largest = d, largest_face = f;
  }
  if (largest > a.radius) return no_contact(out);

  Vec3 normal_in_hull, surface_in_hull = Vec3::Zero();
  double distance;
  if (largest <= 0.0) {
    // inside: out through the nearest face plane
    normal_in_hull = hull.faces[largest_face].normal;
    distance = largest;
    surface_in_hull = centre - largest * normal_in_hull;
  } else {
    // outside: the closest point lies on a face the centre sees; each face is a fan of
    // triangles, and lab 4.1 finds the closest point of each
    double best = std::numeric_limits<double>::infinity();
    for (const HullFace& face : hull.faces) {
      if (face.normal.dot(centre) - face.offset <= 0.0) continue;
      const Vec3& apex = hull.vertices[hull.face_vertices[face.first]];
      for (std::uint32_t i = 1; i + 1 < face.count; ++i) {
        const TrianglePoint q = closest_point_on_triangle(
            centre, apex, hull.vertices[hull.face_vertices[face.first + i]],
            hull.vertices[hull.face_vertices[face.first + i + 1]]);
        if (double d = (centre - q.point).squaredNorm(); d < best)
          best = d, surface_in_hull = q.point;
      }
    }
    distance = std::sqrt(best);
    if (distance > a.radius) return no_contact(out);
    normal_in_hull = distance > 0.0 ? Vec3((centre - surface_in_hull) / distance)
                                    : hull.faces[largest_face].normal;
  }
  return sphere_contact(a.radius, pose_a, pose_b, normal_in_hull, surface_in_hull, distance, out);
}

bool collide_sphere_plane(std::span<const ConvexHull>, const Shape& a, const Pose& pose_a,
                          const Shape& b, const Pose& pose_b, Manifold& out) {
  const Vec3 plane_normal = pose_b.rotation * b.plane_normal;
  const double plane_offset = b.plane_offset + plane_normal.dot(pose_b.position);
  const double height = plane_normal.dot(pose_a.position) - plane_offset;
  if (height > a.radius) return no_contact(out);
  const Vec3 surface_a = pose_a.position - a.radius * plane_normal;
  const Vec3 surface_b = pose_a.position - height * plane_normal;
  return single_contact(-plane_normal, a.radius - height, 0.5 * (surface_a + surface_b), out);
}

bool collide_hull_plane(std::span<const ConvexHull> hulls, const Shape& a, const Pose& pose_a,
                        const Shape& b, const Pose& pose_b, Manifold& out) {
  const ConvexHull& hull = hull_of(a, hulls);
  const Vec3 plane_normal = pose_b.rotation * b.plane_normal;
  const double plane_offset = b.plane_offset + plane_normal.dot(pose_b.position);
  // every vertex on or below the plane, then the four that span the most
  const Vec3 normal_in_hull = pose_a.rotation.transpose() * plane_normal;
  const double centre_height = plane_normal.dot(pose_a.position) - plane_offset;
  std::array<ContactPoint, kPlaneContacts> points;
  std::size_t count = 0;
  double deepest = 0.0;
  for (std::uint32_t i = 0; i < hull.vertices.size(); ++i) {
    const double height = centre_height + normal_in_hull.dot(hull.vertices[i]);
    if (height > 0.0) continue;
    const Vec3 vertex = pose_a.position + pose_a.rotation * hull.vertices[i];
    if (count == points.size()) break;
    points[count++] = {vertex - 0.5 * height * plane_normal, -height,
                       ContactFeature{0, std::uint16_t(i), 0, 0, ContactType::FaceVertex, 1}};
    deepest = std::max(deepest, -height);
  }
  if (count == 0) return no_contact(out);
  if (count > 4) reduce_to_four(points, count, plane_normal);
  out.normal = -plane_normal;
  out.depth = deepest;
  out.count = std::uint8_t(count);
  out.axes_tested = 0;
  std::copy(points.begin(), points.begin() + count, out.points.begin());
  return true;
}

}  // namespace rtp
