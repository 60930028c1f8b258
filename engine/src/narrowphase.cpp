// The narrow phase: the Voronoi-region triangle query, the separating axis tests, clipping.
// The design and its sources are in rtp/collision.h.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>

#include "rtp/collision.h"
#include "simd.h"

namespace rtp {
namespace {

// an edge axis replaces the best face axis only when it is shallower by this fraction of the
// depth plus this length: faces give the steadier manifold (Gregorius, GDC 2013, uses 5 %)
constexpr double kEdgeRelativeTolerance = 0.02;
constexpr double kEdgeAbsoluteTolerance = 1e-4;  // m
// two edges whose unit directions' cross product is shorter than this are parallel: their axis
// is numerically meaningless and the face axes cover them (Ericson §4.4.1)
constexpr double kParallelSine = 1e-5;
// the second shape's face is a duplicate of the first's when their normals are this close
constexpr double kDuplicateCosine = 1.0 - 1e-9;

using simd::Double4;
using simd::Double8;
using simd::Mask4;
using simd::load4;
using simd::load8;
constexpr double kInfinity = std::numeric_limits<double>::infinity();
constexpr Double4 kInfinity4 = Double4(kInfinity);
// lanes 0, 1, 2 ← 1, 2, 0; lane 3 stays
inline Double4 rotate4(Double4 x) { return simd::shuffle<1, 2, 0, 3>(x); }
// lanes 0, 1, 2, 3 ← 1, 2, 3, 0
inline Double4 next4(Double4 x) { return simd::shuffle<1, 2, 3, 0>(x); }
// the three rows of a column-major 3×3 matrix (lane 3 zero) from two unaligned loads and shuffles,
// where element-wise loads take three loads and two inserts a row
inline void rows_of(const Mat3& m, Double4 rows[3]) {
  static_assert(sizeof(Mat3) == 9 * sizeof(double));
  const Double4 low = load4(m.data()), high = load4(m.data() + 4);  // m00 m10 m20 m01, m11 m21 m02 m12
  constexpr Mask4 kThree = {-1, -1, -1, 0};
  rows[0] = simd::select(kThree, simd::shuffle<0, 3, 6, 0>(low, high), 0.0);
  rows[1] = simd::select(kThree, simd::shuffle<1, 4, 7, 0>(low, high), 0.0);
  rows[2] = simd::shuffle<2, 5, 0, 0>(low, high);
  rows[2].set(2, m(2, 2)), rows[2].set(3, 0.0);
}
// the columns of a 3×3 matrix held as rows in lanes 0–2 (lane 3 zero), by shuffles
inline void transpose3(const Double4 rows[3], Double4 columns[3]) {
  const Double4 low = simd::shuffle<0, 4, 1, 5>(rows[0], rows[1]);   // r00 r10 r01 r11
  const Double4 high = simd::shuffle<2, 6, 3, 7>(rows[0], rows[1]);  // r02 r12 0 0
  columns[0] = simd::shuffle<0, 1, 4, 7>(low, rows[2]);
  columns[1] = simd::shuffle<2, 3, 5, 7>(low, rows[2]);
  columns[2] = simd::shuffle<0, 1, 6, 3>(high, rows[2]);
}

// the separation an edge axis must exceed to replace the best face axis
double edge_threshold(double face_separation) {
  return face_separation * (1.0 - kEdgeRelativeTolerance) + kEdgeAbsoluteTolerance;
}
bool edge_axis_wins(double edge_separation, double face_separation) {
  return edge_separation > edge_threshold(face_separation);
}

// ---- clipping ----

struct ClipVertex {
  Vec3 point;
  ContactFeature feature;
};

// the vertices of a clipped hull face: the incident face plus one per side plane (boxes clip in
// their own frame, by candidates: collide_boxes)
constexpr std::size_t kHullClip = 2 * kMaxFaceVertices + 2;
// the vertices of a hull below a plane (hull against plane)
constexpr std::size_t kPlaneContacts = kMaxHullVertices;

// a polygon being clipped
struct ClipPolygon {
  std::array<ClipVertex, kHullClip> vertices;
  std::size_t count = 0;
};

// the reference face in the world: its plane and its side planes (normals need not be unit)
struct ReferenceFace {
  Vec3 normal;    // unit, outward
  double offset;  // normal · x = offset on the face
  std::array<Vec3, kMaxFaceVertices> side_normals;
  std::array<double, kMaxFaceVertices> side_offsets;
  std::size_t side_count = 0;
  std::uint16_t face = 0;
};

// Sutherland–Hodgman: the part of the polygon where side · x ≤ offset
void clip_against_side(const ClipPolygon& in, const Vec3& side, double offset,
                       std::uint8_t side_index, ClipPolygon& out) {
  out.count = 0;
  if (in.count == 0) return;
  const ClipVertex* previous = &in.vertices[in.count - 1];
  double previous_distance = side.dot(previous->point) - offset;
  for (std::size_t i = 0; i < in.count; ++i) {
    const ClipVertex& current = in.vertices[i];
    const double distance = side.dot(current.point) - offset;
    if ((previous_distance <= 0.0) != (distance <= 0.0)) {
      // the edge previous → current crosses the side plane: a new point on the incident edge
      // that starts at previous's incident vertex
      const double t = previous_distance / (previous_distance - distance);
      ClipVertex& crossing = out.vertices[out.count++];
      crossing.point = previous->point + t * (current.point - previous->point);
      crossing.feature = previous->feature;
      crossing.feature.type = ContactType::FaceClip;
      crossing.feature.reference_side = side_index;
    }
    if (distance <= 0.0) out.vertices[out.count++] = current;
    previous = &current;
    previous_distance = distance;
  }
}

// which four of n > 4 points to keep: the deepest, the farthest from it, the one making the
// largest triangle with those two, and the one adding the most area outside that triangle.
// position(i) is a point in any vector type; area(p, q, r) the signed area of pqr about the normal.
template <typename Depth, typename Position, typename Area>
std::array<std::size_t, 4> choose_four(std::size_t count, Depth depth, Position position,
                                       Area area) {
  std::array<std::size_t, 4> chosen{};
  for (std::size_t i = 1; i < count; ++i)
    if (depth(i) > depth(chosen[0])) chosen[0] = i;
  const auto p0 = position(chosen[0]);
  double best = -1.0;
  for (std::size_t i = 0; i < count; ++i)
    if (double d = (position(i) - p0).squaredNorm(); d > best) best = d, chosen[1] = i;
  const auto p1 = position(chosen[1]);
  best = -1.0;
  for (std::size_t i = 0; i < count; ++i)
    if (double a = std::abs(area(p0, p1, position(i))); a > best) best = a, chosen[2] = i;
  const auto p2 = position(chosen[2]);
  const double orientation = area(p0, p1, p2) >= 0.0 ? 1.0 : -1.0;
  best = -std::numeric_limits<double>::infinity();
  chosen[3] = chosen[0];
  for (std::size_t i = 0; i < count; ++i) {
    if (i == chosen[0] || i == chosen[1] || i == chosen[2]) continue;
    const auto q = position(i);
    // the area q adds: the largest triangle it makes outside one of the three edges
    const double added =
        -orientation * std::min({area(p0, p1, q), area(p1, p2, q), area(p2, p0, q)});
    if (added > best) best = added, chosen[3] = i;
  }
  return chosen;
}

// keeps four of n > 4 contact points (choose_four in the world)
template <std::size_t Capacity>
void reduce_to_four(std::array<ContactPoint, Capacity>& points, std::size_t& count,
                    const Vec3& normal) {
  const std::array<std::size_t, 4> chosen = choose_four(
      count, [&](std::size_t i) { return points[i].depth; },
      [&](std::size_t i) -> const Vec3& { return points[i].point; },
      [&](const Vec3& p, const Vec3& q, const Vec3& r) {
        return (q - p).cross(r - p).dot(normal);
      });
  std::array<ContactPoint, 4> kept;
  for (int k = 0; k < 4; ++k) kept[k] = points[chosen[k]];
  std::copy(kept.begin(), kept.end(), points.begin());
  count = 4;
}

// clips the incident polygon to the reference face and writes the manifold; `flipped` when the
// second shape holds the reference face (the manifold's normal then opposes the face's)
void clip_to_manifold(const ReferenceFace& reference, const ClipPolygon& incident, bool flipped,
                      double depth, Manifold& out) {
  ClipPolygon buffers[2];
  const ClipPolygon* current = &incident;
  for (std::size_t s = 0; s < reference.side_count; ++s) {
    ClipPolygon& next = buffers[s % 2];
    clip_against_side(*current, reference.side_normals[s], reference.side_offsets[s],
                      std::uint8_t(s), next);
    current = &next;
  }

  // points on or below the reference face, placed midway between the two surfaces
  std::array<ContactPoint, kHullClip> points;
  std::size_t count = 0;
  for (std::size_t i = 0; i < current->count; ++i) {
    const ClipVertex& v = current->vertices[i];
    const double distance = reference.normal.dot(v.point) - reference.offset;
    if (distance > 0.0) continue;
    ContactPoint& p = points[count++];
    p.point = v.point - 0.5 * distance * reference.normal;
    p.depth = -distance;
    p.feature = v.feature;
    p.feature.reference = reference.face;
    p.feature.flipped = flipped;
  }
  if (count > 4) reduce_to_four(points, count, reference.normal);

  out.normal = flipped ? Vec3(-reference.normal) : reference.normal;
  out.depth = depth;
  out.count = std::uint8_t(count);
  std::copy(points.begin(), points.begin() + count, out.points.begin());
}

// the closest points of segments p1 + s d1 and p2 + t d2, s, t ∈ [0, 1] (Ericson §5.1.9)
void closest_points_of_segments(const Vec3& p1, const Vec3& d1, const Vec3& p2, const Vec3& d2,
                                Vec3& c1, Vec3& c2) {
  const Vec3 r = p1 - p2;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  const double c = d1.dot(r), b = d1.dot(d2);
  const double denominator = a * e - b * b;
  double s = denominator > 1e-30 ? std::clamp((b * f - c * e) / denominator, 0.0, 1.0) : 0.0;
  double t = (b * s + f) / e;
  if (t < 0.0) {
    t = 0.0;
    s = std::clamp(-c / a, 0.0, 1.0);
  } else if (t > 1.0) {
    t = 1.0;
    s = std::clamp((b - c) / a, 0.0, 1.0);
  }
  c1 = p1 + s * d1;
  c2 = p2 + t * d2;
}

// one edge–edge contact point midway between the edges' closest points
void edge_contact(const Vec3& tail_a, const Vec3& edge_a, const Vec3& tail_b, const Vec3& edge_b,
                  const Vec3& normal, double depth, std::uint16_t feature_a,
                  std::uint16_t feature_b, Manifold& out) {
  Vec3 on_a, on_b;
  closest_points_of_segments(tail_a, edge_a, tail_b, edge_b, on_a, on_b);
  out.normal = normal;
  out.depth = depth;
  out.count = 1;
  out.points[0].point = 0.5 * (on_a + on_b);
  out.points[0].depth = depth;
  out.points[0].feature = {feature_a, feature_b, 0, 0, ContactType::EdgeEdge, 0};
}

// a manifold of one point, for the round shapes and the planes
bool single_contact(const Vec3& normal, double depth, const Vec3& point, Manifold& out) {
  out.normal = normal;
  out.depth = depth;
  out.count = 1;
  out.points[0] = {point, depth, ContactFeature{}};
  out.axes_tested = 0;
  return true;
}

bool no_contact(Manifold& out) {
  out.count = 0;
  return false;
}

// the reference face `face` of a hull at a pose, with its side planes
void reference_face_of(const ConvexHull& hull, const Pose& pose, std::uint32_t face,
                       ReferenceFace& out) {
  const HullFace& f = hull.faces[face];
  out.normal = pose.rotation * f.normal;
  out.offset = f.offset + out.normal.dot(pose.position);
  out.face = std::uint16_t(face);
  out.side_count = f.count;
  Vec3 tail = pose.position + pose.rotation * hull.vertices[hull.face_vertices[f.first]];
  for (std::uint32_t i = 0; i < f.count; ++i) {
    const Vec3 head =
        pose.position +
        pose.rotation * hull.vertices[hull.face_vertices[f.first + (i + 1) % f.count]];
    // for a counter-clockwise loop, edge × normal points out of the face
    out.side_normals[i] = (head - tail).cross(out.normal);
    out.side_offsets[i] = out.side_normals[i].dot(tail);
    tail = head;
  }
}

void incident_face_of(const ConvexHull& hull, const Pose& pose, std::uint32_t face,
                      ClipPolygon& out) {
  const HullFace& f = hull.faces[face];
  out.count = f.count;
  for (std::uint32_t i = 0; i < f.count; ++i) {
    out.vertices[i].point =
        pose.position + pose.rotation * hull.vertices[hull.face_vertices[f.first + i]];
    out.vertices[i].feature = {0, std::uint16_t(face), 0, std::uint8_t(i), ContactType::FaceVertex,
                               0};
  }
}

// the incident face for a reference normal (world): among the faces around the incident hull's
// deepest vertex, the one most opposed to the normal. The most opposed face of the whole hull
// can lie beside the contact on a hull of many small faces; the faces at the deepest vertex hold
// the deepest point.
std::uint32_t incident_face_for(const ConvexHull& hull, const Pose& pose,
                                const Vec3& reference_normal) {
  const Vec3 local = pose.rotation.transpose() * reference_normal;
  std::uint32_t deepest = 0;
  for (std::uint32_t i = 1; i < hull.vertices.size(); ++i)
    if (hull.vertices[i].dot(local) < hull.vertices[deepest].dot(local)) deepest = i;
  std::uint32_t best = 0;
  double most_opposed = std::numeric_limits<double>::infinity();
  for (std::uint32_t f = 0; f < hull.faces.size(); ++f) {
    const HullFace& face = hull.faces[f];
    const double alignment = face.normal.dot(local);
    if (alignment >= most_opposed) continue;
    for (std::uint32_t i = 0; i < face.count; ++i)
      if (hull.face_vertices[face.first + i] == deepest) {
        most_opposed = alignment, best = f;
        break;
      }
  }
  return best;
}

// the face-contact manifold when `reference_face` of the reference hull is the separating axis
void hull_face_manifold(const ConvexHull& reference_hull, const Pose& reference_pose,
                        std::uint32_t reference_face, const ConvexHull& incident_hull,
                        const Pose& incident_pose, bool flipped, double depth, Manifold& out) {
  ReferenceFace reference;
  reference_face_of(reference_hull, reference_pose, reference_face, reference);
  ClipPolygon incident;
  incident_face_of(incident_hull, incident_pose,
                   incident_face_for(incident_hull, incident_pose, reference.normal), incident);
  clip_to_manifold(reference, incident, flipped, depth, out);
}

// the extent of a hull's vertices along a direction of its own frame
struct Extent {
  double min, max;
};
// a convex polyhedron has at most 2V − 4 faces
constexpr std::size_t kMaxHullFaces = 2 * kMaxHullVertices - 4;

// up to Capacity points (or directions) as structure of arrays, read four or eight to a vector;
// the count is rounded up to a multiple of eight with copies of the first (which change no least
// or largest projection)
template <std::size_t Capacity>
struct PointLanes {
  static constexpr std::size_t kLanes = (Capacity + 7) / 8 * 8;
  std::array<double, kLanes> x, y, z;
  std::size_t count = 0, padded = 0;
  template <typename Point>
  void fill(std::size_t n, Point point) {  // point(i) → Vec3
    count = n, padded = (n + 7) / 8 * 8;
    for (std::size_t i = 0; i < padded; ++i) {
      const Vec3 p = point(i < n ? i : 0);
      x[i] = p.x(), y[i] = p.y(), z[i] = p.z();
    }
  }
  Vec3 at(std::size_t i) const { return {x[i], y[i], z[i]}; }
  Double4 dot(std::size_t i, const Vec3& d) const {  // lanes i … i + 3
    return load4(&x[i]) * d.x() + load4(&y[i]) * d.y() + load4(&z[i]) * d.z();
  }
  Double8 dot8(std::size_t i, const Vec3& d) const {  // lanes i … i + 7
    return load8(&x[i]) * d.x() + load8(&y[i]) * d.y() + load8(&z[i]) * d.z();
  }
  // the bits of lanes i … i + width − 1 that are below the count (none for lanes wholly past it)
  unsigned lanes_in_count(std::size_t i, std::size_t width = 4) const {
    return i >= count ? 0u : count - i >= width ? (1u << width) - 1u : (1u << (count - i)) - 1u;
  }
  Extent extent_along(const Vec3& direction) const {
    Double4 least = kInfinity4, largest = -kInfinity4;
    for (std::size_t i = 0; i < padded; i += 4) {
      const Double4 d = dot(i, direction);
      least = simd::min(least, d), largest = simd::max(largest, d);
    }
    return {-largest_lane(-least), largest_lane(largest)};
  }
};

}  // namespace

// ---- lab 4.1 ----

TrianglePoint closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b,
                                        const Vec3& c) {
  // vertex region of a
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return {a, TriangleFeature::VertexA};
  // vertex region of b
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return {b, TriangleFeature::VertexB};
  // edge region of ab
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    const double v = d1 / (d1 - d3);
    return {a + v * ab, TriangleFeature::EdgeAB};
  }
  // vertex region of c
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return {c, TriangleFeature::VertexC};
  // edge region of ac
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    const double w = d2 / (d2 - d6);
    return {a + w * ac, TriangleFeature::EdgeCA};
  }
  // edge region of bc
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {b + w * (c - b), TriangleFeature::EdgeBC};
  }
  // face region: barycentric coordinates (u, v, w) = (va, vb, vc) / (va + vb + vc)
  const double sum = va + vb + vc;
  if (!(sum > 0.0)) {
    // a degenerate triangle has no face region: the closest point of its three edges
    TrianglePoint best{a, TriangleFeature::VertexA};
    double best_distance = std::numeric_limits<double>::infinity();
    const Vec3* corners[3] = {&a, &b, &c};
    const TriangleFeature edges[3] = {TriangleFeature::EdgeAB, TriangleFeature::EdgeBC,
                                      TriangleFeature::EdgeCA};
    for (int i = 0; i < 3; ++i) {
      const Vec3& s = *corners[i];
      const Vec3 e = *corners[(i + 1) % 3] - s;
      const double t =
          e.squaredNorm() > 0.0 ? std::clamp((p - s).dot(e) / e.squaredNorm(), 0.0, 1.0) : 0.0;
      const Vec3 q = s + t * e;
      if (double d = (p - q).squaredNorm(); d < best_distance)
        best_distance = d, best = {q, edges[i]};
    }
    return best;
  }
  const double v = vb / sum, w = vc / sum;
  return {a + v * ab + w * ac, TriangleFeature::Face};
}

// ---- shapes ----

Shape Shape::sphere(double radius) {
  Shape s;
  s.kind = ShapeKind::Sphere;
  s.radius = radius;
  return s;
}

Shape Shape::box(const ConvexHull& box_hull, const Vec3& half_extents) {
  Shape s;
  s.kind = ShapeKind::Box;
  s.half_extents = half_extents;
  s.hull = &box_hull;
  return s;
}

Shape Shape::convex(const ConvexHull& hull) {
  Shape s;
  s.kind = ShapeKind::Hull;
  s.hull = &hull;
  return s;
}

Shape Shape::plane(const Vec3& normal, double offset) {
  Shape s;
  s.kind = ShapeKind::Plane;
  s.plane_normal = normal.normalized();
  s.plane_offset = offset;
  return s;
}

// ---- round shapes and planes ----

bool collide_spheres(const Shape& a, const Pose& pose_a, const Shape& b, const Pose& pose_b,
                     Manifold& out) {
  const Vec3 d = pose_b.position - pose_a.position;
  const double distance = d.norm(), reach = a.radius + b.radius;
  if (distance > reach) return no_contact(out);
  // concentric spheres: any direction will do, up is as good as any
  const Vec3 normal = distance > 0.0 ? Vec3(d / distance) : Vec3::UnitY();
  const Vec3 surface_a = pose_a.position + a.radius * normal;
  const Vec3 surface_b = pose_b.position - b.radius * normal;
  return single_contact(normal, reach - distance, 0.5 * (surface_a + surface_b), out);
}

bool collide_sphere_box(const Shape& a, const Pose& pose_a, const Shape& b, const Pose& pose_b,
                        Manifold& out) {
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
  // the manifold's normal runs from the sphere (first) to the box
  const Vec3 normal = -(pose_b.rotation * normal_in_box);
  const Vec3 surface_b = pose_b.position + pose_b.rotation * surface_in_box;
  const Vec3 surface_a = pose_a.position + a.radius * normal;
  return single_contact(normal, a.radius - distance, 0.5 * (surface_a + surface_b), out);
}

bool collide_sphere_hull(const Shape& a, const Pose& pose_a, const Shape& b, const Pose& pose_b,
                         Manifold& out) {
  const ConvexHull& hull = *b.hull;
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
  const Vec3 normal = -(pose_b.rotation * normal_in_hull);
  const Vec3 surface_b = pose_b.position + pose_b.rotation * surface_in_hull;
  const Vec3 surface_a = pose_a.position + a.radius * normal;
  return single_contact(normal, a.radius - distance, 0.5 * (surface_a + surface_b), out);
}

bool collide_sphere_plane(const Shape& a, const Pose& pose_a, const Shape& b, const Pose& pose_b,
                          Manifold& out) {
  const Vec3 plane_normal = pose_b.rotation * b.plane_normal;
  const double plane_offset = b.plane_offset + plane_normal.dot(pose_b.position);
  const double height = plane_normal.dot(pose_a.position) - plane_offset;
  if (height > a.radius) return no_contact(out);
  const Vec3 surface_a = pose_a.position - a.radius * plane_normal;
  const Vec3 surface_b = pose_a.position - height * plane_normal;
  return single_contact(-plane_normal, a.radius - height, 0.5 * (surface_a + surface_b), out);
}

bool collide_hull_plane(const Shape& a, const Pose& pose_a, const Shape& b, const Pose& pose_b,
                        Manifold& out) {
  const ConvexHull& hull = *a.hull;
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

// ---- polyhedra ----

bool collide_boxes(const Shape& a, const Pose& pose_a, const Shape& b, const Pose& pose_b,
                   Manifold& out) {
  const Vec3& ha = a.half_extents;
  const Vec3& hb = b.half_extents;
  // B's axes and centre in A's frame, c(i, j) = a_i · b_j and t = Aᵀ(p_b − p_a), in 4-lane
  // vectors (lane 3 is padding): rows of c over j, columns of c over i, t over i
  const Mat3& ra = pose_a.rotation;
  const Mat3& rb = pose_b.rotation;
  Double4 rows_a[3], rows_b[3];
  rows_of(ra, rows_a), rows_of(rb, rows_b);
  const Double4 a_x = rows_a[0], a_y = rows_a[1], a_z = rows_a[2];  // lanes i
  const Double4 b_x = rows_b[0], b_y = rows_b[1], b_z = rows_b[2];  // lanes j
  Double4 row[3], column[3], abs_row[3], abs_column[3];
  for (int k = 0; k < 3; ++k) row[k] = ra(0, k) * b_x + ra(1, k) * b_y + ra(2, k) * b_z;
  transpose3(row, column);
  for (int k = 0; k < 3; ++k) abs_row[k] = simd::abs(row[k]), abs_column[k] = simd::abs(column[k]);
  const Vec3 d = pose_b.position - pose_a.position;
  const Double4 t4 = d.x() * a_x + d.y() * a_y + d.z() * a_z;
  const Double4 ha4 = {ha.x(), ha.y(), ha.z(), 0.0}, hb4 = {hb.x(), hb.y(), hb.z(), 0.0};

  // face axes, three at a time and without a branch per axis (random pairs defeat the branch
  // predictor): along a_i the separation is |t_i| − (ha_i + Σ_j hb_j |c_ij|), along b_j it is
  // |(cᵀt)_j| − (hb_j + Σ_i ha_i |c_ij|); a b_j parallel to some a_i was tested as that a_i
  constexpr Mask4 kThreeLanes = {-1, -1, -1, 0};
  const Double4 separation_a = simd::select(
      kThreeLanes,
      simd::abs(t4) - (ha4 + hb.x() * abs_column[0] + hb.y() * abs_column[1] +
                       hb.z() * abs_column[2]),
      -kInfinity4);
  const Double4 t_in_b4 = t4[0] * row[0] + t4[1] * row[1] + t4[2] * row[2];
  const Mask4 duplicate =
      (simd::max(simd::max(abs_row[0], abs_row[1]), abs_row[2]) > kDuplicateCosine) & kThreeLanes;
  const Double4 separation_b = simd::select(
      kThreeLanes & ~duplicate,
      simd::abs(t_in_b4) - (hb4 + ha.x() * abs_row[0] + ha.y() * abs_row[1] + ha.z() * abs_row[2]),
      -kInfinity4);
  std::uint16_t axes = std::uint16_t(6 - lane_count(duplicate));
  if (lane_bits((separation_a > 0.0) | (separation_b > 0.0)) != 0) {
    out.axes_tested = axes;
    return no_contact(out);
  }
  const double largest_a = largest_lane(separation_a), largest_b = largest_lane(separation_b);
  // the first axis holding each largest; A's face on a tie. A non-finite pose leaves no lane
  // equal to its largest: the bit of axis 2, set always, keeps the index in range then.
  const int best_a = std::countr_zero(lane_bits(separation_a == largest_a) | 0b100u);
  const int best_b = std::countr_zero(lane_bits(separation_b == largest_b) | 0b100u);
  const double best_face = std::max(largest_a, largest_b);
  const int best_face_axis = largest_b > largest_a ? 3 + best_b : best_a;  // 0–2: A's, 3–5: B's

  // edge axes L = a_i × b_j in closed form (Ericson §4.4.1; B's axes in A's frame are c's
  // columns): L = (…, −c(i2, j), c(i1, j)) on A's axes i1, i2, and in B's frame it has c(i, j2)
  // and −c(i, j1) on B's axes j1, j2, so the radii and |L|² = 1 − c(i, j)² need no products of
  // matrices. An axis of parallel edges (|L| ≈ 0) or one parallel to a face normal (one of the two
  // components ≈ 0) is skipped: the faces covered it. The separation (|t·L| − r)/|L| is compared
  // squared, so only the winner takes a square root.
  // The nine axes are evaluated together, one row i of A's axes per 4-lane vector with B's axes j
  // in its lanes (lane 3 is padding and never valid): on random pairs a branch per axis costs
  // more than the arithmetic. Along a row, c(i1, ·) and c(i2, ·) are whole rows of c and
  // c(i, j1), c(i, j2) the row rotated.
  const Double4 hb_next = {hb[1], hb[2], hb[0], 0.0}, hb_after = {hb[2], hb[0], hb[1], 0.0};
  constexpr double kSine2 = kParallelSine * kParallelSine;
  Double4 metric[3];  // gap² / |L|², +∞ where the axis is skipped
  Mask4 any_apart = {0, 0, 0, 0};
  for (int i = 0; i < 3; ++i) {
    const int i1 = (i + 1) % 3, i2 = (i + 2) % 3;
    const Double4 length_squared = row[i1] * row[i1] + row[i2] * row[i2];
    // (the division starts here, not after the gap)
    const Double4 inverse_length_squared = 1.0 / simd::select(length_squared >= kSine2, length_squared, 1.0);
    const Double4 least_a = simd::min(abs_row[i1], abs_row[i2]);
    // |c(i, j1)| and |c(i, j2)|
    const Double4 c_next = rotate4(abs_row[i]), c_after = rotate4(c_next);
    const Double4 least_b = simd::min(c_next, c_after);
    const Mask4 valid = (length_squared >= kSine2) &
                        (least_a * least_a >= kSine2 * length_squared) &
                        (least_b * least_b >= kSine2 * length_squared);
    const Double4 radius_a = ha[i1] * abs_row[i2] + ha[i2] * abs_row[i1];
    const Double4 radius_b = hb_next * c_after + hb_after * c_next;
    const Double4 gap = simd::abs(t4[i2] * row[i1] - t4[i1] * row[i2]) - (radius_a + radius_b);
    any_apart |= valid & (gap > 0.0);
    axes += std::uint16_t(lane_count(valid));
    metric[i] = simd::select(valid, gap * gap * inverse_length_squared, kInfinity4);
  }
  out.axes_tested = axes;
  if (lane_bits(any_apart) != 0) return no_contact(out);
  // the least metric and the first (i-major) axis holding it, without a branch per axis
  const Double4 least = simd::min(simd::min(metric[0], metric[1]), metric[2]);
  const double best_metric = std::min({least[0], least[1], least[2]});
  // (axis (2, 2)'s bit, set always, keeps the index in range for a non-finite pose)
  const unsigned holders = lane_bits(metric[0] == best_metric) |
                           lane_bits(metric[1] == best_metric) << 4 |
                           lane_bits(metric[2] == best_metric) << 8 | 1u << 10;
  const int best_edge_i = std::countr_zero(holders) / 4;
  const int best_edge_j = std::countr_zero(holders) % 4;
  const double best_edge = -std::sqrt(best_metric);

  // edge–edge: the edge of A parallel to a_i that is farthest along the normal and the edge of B
  // parallel to b_j farthest against it, in A's frame and in the lanes, without a branch: which
  // edges these are is as good as random on random pairs
  auto edge_manifold = [&] {
    const int i = best_edge_i, j = best_edge_j;
    constexpr Mask4 kLane[3] = {{-1, 0, 0, 0}, {0, -1, 0, 0}, {0, 0, -1, 0}};
    const Double4 a_i = simd::select(kLane[i], 1.0, 0.0), b_j = column[j];
    // a_i × b_j, turned to run from A towards B
    Double4 normal = rotate4(a_i) * rotate4(rotate4(b_j)) - rotate4(rotate4(a_i)) * rotate4(b_j);
    const Double4 normal_t = normal * t4;
    normal = flip_where(normal, Double4(normal_t[0] + normal_t[1] + normal_t[2]) < 0.0);
    // the edges' midpoints: A's at ±ha_k on its two other axes by the normal's signs there, B's at
    // ∓hb_k by the signs of the normal in B's frame
    const Mask4 up_a = normal >= 0.0;
    const Double4 mid_a = simd::select(kThreeLanes & ~kLane[i], simd::select(up_a, ha4, -ha4), 0.0);
    const Double4 normal_in_b = normal[0] * row[0] + normal[1] * row[1] + normal[2] * row[2];
    const Mask4 up_b = normal_in_b < 0.0;
    const Double4 mid_b_in_b =
        simd::select(kThreeLanes & ~kLane[j], simd::select(up_b, hb4, -hb4), 0.0);
    const Double4 mid_b =
        t4 + mid_b_in_b[0] * column[0] + mid_b_in_b[1] * column[1] + mid_b_in_b[2] * column[2];
    // the closest points of the edges mid_a + α a_i, |α| ≤ ha_i, and mid_b + β b_j, |β| ≤ hb_j:
    // Ericson §5.1.9 with unit directions, one division by 1 − (a_i · b_j)², which is at least
    // the square of the parallel threshold on a tested axis
    const Double4 r = mid_a - mid_b, r_along_b = b_j * r;
    const double cosine = b_j[i], r_a = r[i], r_b = r_along_b[0] + r_along_b[1] + r_along_b[2];
    // (the clamps by min and max and the last step selected: std::clamp and an if branch)
    const double alpha_free =
        std::min(std::max((cosine * r_b - r_a) / (1.0 - cosine * cosine), -ha[i]), ha[i]);
    const double beta_free = cosine * alpha_free + r_b;
    const double beta = std::min(std::max(beta_free, -hb[j]), hb[j]);
    const double alpha_held = std::min(std::max(cosine * beta - r_a, -ha[i]), ha[i]);
    const double alpha = beta != beta_free ? alpha_held : alpha_free;
    const Double4 midway = 0.5 * (mid_a + alpha * a_i + mid_b + beta * b_j);
    // an edge's id: its axis, then the sign bits of the two other axes in order
    auto edge_id = [](Mask4 up, int axis) {
      const unsigned bits = lane_bits(up) & 7u;
      const unsigned others = (bits & ((1u << axis) - 1u)) | (bits >> (axis + 1) & 3u) << axis;
      return std::uint16_t(4 * axis + others);
    };
    const Vec3 n(normal[0], normal[1], normal[2]), p(midway[0], midway[1], midway[2]);
    out.normal = pose_a.rotation * n / n.norm();
    out.depth = -best_edge;
    out.count = 1;
    out.points[0].point = pose_a.position + pose_a.rotation * p;
    out.points[0].depth = -best_edge;
    out.points[0].feature = {edge_id(up_a, i), edge_id(up_b, j), 0, 0, ContactType::EdgeEdge, 0};
    return true;
  };
  // edge_axis_wins(best_edge, best_face) without waiting for the square root: the face's threshold
  // is negative where an edge can beat it, and then the edge is above it when its square is below
  const double threshold = edge_threshold(best_face);
  if (threshold < 0.0 && best_metric < threshold * threshold)
    return edge_manifold();

  // face contact, clipped in the reference box's frame (as ODE's dBoxBox does): the incident
  // face's quad is cut to the reference face's rectangle in the face's two coordinates, the third
  // giving the depth. In that frame the side planes are |u| ≤ h_u and |v| ≤ h_v.
  // Which box holds the reference face is as good as random, and so are the signs and the
  // incident axis below: they are selected, not branched on.
  const bool flipped = best_face_axis >= 3;
  const Pose* const poses[2] = {&pose_a, &pose_b};
  const Pose& reference_pose = *poses[flipped];  // (by index: GCC branches on a ?: of references)
  const Mask4 flip = flipped;
  const Double4 reference_half4 = simd::select(flip, hb4, ha4);
  const Double4 incident_half4 = simd::select(flip, ha4, hb4);
  // the incident box's axes and centre in the reference frame: c's columns and t when A holds
  // the reference face, c's rows and −cᵀt when B does
  const Double4 incident_axes[3] = {simd::select(flip, row[0], column[0]),
                                    simd::select(flip, row[1], column[1]),
                                    simd::select(flip, row[2], column[2])};
  const Double4 incident_centre = simd::select(flip, -t_in_b4, t4);
  const int axis = best_face_axis - 3 * flipped, ku = (axis + 1) % 3, kv = (axis + 2) % 3;
  // +1 where the centre is at or above 0 (x + 0 turns −0 into +0), by the sign bit
  const double sign = std::copysign(1.0, incident_centre[axis] + 0.0);
  const Vec3 reference_half(reference_half4[0], reference_half4[1], reference_half4[2]);

  // the incident face: the other box's axis most (anti-)parallel to the reference normal (the
  // first on a tie)
  // (the incident axes' components along the reference axis: row `axis` of c, or its column when
  // B holds the reference face; lane 3 is 0 and loses to a unit vector's largest component)
  const Double4 alignment = simd::select(flip, column[axis], row[axis]);
  const Double4 abs_alignment = simd::abs(alignment);
  const int incident_axis = std::countr_zero(
      lane_bits(abs_alignment == largest_lane(abs_alignment)) | 0b100u);
  // −1 where the face's outward axis points along the reference normal (the product is never 0:
  // the largest component of a unit vector is at least 1/√3)
  const double incident_sign = std::copysign(1.0, -sign * alignment[incident_axis]);
  const int iu = (incident_axis + 1) % 3, iv = (incident_axis + 2) % 3;
  const Double4 face_centre4 =
      incident_centre +
      incident_sign * incident_half4[incident_axis] * incident_axes[incident_axis];
  const Double4 edge_u = incident_half4[iu] * incident_axes[iu];
  const Double4 edge_v = incident_half4[iv] * incident_axes[iv];
  const Vec3 face_centre(face_centre4[0], face_centre4[1], face_centre4[2]);
  const auto incident_face = std::uint16_t(2 * incident_axis + (incident_sign > 0.0 ? 0 : 1));
  const auto reference_face = std::uint16_t(2 * axis + (sign > 0.0 ? 0 : 1));

  // The clipped polygon's corners are, in no order: the incident quad's vertices inside the
  // rectangle, the points where the quad's edges cross the rectangle's sides within the other
  // side pair, and the rectangle's corners strictly inside the quad (the intersection of two
  // convex polygons has no others; Sutherland–Hodgman finds the same points one side at a time).
  // All 24 candidates are computed in 4-lane vectors and only the survivors are visited: the
  // branches of a clip loop, on random pairs, cost more than the arithmetic. Candidate k is lane
  // k % 4 of group k / 4: group 0 the quad's vertices, groups 1–4 the crossings of the edge that
  // starts at vertex k % 4 with the sides u = h_u, u = −h_u, v = h_v, v = −h_v, group 5 the
  // rectangle's corners (+u, +v), (−u, +v), (−u, −v), (+u, −v) (the quad's vertices' sign order).
  const double hu = reference_half[ku], hv = reference_half[kv];
  const Double4 corner_u = {1, -1, -1, 1}, corner_v = {1, 1, -1, -1};
  const Double4 u = face_centre[ku] + corner_u * edge_u[ku] + corner_v * edge_v[ku];
  const Double4 v = face_centre[kv] + corner_u * edge_u[kv] + corner_v * edge_v[kv];
  const Double4 w = face_centre[axis] + corner_u * edge_u[axis] + corner_v * edge_v[axis];
  const Double4 u_next = next4(u), v_next = next4(v), w_next = next4(w);
  Double4 cu[6], cv[6], cw[6];
  Mask4 inside[6];
  cu[0] = u, cv[0] = v, cw[0] = w;
  inside[0] = (simd::abs(u) <= hu) & (simd::abs(v) <= hv);
  // an edge crosses u = ±h_u at the fraction (u ∓ h_u) / (u − u_next) of its length, v = ±h_v
  // likewise: two divisions serve the four sides (an edge parallel to a side does not cross it)
  const Double4 du = u - u_next, dv = v - v_next;
  const Double4 one = {1, 1, 1, 1};
  const Double4 inverse_du = one / simd::select(du != 0.0, du, one);
  const Double4 inverse_dv = one / simd::select(dv != 0.0, dv, one);
  for (int side = 0; side < 4; ++side) {
    const bool along_u = side < 2;  // the side is a line of constant u
    const double side_sign = side % 2 == 0 ? 1.0 : -1.0, limit = side_sign * (along_u ? hu : hv);
    const Double4& across = along_u ? u : v;  // the coordinate the side limits
    const Mask4 crosses = (side_sign * across <= side_sign * limit) ^
                          (side_sign * next4(across) <= side_sign * limit);
    const Double4 f = (across - limit) * (along_u ? inverse_du : inverse_dv);
    Double4& x = cu[1 + side];
    Double4& y = cv[1 + side];
    x = along_u ? Double4(limit) : u - f * du;
    y = along_u ? v - f * dv : Double4(limit);
    cw[1 + side] = w + f * (w_next - w);
    inside[1 + side] = crosses & (along_u ? simd::abs(y) <= hv : simd::abs(x) <= hu);
  }
  // a rectangle corner is inside the quad when it is strictly on the inner side of every edge
  // (strictly, so that a quad vertex on the corner is not counted twice); the quad's winding in
  // (u, v) is the sign of edge_u × edge_v there
  {
    const double winding = edge_u[ku] * edge_v[kv] - edge_u[kv] * edge_v[ku] >= 0.0 ? 1.0 : -1.0;
    const Double4 qu = hu * corner_u, qv = hv * corner_v;
    Double4 innermost = kInfinity4;  // the least signed distance, scaled, to the quad's edges
    for (int k = 0; k < 4; ++k) {
      const double eu = u_next[k] - u[k], ev = v_next[k] - v[k];
      innermost = simd::min(innermost, winding * (eu * (qv - v[k]) - ev * (qu - u[k])));
    }
    // the corner's height on the incident face's plane (|n_w| ≥ 1/√3: it is the face most
    // aligned with the reference normal)
    const Double4& n = incident_axes[incident_axis];
    cu[5] = qu, cv[5] = qv;
    cw[5] = face_centre[axis] -
            (n[ku] * (qu - face_centre[ku]) + n[kv] * (qv - face_centre[kv])) / n[axis];
    inside[5] = innermost > 0.0;
  }
  // on or below the reference face
  std::uint32_t survivors = 0;
  Double4 depth[6];
  for (int g = 0; g < 6; ++g) {
    depth[g] = reference_half[axis] - sign * cw[g];
    survivors |= lane_bits(inside[g] & (depth[g] >= 0.0)) << (4 * g);
  }
  std::array<std::uint8_t, 24> kept;
  std::size_t below = 0;
  for (; survivors != 0; survivors &= survivors - 1)
    kept[below++] = std::uint8_t(std::countr_zero(survivors));
  auto u_of = [&](std::size_t k) { return cu[k / 4][k % 4]; };
  auto v_of = [&](std::size_t k) { return cv[k / 4][k % 4]; };
  auto depth_of = [&](std::size_t k) { return depth[k / 4][k % 4]; };

  std::array<std::size_t, 4> chosen{0, 1, 2, 3};
  if (below > 4) {
    using Vec2 = Eigen::Vector2d;
    chosen = choose_four(
        below, [&](std::size_t i) { return depth_of(kept[i]); },
        [&](std::size_t i) { return Vec2(u_of(kept[i]), v_of(kept[i])); },
        [](const Vec2& p, const Vec2& q, const Vec2& r) {
          return (q.x() - p.x()) * (r.y() - p.y()) - (q.y() - p.y()) * (r.x() - p.x());
        });
    below = 4;
  }
  // midway between the surfaces, back in the world
  const Vec3 normal = sign * reference_pose.rotation.col(axis);
  for (std::size_t k = 0; k < below; ++k) {
    const std::size_t candidate = kept[chosen[k]];
    const int group = int(candidate / 4);
    const auto lane = std::uint8_t(candidate % 4);
    Vec3 local;
    local[ku] = u_of(candidate);
    local[kv] = v_of(candidate);
    local[axis] = sign * (reference_half[axis] - 0.5 * depth_of(candidate));
    ContactPoint& p = out.points[k];
    p.point = reference_pose.position + reference_pose.rotation * local;
    p.depth = depth_of(candidate);
    // by tables, not ?: chains (GCC branches on those, and the group is as good as random)
    constexpr std::uint8_t kSide[6] = {0, 0, 1, 2, 3, 0};
    constexpr ContactType kType[6] = {ContactType::FaceVertex, ContactType::FaceClip,
                                      ContactType::FaceClip,   ContactType::FaceClip,
                                      ContactType::FaceClip,   ContactType::FaceCorner};
    const bool corner = group == 5;
    p.feature = {reference_face,
                 incident_face,
                 std::uint8_t(kSide[group] + corner * lane),
                 std::uint8_t(!corner * lane),
                 kType[group],
                 std::uint8_t(flipped)};
  }
  if (below > 0) {
    out.normal = flipped ? Vec3(-normal) : normal;
    out.depth = -best_face;
    out.count = std::uint8_t(below);
    return true;
  }
  // the preferred face axis was not the shallowest and its clip came out empty
  if (best_edge > -std::numeric_limits<double>::infinity()) return edge_manifold();
  // touching within rounding: one point at the centre of the incident face keeps the verdict and
  // the manifold consistent
  out.normal = flipped ? Vec3(-normal) : normal;
  out.depth = -best_face;
  out.count = 1;
  out.points[0] = {reference_pose.position + reference_pose.rotation * face_centre, 0.0,
                   ContactFeature{reference_face, incident_face, 0, 0, ContactType::FaceVertex,
                                  std::uint8_t(flipped)}};
  return true;
}

bool collide_hulls(const Shape& a, const Pose& pose_a, const Shape& b, const Pose& pose_b,
                   Manifold& out) {
  const ConvexHull& hull_a = *a.hull;
  const ConvexHull& hull_b = *b.hull;
  // B in A's frame: x_a = rotation · x_b + translation
  const Mat3 rotation = pose_a.rotation.transpose() * pose_b.rotation;
  const Vec3 translation = pose_a.rotation.transpose() * (pose_b.position - pose_a.position);
  std::uint16_t axes = 0;

  // face axes (Gregorius's face query: the other hull's deepest vertex below each face plane),
  // grouped by unique normal so that one projection of the other hull serves the face on either
  // side; a face of B whose opposite is a face of A tests the same gap and is skipped
  double best_face = -std::numeric_limits<double>::infinity();
  std::uint32_t best_face_index = 0;
  bool best_face_on_b = false;
  // the projections run over the vertices four at a time (A's copy is made only if A's faces
  // find no separating axis: most separated pairs end there)
  PointLanes<kMaxHullVertices> body_b;
  body_b.fill(hull_b.vertices.size(), [&](std::size_t i) { return hull_b.vertices[i]; });
  auto consider = [&](double separation, std::uint32_t face, bool on_b) {
    if (separation > best_face)
      best_face = separation, best_face_index = face, best_face_on_b = on_b;
    return separation <= 0.0;
  };
  for (std::size_t k = 0; k < hull_a.unique_face_normals.size(); ++k) {
    const Vec3& u = hull_a.unique_face_normals[k];
    const auto [plus, minus] = hull_a.unique_normal_faces[k];
    ++axes;
    const double shift = translation.dot(u);
    const Extent b_along = body_b.extent_along(rotation.transpose() * u);
    const bool apart =
        (plus != kNoFace &&
         !consider(b_along.min + shift - hull_a.faces[plus].offset, plus, false)) ||
        (minus != kNoFace &&
         !consider(-(b_along.max + shift) - hull_a.faces[minus].offset, minus, false));
    if (apart) {
      out.axes_tested = axes;
      return no_contact(out);
    }
  }
  PointLanes<kMaxHullVertices> body_a;
  body_a.fill(hull_a.vertices.size(), [&](std::size_t i) { return hull_a.vertices[i]; });
  PointLanes<kMaxHullFaces> normals_a;
  normals_a.fill(hull_a.unique_face_normals.size(),
                 [&](std::size_t i) { return hull_a.unique_face_normals[i]; });
  for (std::size_t k = 0; k < hull_b.unique_face_normals.size(); ++k) {
    const Vec3 u = rotation * hull_b.unique_face_normals[k];  // A's frame
    auto [plus, minus] = hull_b.unique_normal_faces[k];
    // A's faces with normals +u and −u, if any (the last unique normal of A within the duplicate
    // cosine, four normals at a time; the lanes past the count are not read)
    std::uint32_t a_plus = kNoFace, a_minus = kNoFace;
    std::size_t parallel = normals_a.count;  // none
    for (std::size_t m = 0; m < normals_a.count; m += 4) {
      const unsigned bits = lane_bits(simd::abs(normals_a.dot(m, u)) > kDuplicateCosine) &
                            normals_a.lanes_in_count(m);
      if (bits != 0) parallel = m + std::size_t(31 - std::countl_zero(bits));
    }
    if (parallel != normals_a.count) {
      const double cosine = hull_a.unique_face_normals[parallel].dot(u);
      a_plus = hull_a.unique_normal_faces[parallel][cosine > 0.0 ? 0 : 1];
      a_minus = hull_a.unique_normal_faces[parallel][cosine > 0.0 ? 1 : 0];
    }
    if (a_minus != kNoFace) plus = kNoFace;  // B's +u face tests the gap A's −u face tested
    if (a_plus != kNoFace) minus = kNoFace;
    if (plus == kNoFace && minus == kNoFace) continue;
    ++axes;
    // B's face planes in A's frame: u · x = offset + u · translation
    const double shift = translation.dot(u);
    const Extent a_along = body_a.extent_along(u);
    const bool apart =
        (plus != kNoFace &&
         !consider(a_along.min - (hull_b.faces[plus].offset + shift), plus, true)) ||
        (minus != kNoFace &&
         !consider(-a_along.max - (hull_b.faces[minus].offset - shift), minus, true));
    if (apart) {
      out.axes_tested = axes;
      return no_contact(out);
    }
  }

  // edge pairs that make a face of the Minkowski difference. B's vertices come into A's frame
  // once, and B's edges are laid out as arrays of the Gauss-map arc ends −c, −d (its faces'
  // normals, negated) so that the arc test runs over them in vectors: the test is most of the
  // work (EA × EB pairs), and it rejects most pairs.
  std::array<Vec3, kMaxHullVertices> vertices_b;
  for (std::size_t i = 0; i < hull_b.vertices.size(); ++i)
    vertices_b[i] = rotation * hull_b.vertices[i] + translation;
  const std::size_t edge_count_b = hull_b.edges.size();
  // per B edge: the arc ends −c, −d (its faces' normals negated, A's frame) and d × c
  auto arc_end = [&](std::size_t j, bool left) {
    const HullEdge& eb = hull_b.edges[j];
    return Vec3(-(rotation * hull_b.faces[left ? eb.left : eb.right].normal));
  };
  PointLanes<kMaxHullEdges> c_b, d_b, d_cross_c;
  c_b.fill(edge_count_b, [&](std::size_t j) { return arc_end(j, true); });
  d_b.fill(edge_count_b, [&](std::size_t j) { return arc_end(j, false); });
  d_cross_c.fill(edge_count_b, [&](std::size_t j) { return d_b.at(j).cross(c_b.at(j)); });
  // the B edges whose arcs cross the A edge's, one bit each
  std::array<std::uint64_t, (kMaxHullEdges + 63) / 64> crossing;

  double best_gap_squared = std::numeric_limits<double>::infinity(), best_length_squared = 1.0;
  Vec3 best_edge_axis = Vec3::Zero();  // unnormalised
  std::uint32_t best_edge_a = 0, best_edge_b = 0;
  for (std::uint32_t i = 0; i < hull_a.edges.size(); ++i) {
    const HullEdge& ea = hull_a.edges[i];
    const Vec3& a = hull_a.faces[ea.left].normal;
    const Vec3& b = hull_a.faces[ea.right].normal;
    const Vec3 b_x_a = b.cross(a);
    // arcs a→b and c→d cross when c, d lie either side of a, b's plane, a, b either side of c,
    // d's plane, and on the same hemisphere (Gregorius, GDC 2013); for B's edges eight at a time,
    // with no branch: few pairs cross, and the loop that follows visits those by their bits
    crossing.fill(0);
    for (std::size_t j = 0; j < c_b.padded; j += 8) {
      const Double8 cba = c_b.dot8(j, b_x_a), dba = d_b.dot8(j, b_x_a);
      const Double8 adc = d_cross_c.dot8(j, a), bdc = d_cross_c.dot8(j, b);
      const unsigned bits =
          lane_bits((cba * dba < 0.0) & (adc * bdc < 0.0) & (cba * bdc > 0.0)) &
          c_b.lanes_in_count(j, 8);
      crossing[j / 64] |= std::uint64_t(bits) << (j % 64);
    }
    const Vec3& tail_a = hull_a.vertices[ea.tail];
    const Vec3 direction_a = hull_a.vertices[ea.head] - tail_a;
    const Vec3 outward_a = tail_a - hull_a.centre;
    for (std::size_t word = 0; word * 64 < edge_count_b; ++word) {
      for (std::uint64_t bits = crossing[word]; bits != 0; bits &= bits - 1) {
        const auto j = std::uint32_t(word * 64 + std::size_t(std::countr_zero(bits)));
        const HullEdge& eb = hull_b.edges[j];
        const Vec3 direction_b = vertices_b[eb.head] - vertices_b[eb.tail];
        Vec3 axis = direction_a.cross(direction_b);
        const double length_squared = axis.squaredNorm();
        if (length_squared <
            kParallelSine * kParallelSine * direction_a.squaredNorm() * direction_b.squaredNorm())
          continue;
        ++axes;
        // outward from A; the separation is gap / |axis|, compared squared (no root, no division)
        if (axis.dot(outward_a) < 0.0) axis = -axis;
        const double gap = axis.dot(vertices_b[eb.tail] - tail_a);
        if (gap > 0.0) {
          out.axes_tested = axes;
          return no_contact(out);
        }
        if (gap * gap * best_length_squared < best_gap_squared * length_squared)
          best_gap_squared = gap * gap, best_length_squared = length_squared, best_edge_axis = axis,
          best_edge_a = i, best_edge_b = j;
      }
    }
  }
  const double best_edge = -std::sqrt(best_gap_squared / best_length_squared);
  const Vec3 best_edge_normal = best_edge_axis.normalized();
  out.axes_tested = axes;

  // faces first unless an edge axis is clearly shallower; when the preferred face axis was not
  // the shallowest, its clip can come out empty, and the edge contact stands in
  if (!edge_axis_wins(best_edge, best_face)) {
    if (best_face_on_b)
      hull_face_manifold(hull_b, pose_b, best_face_index, hull_a, pose_a, true, -best_face, out);
    else
      hull_face_manifold(hull_a, pose_a, best_face_index, hull_b, pose_b, false, -best_face, out);
    if (out.count > 0) return true;
  }
  if (best_edge > -std::numeric_limits<double>::infinity()) {
    const HullEdge& ea = hull_a.edges[best_edge_a];
    const HullEdge& eb = hull_b.edges[best_edge_b];
    const Vec3 tail_a = pose_a.position + pose_a.rotation * hull_a.vertices[ea.tail];
    const Vec3 head_a = pose_a.position + pose_a.rotation * hull_a.vertices[ea.head];
    const Vec3 tail_b = pose_b.position + pose_b.rotation * hull_b.vertices[eb.tail];
    const Vec3 head_b = pose_b.position + pose_b.rotation * hull_b.vertices[eb.head];
    edge_contact(tail_a, head_a - tail_a, tail_b, head_b - tail_b,
                 pose_a.rotation * best_edge_normal, -best_edge, std::uint16_t(best_edge_a),
                 std::uint16_t(best_edge_b), out);
    return true;
  }
  if (out.count == 0) {
    // touching within rounding: one point midway between the two supports along the normal
    const Vec3 normal = out.normal;
    Vec3 support_a = hull_a.vertices[0], support_b = hull_b.vertices[0];
    const Vec3 na = pose_a.rotation.transpose() * normal, nb = pose_b.rotation.transpose() * normal;
    for (const Vec3& v : hull_a.vertices)
      if (v.dot(na) > support_a.dot(na)) support_a = v;
    for (const Vec3& v : hull_b.vertices)
      if (v.dot(nb) < support_b.dot(nb)) support_b = v;
    out.count = 1;
    out.points[0] = {0.5 * (pose_a.position + pose_a.rotation * support_a + pose_b.position +
                            pose_b.rotation * support_b),
                     out.depth, ContactFeature{}};
  }
  return true;
}

// ---- dispatch ----

namespace {

// the table holds each pair once in the order written; the mirrored entries swap the shapes
// and turn the normal round
template <CollideFunction function>
bool mirrored(const Shape& a, const Pose& pose_a, const Shape& b, const Pose& pose_b,
              Manifold& out) {
  const bool touching = function(b, pose_b, a, pose_a, out);
  out.normal = -out.normal;
  for (std::uint8_t i = 0; i < out.count; ++i) out.points[i].feature.flipped ^= 1;
  return touching;
}

bool never(const Shape&, const Pose&, const Shape&, const Pose&, Manifold& out) {
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

bool collide(const Shape& a, const Pose& pose_a, const Shape& b, const Pose& pose_b,
             Manifold& out) {
  out.axes_tested = 0;
  return kCollide[std::size_t(a.kind)][std::size_t(b.kind)](a, pose_a, b, pose_b, out);
}

}  // namespace rtp
