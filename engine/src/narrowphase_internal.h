// What the narrow phase's files share. The narrow phase is one file per shape family, as MuJoCo's
// engine_collision_{box,primitive,convex,driver}.c: narrowphase.cpp (the dispatch table),
// narrowphase_clip.h (clipping a hull face to a manifold), narrowphase_triangle.cpp (lab 4.1),
// narrowphase_round.cpp (spheres and planes), narrowphase_box.cpp (two boxes, in closed form) and
// narrowphase_hull.cpp (two hulls, by the Gauss map). The design and its sources are in
// rtp/collision.h.
//
// Everything here has internal linkage (an unnamed namespace), so each file gets its own copy, as
// it had when the narrow phase was one file. That is for the native build: with FMA contraction
// on (GCC's default), which products fuse into a multiply-add depends on what is inlined where,
// and shared out-of-line copies changed the last bits of contact points. Internal copies keep
// every result the same bit for bit (bench/dump_outputs).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

#include "rtp/collision.h"
#include "simd.h"

namespace rtp::detail {
namespace {

// an edge axis replaces the best face axis only when it is shallower by this fraction of the
// depth plus this length: faces give the steadier manifold (Gregorius, GDC 2013, uses 5 %)
inline constexpr double kEdgeRelativeTolerance = 0.02;
inline constexpr double kEdgeAbsoluteTolerance = 1e-4;  // m
// a face of the second shape replaces the first shape's best face only when it is shallower by
// this much: two stacked boxes have two near-equal face axes, and a reference face that flips
// between them from step to step changes every feature id and loses the contact's warm start
// (Box2D keeps the first polygon's face within a tenth of its linear slop the same way)
inline constexpr double kFaceTolerance = 1e-5;  // m (tilts of a resting stack differ by less)
// contact points this much less deep than the deepest count as deep as it when four are kept (m)
inline constexpr double kDepthTie = 1e-3;
// two edges whose unit directions' cross product is shorter than this are parallel: their axis
// is numerically meaningless and the face axes cover them (Ericson §4.4.1)
inline constexpr double kParallelSine = 1e-5;
// the second shape's face is a duplicate of the first's when their normals are this close
inline constexpr double kDuplicateCosine = 1.0 - 1e-9;

inline constexpr double kInfinity = std::numeric_limits<double>::infinity();

// the lanes the box and hull paths compute in (simd.h)
using simd::Double4;
using simd::Double8;
using simd::flip_where;
using simd::lane_bits;
using simd::lane_count;
using simd::largest_lane;
using simd::load4;
using simd::load8;
using simd::Mask4;
inline constexpr Double4 kInfinity4 = simd::splat<Double4>(kInfinity);

// the separation an edge axis must exceed to replace the best face axis
inline double edge_threshold(double face_separation) {
  return face_separation * (1.0 - kEdgeRelativeTolerance) + kEdgeAbsoluteTolerance;
}
inline bool edge_axis_wins(double edge_separation, double face_separation) {
  return edge_separation > edge_threshold(face_separation);
}
// whether an edge axis may stand in for a face whose clip came out empty: not much deeper than
// the face (an axis of two nearly parallel edges, valid by the parallel test, can come out
// metres deep on boxes a micrometre apart; its contact would be a fiction)
inline bool edge_may_stand_in(double edge_separation, double face_separation) {
  return edge_separation >=
         face_separation * (1.0 + kEdgeRelativeTolerance) - kEdgeAbsoluteTolerance;
}

// which four of n > 4 points to keep: the deepest (a corner among near-ties), the farthest from
// it, the one making the largest triangle with those two, and the one adding the most area
// outside that triangle.
// position(i) is a point in any vector type; area(p, q, r) the signed area of pqr about the normal.
template <typename Depth, typename Position, typename Area>
std::array<std::size_t, 4> choose_four(std::size_t count, Depth depth, Position position,
                                       Area area) {
  std::array<std::size_t, 4> chosen{};
  // the deepest point; among points within a tie of it, the one farthest from their mean. Faces
  // resting flat have depths equal but for rounding and tilt, and a first point picked by those
  // wanders the overlap from step to step (the three after it follow it): the farthest is a
  // corner, and stays one
  double deepest = depth(0);
  for (std::size_t i = 1; i < count; ++i) deepest = std::max(deepest, depth(i));
  auto mean = position(0);
  for (std::size_t i = 1; i < count; ++i) mean += position(i);
  mean /= double(count);
  double farthest = -1.0;
  for (std::size_t i = 0; i < count; ++i)
    if (depth(i) >= deepest - kDepthTie)
      if (double d = (position(i) - mean).squaredNorm(); d > farthest) farthest = d, chosen[0] = i;
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
    // the area q adds: the largest triangle it makes outside one of the three edges (outside
    // is the side opposite the triangle's own orientation, whichever way round it runs)
    const double added = std::max({-orientation * area(p0, p1, q), -orientation * area(p1, p2, q),
                                   -orientation * area(p2, p0, q)});
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

// a manifold of one point, for the round shapes and the planes
inline bool single_contact(const Vec3& normal, double depth, const Vec3& point, Manifold& out) {
  out.normal = normal;
  out.depth = depth;
  out.count = 1;
  out.points[0] = {point, depth, ContactFeature{}};
  out.axes_tested = 0;
  return true;
}

inline bool no_contact(Manifold& out) {
  out.count = 0;
  return false;
}

}  // namespace
}  // namespace rtp::detail
