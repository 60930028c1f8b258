// Lab 4.1: the closest point on a triangle, by Voronoi regions (Ericson §5.1.5).
#include <algorithm>
#include <limits>

#include "rtp/collision.h"

namespace rtp {

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

}  // namespace rtp
