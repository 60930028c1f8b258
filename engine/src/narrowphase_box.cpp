// Two boxes: the separating axes in closed form (Gottschalk's OBB test, Ericson §4.4.1) and the
// face clip by candidates in the reference box's frame, in 4-lane vectors rather than a branch per
// axis or per vertex: on random pairs the branch predictor loses, and a branch costs more than the
// arithmetic it skips.
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>

#include "narrowphase_internal.h"

namespace rtp {
// Compiled once more in each copy of the contact pipeline (engine/CMakeLists.txt), whose narrow
// phase calls its own (contacts.h, box_pairs): a box pair's test then runs at the copy's
// instruction set, its 4-lane doubles one register, not the baseline's two SSE2 halves
// (docs/solver.md, "One binary, the widest passes the core has")
#ifdef RTP_CONTACT_ISA_ENTRY
inline namespace RTP_CONTACT_ISA_NAMESPACE {
namespace box_pairs {
#endif
using namespace detail;
namespace {

// lanes 0, 1, 2 ← 1, 2, 0; lane 3 stays
inline Double4 rotate4(Double4 x) { return simd::shuffle<1, 2, 0, 3>(x); }
// lanes 0, 1, 2, 3 ← 1, 2, 3, 0
inline Double4 next4(Double4 x) { return simd::shuffle<1, 2, 3, 0>(x); }
// the three rows of a column-major 3×3 matrix (lane 3 zero), from two loads of the whole matrix
// and shuffles rather than nine element loads (docs/narrowphase.md, code generation)
inline void rows_of(const Mat3& m, Double4 rows[3]) {
  static_assert(sizeof(Mat3) == 9 * sizeof(double));
  const Double4 low = load4(m.data());       // m00 m10 m20 m01
  const Double4 high = load4(m.data() + 4);  // m11 m21 m02 m12
  constexpr Mask4 kThree = {-1, -1, -1, 0};
  rows[0] = simd::select(kThree, simd::shuffle<0, 3, 6, 0>(low, high), Double4{});
  rows[1] = simd::select(kThree, simd::shuffle<1, 4, 7, 0>(low, high), Double4{});
  rows[2] = simd::shuffle<2, 5, 0, 0>(low, high);
  rows[2][2] = m(2, 2), rows[2][3] = 0.0;
}
// the columns of a 3×3 matrix held as rows in lanes 0–2 (lane 3 zero), by shuffles
inline void transpose3(const Double4 rows[3], Double4 columns[3]) {
  const Double4 low = simd::shuffle<0, 4, 1, 5>(rows[0], rows[1]);   // r00 r10 r01 r11
  const Double4 high = simd::shuffle<2, 6, 3, 7>(rows[0], rows[1]);  // r02 r12 0 0
  columns[0] = simd::shuffle<0, 1, 4, 7>(low, rows[2]);
  columns[1] = simd::shuffle<2, 3, 5, 7>(low, rows[2]);
  columns[2] = simd::shuffle<0, 1, 6, 3>(high, rows[2]);
}

}  // namespace

bool collide_boxes(std::span<const ConvexHull>, const Shape& a, const Pose& pose_a,
                   const Shape& b, const Pose& pose_b, Manifold& out) {
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
  // |(cᵀt)_j| − (hb_j + Σ_i ha_i |c_ij|)
  constexpr Mask4 kThreeLanes = {-1, -1, -1, 0};
  const Double4 separation_a = simd::select(
      kThreeLanes,
      simd::abs(t4) -
          (ha4 + hb.x() * abs_column[0] + hb.y() * abs_column[1] + hb.z() * abs_column[2]),
      -kInfinity4);
  const Double4 t_in_b4 = t4[0] * row[0] + t4[1] * row[1] + t4[2] * row[2];
  // (a b_j parallel to an a_i within the duplicate cosine is counted as one axis but still
  // tested: with the boxes half a metre apart sideways, 2·10⁻⁵ rad between the axes moves the gap
  // by 10 µm, and two boxes that far apart along b_j read as touching along a_i)
  const Mask4 duplicate =
      (simd::max(simd::max(abs_row[0], abs_row[1]), abs_row[2]) > kDuplicateCosine) & kThreeLanes;
  const Double4 separation_b = simd::select(
      kThreeLanes,
      simd::abs(t_in_b4) - (hb4 + ha.x() * abs_row[0] + ha.y() * abs_row[1] + ha.z() * abs_row[2]),
      -kInfinity4);
  std::uint16_t axes = std::uint16_t(6 - lane_count(duplicate));
  if (lane_bits((separation_a > 0.0) | (separation_b > 0.0)) != 0) {
    out.axes_tested = axes;
    return no_contact(out);
  }
  const double largest_a = largest_lane(separation_a), largest_b = largest_lane(separation_b);
  // the first axis holding each largest; A's face unless B's is shallower by kFaceTolerance. A
  // non-finite pose leaves no lane equal to its largest: the bit of axis 2, set always, keeps the
  // index in range then.
  const int best_a = std::countr_zero(lane_bits(separation_a == largest_a) | 0b100u);
  const int best_b = std::countr_zero(lane_bits(separation_b == largest_b) | 0b100u);
  const bool b_face = largest_b > largest_a + kFaceTolerance;
  const int best_face_axis = b_face ? 3 + best_b : best_a;  // 0–2: A's, 3–5: B's
  const double best_face = b_face ? largest_b : largest_a;

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
    const Double4 inverse_length_squared =
        1.0 / simd::select(length_squared >= kSine2, length_squared, Double4{1, 1, 1, 1});
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
    const Double4 a_i = simd::select(kLane[i], Double4{1, 1, 1, 1}, Double4{}), b_j = column[j];
    // a_i × b_j, turned to run from A towards B
    Double4 normal = rotate4(a_i) * rotate4(rotate4(b_j)) - rotate4(rotate4(a_i)) * rotate4(b_j);
    const Double4 normal_t = normal * t4;
    normal = flip_where(normal, Double4{} + (normal_t[0] + normal_t[1] + normal_t[2]) < 0.0);
    // the edges' midpoints: A's at ±ha_k on its two other axes by the normal's signs there, B's at
    // ∓hb_k by the signs of the normal in B's frame
    const Mask4 up_a = normal >= 0.0;
    const Double4 mid_a =
        simd::select(kThreeLanes & ~kLane[i], simd::select(up_a, ha4, -ha4), Double4{});
    const Double4 normal_in_b = normal[0] * row[0] + normal[1] * row[1] + normal[2] * row[2];
    const Mask4 up_b = normal_in_b < 0.0;
    const Double4 mid_b_in_b =
        simd::select(kThreeLanes & ~kLane[j], simd::select(up_b, hb4, -hb4), Double4{});
    const Double4 mid_b =
        t4 + mid_b_in_b[0] * column[0] + mid_b_in_b[1] * column[1] + mid_b_in_b[2] * column[2];
    // the closest points of the edges mid_a + α a_i, |α| ≤ ha_i, and mid_b + β b_j, |β| ≤ hb_j:
    // Ericson §5.1.9 with unit directions, one division by 1 − (a_i · b_j)², which is at least
    // the square of the parallel threshold on a tested axis
    const Double4 r = mid_a - mid_b, r_along_b = b_j * r;
    const double cosine = b_j[i], r_a = r[i], r_b = r_along_b[0] + r_along_b[1] + r_along_b[2];
    // (clamped by min and max and the last step selected, not branched on: which clamp binds is
    // as good as random)
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
  if (threshold < 0.0 && best_metric < threshold * threshold) return edge_manifold();

  // face contact, clipped in the reference box's frame (as ODE's dBoxBox does): the incident
  // face's quad is cut to the reference face's rectangle in the face's two coordinates, the third
  // giving the depth. In that frame the side planes are |u| ≤ h_u and |v| ≤ h_v.
  // Which box holds the reference face is as good as random, and so are the signs and the
  // incident axis below: they are selected, not branched on.
  const bool flipped = best_face_axis >= 3;
  const Pose* const poses[2] = {&pose_a, &pose_b};
  const Pose& reference_pose = *poses[flipped];  // (by index: a ?: of references is a branch)
  const Mask4 flip = simd::splat<Mask4>(-std::int64_t(flipped));
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
  const int incident_axis =
      std::countr_zero(lane_bits(abs_alignment == largest_lane(abs_alignment)) | 0b100u);
  // −1 where the face's outward axis points along the reference normal (the product is never 0:
  // the largest component of a unit vector is at least 1/√3)
  const double incident_sign = std::copysign(1.0, -sign * alignment[incident_axis]);
  const int iu = (incident_axis + 1) % 3, iv = (incident_axis + 2) % 3;
  const Double4 face_centre4 = incident_centre + incident_sign * incident_half4[incident_axis] *
                                                     incident_axes[incident_axis];
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
    x = along_u ? Double4{limit, limit, limit, limit} : u - f * du;
    y = along_u ? v - f * dv : Double4{limit, limit, limit, limit};
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
    // by tables, not ?: chains, which compile to branches, and the group is as good as random
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
  if (edge_may_stand_in(best_edge, best_face)) return edge_manifold();
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

#ifdef RTP_CONTACT_ISA_ENTRY
}  // namespace box_pairs
}  // namespace RTP_CONTACT_ISA_NAMESPACE
#endif
}  // namespace rtp
