// Two convex hulls: the separating axis test over the face normals of both and the edge pairs that
// make a face of the Minkowski difference (their arcs cross on the Gauss map: Gregorius, GDC 2013),
// over columns of lanes, several at a time (each hull's own, made with it, and B's arc ends for the
// pair); the manifold by clipping (narrowphase_clip.h).
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>

#include "narrowphase_clip.h"
#include "narrowphase_internal.h"

namespace rtp {
using namespace detail;
namespace {

// the extent of a hull's vertices along a direction of its own frame
struct Extent {
  double min, max;
};

// points (or directions) as structure of arrays, read four or eight to a vector; the count is
// rounded up to a multiple of eight with copies of the first (which change no least or largest
// projection). Columns gives x(), y(), z(), count and padded: a hull's own columns (HullColumns)
// or arrays of the pair's own (PairColumns).
template <typename Columns>
struct Lanes : Columns {
  using Columns::Columns;
  Vec3 at(std::size_t i) const { return {this->x()[i], this->y()[i], this->z()[i]}; }
  Double4 dot(std::size_t i, const Vec3& d) const {  // lanes i … i + 3
    return load4(this->x() + i) * d.x() + load4(this->y() + i) * d.y() +
           load4(this->z() + i) * d.z();
  }
  Double8 dot8(std::size_t i, const Vec3& d) const {  // lanes i … i + 7
    return load8(this->x() + i) * d.x() + load8(this->y() + i) * d.y() +
           load8(this->z() + i) * d.z();
  }
  // the bits of lanes i … i + width − 1 that are below the count (none for lanes wholly past it)
  unsigned lanes_in_count(std::size_t i, std::size_t width = 4) const {
    const std::size_t count = this->count;
    return i >= count ? 0u : count - i >= width ? (1u << width) - 1u : (1u << (count - i)) - 1u;
  }
  Extent extent_along(const Vec3& direction) const {
    Double4 least = kInfinity4, largest = -kInfinity4;
    for (std::size_t i = 0; i < this->padded; i += 4) {
      const Double4 d = dot(i, direction);
      least = simd::min(least, d), largest = simd::max(largest, d);
    }
    return {-largest_lane(-least), largest_lane(largest)};
  }
};

// a hull's columns, made with the hull (ConvexHull::vertex_columns, normal_columns)
struct HullColumns {
  const double *xs, *ys, *zs;
  std::size_t count, padded;
  explicit HullColumns(const PointColumns& c)
      : xs(c.x.data()), ys(c.y.data()), zs(c.z.data()), count(c.count), padded(c.x.size()) {}
  const double* x() const { return xs; }
  const double* y() const { return ys; }
  const double* z() const { return zs; }
};

// up to Capacity points that depend on the pair (B's edges' arc ends in A's frame), in arrays on
// the stack (their addresses known to the compiler, which the arc test's loop profits from)
template <std::size_t Capacity>
struct PairColumns {
  static constexpr std::size_t kLanes = (Capacity + 7) / 8 * 8;
  std::array<double, kLanes> xs, ys, zs;
  std::size_t count = 0, padded = 0;
  const double* x() const { return xs.data(); }
  const double* y() const { return ys.data(); }
  const double* z() const { return zs.data(); }
  template <typename Point>
  void fill(std::size_t n, Point point) {  // point(i) → Vec3
    count = n, padded = (n + 7) / 8 * 8;
    for (std::size_t i = 0; i < padded; ++i) {
      const Vec3 p = point(i < n ? i : 0);
      xs[i] = p.x(), ys[i] = p.y(), zs[i] = p.z();
    }
  }
};

using LaneView = Lanes<HullColumns>;
template <std::size_t Capacity>
using PointLanes = Lanes<PairColumns<Capacity>>;

}  // namespace

bool collide_hulls(std::span<const ConvexHull> hulls, const Shape& a, const Pose& pose_a,
                   const Shape& b, const Pose& pose_b, Manifold& out) {
  const ConvexHull& hull_a = hull_of(a, hulls);
  const ConvexHull& hull_b = hull_of(b, hulls);
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
  // the projections run over the hulls' own columns, four vertices at a time
  const LaneView body_b(hull_b.vertex_columns);
  auto consider = [&](double separation, std::uint32_t face, bool on_b) {
    if (separation > best_face + (on_b && !best_face_on_b ? kFaceTolerance : 0.0))
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
  const LaneView body_a(hull_a.vertex_columns), normals_a(hull_a.normal_columns);
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
      const unsigned bits = lane_bits((cba * dba < 0.0) & (adc * bdc < 0.0) & (cba * bdc > 0.0)) &
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
  if (best_edge > -std::numeric_limits<double>::infinity() &&
      (edge_axis_wins(best_edge, best_face) || edge_may_stand_in(best_edge, best_face))) {
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

}  // namespace rtp
