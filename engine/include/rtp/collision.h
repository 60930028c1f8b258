// rtp narrow phase (the seed's labs 4.1 and 4.2): which shapes touch, and where.
//
// Shapes carry a collision mesh kept apart from anything drawn: a convex hull with its vertices,
// its faces as vertex loops with outward normals, each edge once with the two faces it joins, and
// the hull's unique edge directions and unique face normals (three of each for a box). Hulls of
// arbitrary point sets come from qhull.
//
// Two polyhedra are tested by the separating axis theorem. The candidate axes are the unique face
// normals of both and the cross products of edge pairs; an edge pair is tried only when its two
// edges make a face of the Minkowski difference — their arcs on the Gauss map cross (Gregorius,
// "The Separating Axis Test between Convex Polyhedra", GDC 2013) — which prunes the parallel and
// duplicate axes the seed prunes by hand and most others besides; the projections and the arc
// test run over structure-of-arrays copies of the hulls, several lanes at a time. Boxes take a
// path of their own:
// the same axes in closed form (Gottschalk's OBB test, Ericson §4.4.1), 15 for two rotated boxes,
// fewer when edges are parallel, evaluated in 4-lane vectors rather than one branch per axis
// (random pairs defeat the branch predictor). A separating axis ends the test; otherwise the axis
// of least penetration is the contact normal, with faces preferred over edges unless an edge axis
// is clearly shallower (by 2 % of the depth plus 0.1 mm), which keeps manifolds from flickering
// between the two.
//
// The manifold comes from clipping (the seed's choice): the reference face is the face most
// aligned with the normal, the incident face the other shape's face most opposed to it; the
// incident face is clipped against the reference face's side planes (Sutherland–Hodgman), points
// above the reference face are dropped and at most four are kept — the deepest, then those that
// span the largest area. Two boxes clip by candidates instead: every point the clip can yield
// (incident vertices, edge crossings, reference corners) is computed at once and the survivors
// kept, the same points without a branch per vertex. An edge–edge contact is one point, from the
// closest points of the two edges. Each point carries the features that made it, so a solver can
// match it next step.
//
// Every collision function is stateless and writes a Manifold; collide() picks one from a table
// indexed by the two shape kinds (as MuJoCo's mjCOLLISIONFUNC does).
#pragma once

#include <algorithm>
#include <array>
#include <cassert>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "rtp/math.h"

namespace rtp {

// body frame to world: x_world = position + rotation · x_body
struct Pose {
  Vec3 position = Vec3::Zero();
  Mat3 rotation = Mat3::Identity();
  Pose() = default;
  Pose(const Vec3& position_, const Quat& orientation)
      : position(position_), rotation(orientation.toRotationMatrix()) {}
};

// ---- lab 4.1: the closest point on a triangle, by Voronoi regions ----

enum class TriangleFeature : std::uint8_t {
  VertexA,
  VertexB,
  VertexC,
  EdgeAB,
  EdgeBC,
  EdgeCA,
  Face
};

struct TrianglePoint {
  Vec3 point;
  TriangleFeature feature;  // the vertex, edge or face whose Voronoi region holds the query
};

// the point of triangle abc closest to p (Ericson, "Real-Time Collision Detection", §5.1.5); a
// degenerate triangle answers with the closest point of its edges
TrianglePoint closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

// ---- the collision mesh ----

struct HullFace {
  Vec3 normal;              // outward unit normal, body frame
  double offset = 0.0;      // the face's plane: normal · x = offset (m)
  std::uint32_t first = 0;  // its vertex loop in face_vertices, counter-clockwise about normal
  std::uint32_t count = 0;
};

// an edge, once; it runs tail → head counter-clockwise around face `left`
struct HullEdge {
  std::uint32_t tail = 0, head = 0;
  std::uint32_t left = 0, right = 0;  // the faces either side
};

// points (or directions) as structure of arrays, padded to a multiple of eight with copies of the
// first (which change no least or largest projection): the layout the separating axis test reads
// four or eight lanes at a time
struct PointColumns {
  std::vector<double> x, y, z;  // count rounded up to eight entries each
  std::size_t count = 0;        // the points
};

struct ConvexHull {
  std::vector<Vec3> vertices;  // body frame (m)
  std::vector<HullFace> faces;
  std::vector<std::uint32_t> face_vertices;
  std::vector<HullEdge> edges;
  std::vector<Vec3> unique_edge_directions;  // unit, one per direction up to sign
  std::vector<Vec3> unique_face_normals;     // unit, one per normal up to sign
  // for each unique normal u, the face whose normal is +u and the face whose normal is −u
  // (kNoFace where the hull has none): one projection of the other shape serves both
  std::vector<std::array<std::uint32_t, 2>> unique_normal_faces;
  Vec3 centre = Vec3::Zero();  // the mean of the vertices: an interior point
  // the vertices and the unique face normals again as columns, made once with the hull
  // (make_box_hull, make_convex_hull) so that no pair of hulls has to copy them
  PointColumns vertex_columns, normal_columns;
};

inline constexpr std::uint32_t kNoFace = ~std::uint32_t{0};

// limits that let the clipper run in fixed buffers (no heap allocation per pair)
inline constexpr std::size_t kMaxHullVertices = 256;
inline constexpr std::size_t kMaxFaceVertices = 64;
// a convex polyhedron has at most 3V − 6 edges
inline constexpr std::size_t kMaxHullEdges = 3 * kMaxHullVertices - 6;

// the hull of a box of half extents h: vertex i has the signs of bits 0, 1, 2 of i on x, y, z;
// faces +x, −x, +y, −y, +z, −z
ConvexHull make_box_hull(const Vec3& half_extents);

// the convex hull of a point set (qhull, coplanar facets merged into polygons); throws
// std::invalid_argument naming the problem for non-finite points, fewer than four points, a flat
// or degenerate set, or a hull beyond the limits above
ConvexHull make_convex_hull(std::span<const Vec3> points);

// ---- shapes ----

enum class ShapeKind : std::uint8_t { Sphere, Box, Hull, Plane };
inline constexpr std::size_t kShapeKinds = 4;

// A box or hull shape names its hull by index: Shape::hull is a position in a pool of hulls that
// the shape's owner keeps (World's contact stage, NarrowphaseSet, a test's local vector) and
// hands to collide() with the shape. Nothing points into the pool, so it may be a plain
// std::vector that grows and moves; the owner keeps each index valid for the pool it passes.
// Spheres and planes have no hull (kNoHull). An index outside the pool is a bug in the owner:
// debug builds assert on it (hull_of), release builds do not check.
inline constexpr std::uint32_t kNoHull = ~std::uint32_t{0};

// one collision shape in its body frame
struct Shape {
  ShapeKind kind = ShapeKind::Sphere;
  double radius = 0.0;                // sphere (m)
  Vec3 half_extents = Vec3::Zero();   // box (m)
  std::uint32_t hull = kNoHull;       // box (a make_box_hull) and hull: index into the pool
  Vec3 plane_normal = Vec3::UnitY();  // plane: the solid side is below normal · x = offset
  double plane_offset = 0.0;          // (m)

  static Shape sphere(double radius);
  static Shape box(std::uint32_t box_hull, const Vec3& half_extents);
  static Shape convex(std::uint32_t hull);
  static Shape plane(const Vec3& normal, double offset);
};

// the hull a box or hull shape names in the owner's pool (asserted in range in debug builds)
inline const ConvexHull& hull_of(const Shape& shape, std::span<const ConvexHull> hulls) {
  assert(shape.hull < hulls.size() && "Shape::hull outside the pool passed with it");
  return hulls[shape.hull];
}

// ---- contacts ----

enum class ContactType : std::uint8_t {
  FaceVertex,  // an incident-face vertex below the reference face
  FaceClip,    // where an incident-face edge crosses a side plane of the reference face
  FaceCorner,  // a corner of a box's reference face inside the incident face (reference_side:
               // 0–3 for the corner at (+u, +v), (−u, +v), (−u, −v), (+u, −v) on the face's two
               // axes; the general hull clip finds such a point as a FaceClip)
  EdgeEdge,    // the closest points of two edges
  Single,      // the one point of a sphere or plane contact
};

// the features that made a contact point: equal ids on consecutive steps mean the same point
// (8 bytes)
struct ContactFeature {
  std::uint16_t reference = 0;       // reference face, or the edge of the first shape
  std::uint16_t incident = 0;        // incident face, or the edge of the second shape
  std::uint8_t reference_side = 0;   // FaceClip: the reference face's side plane (loop index)
  std::uint8_t incident_vertex = 0;  // loop index on the incident face: the vertex, or the
                                     // edge that starts there
  ContactType type = ContactType::Single;
  std::uint8_t flipped = 0;  // 1 when the second shape held the reference face
  friend bool operator==(const ContactFeature&, const ContactFeature&) = default;
};
static_assert(sizeof(ContactFeature) == 8);

struct ContactPoint {
  Vec3 point;          // world, midway between the two surfaces (m)
  double depth = 0.0;  // penetration along the normal (m), ≥ 0
  ContactFeature feature;
};

struct Manifold {
  Vec3 normal = Vec3::Zero();  // unit, world, from the first shape towards the second
  double depth = 0.0;          // penetration along normal by the separating axis test (m)
  std::array<ContactPoint, 4> points;
  std::uint8_t count = 0;         // 0: the shapes do not touch
  std::uint16_t axes_tested = 0;  // separating axes evaluated (polyhedra; 0 otherwise)
};

// one collision function per pair of kinds; true when the shapes touch (touching counts). hulls is
// the pool the shapes' hull indices refer to (empty will do for spheres and planes)
using CollideFunction = bool (*)(std::span<const ConvexHull> hulls, const Shape& a,
                                 const Pose& pose_a, const Shape& b, const Pose& pose_b,
                                 Manifold& out);

// dispatch on the two kinds; a plane against a plane never collides (planes are static)
bool collide(std::span<const ConvexHull> hulls, const Shape& a, const Pose& pose_a, const Shape& b,
             const Pose& pose_b, Manifold& out);

bool collide_spheres(std::span<const ConvexHull> hulls, const Shape& a, const Pose& pose_a,
                     const Shape& b, const Pose& pose_b, Manifold& out);
bool collide_sphere_box(std::span<const ConvexHull> hulls, const Shape& a, const Pose& pose_a,
                        const Shape& b, const Pose& pose_b, Manifold& out);
bool collide_sphere_hull(std::span<const ConvexHull> hulls, const Shape& a, const Pose& pose_a,
                         const Shape& b, const Pose& pose_b, Manifold& out);
bool collide_sphere_plane(std::span<const ConvexHull> hulls, const Shape& a, const Pose& pose_a,
                          const Shape& b, const Pose& pose_b, Manifold& out);
bool collide_boxes(std::span<const ConvexHull> hulls, const Shape& a, const Pose& pose_a,
                   const Shape& b, const Pose& pose_b, Manifold& out);
bool collide_hulls(std::span<const ConvexHull> hulls, const Shape& a, const Pose& pose_a,
                   const Shape& b, const Pose& pose_b, Manifold& out);
bool collide_hull_plane(std::span<const ConvexHull> hulls, const Shape& a, const Pose& pose_a,
                        const Shape& b, const Pose& pose_b, Manifold& out);

// the signed distance from a world point to a hull's surface where it is inside or on it
// (≤ 0), and a lower bound of the distance where it is outside: the largest face-plane distance
inline double face_plane_distance(const ConvexHull& hull, const Pose& pose, const Vec3& point) {
  const Vec3 local = pose.rotation.transpose() * (point - pose.position);
  double largest = -std::numeric_limits<double>::infinity();
  for (const HullFace& face : hull.faces)
    largest = std::max(largest, face.normal.dot(local) - face.offset);
  return largest;
}

}  // namespace rtp
