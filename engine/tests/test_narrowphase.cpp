// The narrow phase against references that do not share its code: brute-force minimisation for
// the triangle query, the closed-form box test against the general hull test, and geometry
// (every contact point on both surfaces) for the manifolds.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <span>
#include <stdexcept>
#include <vector>

#include "rtp/collision.h"

namespace rtp {
namespace {

Quat random_orientation(std::mt19937_64& rng) {
  std::normal_distribution<double> normal;
  Quat q(normal(rng), normal(rng), normal(rng), normal(rng));
  q.normalize();
  return q;
}

Vec3 random_vector(std::mt19937_64& rng, double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  return {u(rng), u(rng), u(rng)};
}

// ---- lab 4.1 ----

// the closest point by minimising over the closed triangle without Voronoi regions: the
// projection onto the plane if it falls inside, else the best of the three clamped edges
struct BruteForce {
  Vec3 point;
  double distance;
};
BruteForce brute_force_closest(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 n = (b - a).cross(c - a);
  const Vec3 projected = p - n * (p - a).dot(n) / n.squaredNorm();
  // inside when the three edge cross products agree in sign with the normal
  const bool inside = (b - a).cross(projected - a).dot(n) >= 0 &&
                      (c - b).cross(projected - b).dot(n) >= 0 &&
                      (a - c).cross(projected - c).dot(n) >= 0;
  if (inside) return {projected, (p - projected).norm()};
  BruteForce best{a, std::numeric_limits<double>::infinity()};
  const Vec3 corners[3] = {a, b, c};
  for (int i = 0; i < 3; ++i) {
    // a fine scan along the edge, then a local refinement: no clamped-projection formula
    const Vec3 s = corners[i], e = corners[(i + 1) % 3] - s;
    double best_t = 0, best_d = std::numeric_limits<double>::infinity();
    for (int k = 0; k <= 1000; ++k)
      if (double d = (p - (s + k / 1000.0 * e)).norm(); d < best_d) best_d = d, best_t = k / 1000.0;
    for (double step = 1e-3; step > 1e-13; step *= 0.5)
      for (double t : {best_t - step, best_t + step})
        if (t >= 0 && t <= 1)
          if (double d = (p - (s + t * e)).norm(); d < best_d) best_d = d, best_t = t;
    if (best_d < best.distance) best = {s + best_t * e, best_d};
  }
  return best;
}

TEST(ClosestPointOnTriangle, MatchesBruteForceMinimisationAndNamesTheFeature) {
  std::mt19937_64 rng(11);
  int checked_features = 0;
  for (int sample = 0; sample < 3000; ++sample) {
    const Vec3 a = random_vector(rng, 1), b = random_vector(rng, 1), c = random_vector(rng, 1);
    if ((b - a).cross(c - a).norm() < 0.05) continue;
    const Vec3 p = random_vector(rng, 2);
    const TrianglePoint answer = closest_point_on_triangle(p, a, b, c);
    const BruteForce reference = brute_force_closest(p, a, b, c);
    ASSERT_NEAR((p - answer.point).norm(), reference.distance, 1e-9) << "sample " << sample;
    ASSERT_LT((answer.point - reference.point).norm(), 1e-6) << "sample " << sample;

    // the feature: the closest point is that vertex, lies on that edge, or is strictly inside
    auto on_segment = [](const Vec3& q, const Vec3& s, const Vec3& e) {
      const double t = (q - s).dot(e - s) / (e - s).squaredNorm();
      return (s + std::clamp(t, 0.0, 1.0) * (e - s) - q).norm() < 1e-9;
    };
    const Vec3& q = reference.point;
    switch (answer.feature) {
      case TriangleFeature::VertexA:
        EXPECT_LT((q - a).norm(), 1e-6);
        break;
      case TriangleFeature::VertexB:
        EXPECT_LT((q - b).norm(), 1e-6);
        break;
      case TriangleFeature::VertexC:
        EXPECT_LT((q - c).norm(), 1e-6);
        break;
      case TriangleFeature::EdgeAB:
        EXPECT_TRUE(on_segment(answer.point, a, b));
        break;
      case TriangleFeature::EdgeBC:
        EXPECT_TRUE(on_segment(answer.point, b, c));
        break;
      case TriangleFeature::EdgeCA:
        EXPECT_TRUE(on_segment(answer.point, c, a));
        break;
      case TriangleFeature::Face:
        EXPECT_FALSE(on_segment(answer.point, a, b) || on_segment(answer.point, b, c) ||
                     on_segment(answer.point, c, a));
        break;
    }
    // an interior edge point is not a vertex
    if (answer.feature >= TriangleFeature::EdgeAB && answer.feature <= TriangleFeature::EdgeCA) {
      EXPECT_GT(std::min({(q - a).norm(), (q - b).norm(), (q - c).norm()}), 1e-12);
    }
    ++checked_features;
  }
  EXPECT_GT(checked_features, 2500);
}

TEST(ClosestPointOnTriangle, EveryRegionIsReached) {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  EXPECT_EQ(closest_point_on_triangle({-1, -1, 1}, a, b, c).feature, TriangleFeature::VertexA);
  EXPECT_EQ(closest_point_on_triangle({2, -0.5, 0}, a, b, c).feature, TriangleFeature::VertexB);
  EXPECT_EQ(closest_point_on_triangle({-0.5, 2, 0}, a, b, c).feature, TriangleFeature::VertexC);
  EXPECT_EQ(closest_point_on_triangle({0.5, -1, 0}, a, b, c).feature, TriangleFeature::EdgeAB);
  EXPECT_EQ(closest_point_on_triangle({1, 1, 3}, a, b, c).feature, TriangleFeature::EdgeBC);
  EXPECT_EQ(closest_point_on_triangle({-1, 0.5, 0}, a, b, c).feature, TriangleFeature::EdgeCA);
  const TrianglePoint face = closest_point_on_triangle({0.25, 0.25, -2}, a, b, c);
  EXPECT_EQ(face.feature, TriangleFeature::Face);
  EXPECT_LT((face.point - Vec3(0.25, 0.25, 0)).norm(), 1e-15);
}

TEST(ClosestPointOnTriangle, DegenerateTriangleStaysFinite) {
  const TrianglePoint q = closest_point_on_triangle({0.5, 1, 0}, {0, 0, 0}, {1, 0, 0}, {2, 0, 0});
  EXPECT_TRUE(q.point.allFinite());
  EXPECT_LT((q.point - Vec3(0.5, 0, 0)).norm(), 1e-12);
}

// ---- collision meshes ----

void expect_closed_convex(const ConvexHull& hull) {
  // Euler: V − E + F = 2; every face vertex on its plane, every vertex inside every plane
  EXPECT_EQ(int(hull.vertices.size()) - int(hull.edges.size()) + int(hull.faces.size()), 2);
  for (const HullFace& face : hull.faces) {
    EXPECT_NEAR(face.normal.norm(), 1.0, 1e-12);
    for (std::uint32_t i = 0; i < face.count; ++i)
      EXPECT_NEAR(face.normal.dot(hull.vertices[hull.face_vertices[face.first + i]]), face.offset,
                  1e-9);
    for (const Vec3& v : hull.vertices) EXPECT_LE(face.normal.dot(v), face.offset + 1e-9);
    // counter-clockwise about the outward normal
    const Vec3& p0 = hull.vertices[hull.face_vertices[face.first]];
    const Vec3& p1 = hull.vertices[hull.face_vertices[face.first + 1]];
    const Vec3& p2 = hull.vertices[hull.face_vertices[face.first + 2]];
    EXPECT_GT((p1 - p0).cross(p2 - p1).dot(face.normal), 0.0);
  }
  for (const HullEdge& edge : hull.edges) EXPECT_NE(edge.left, edge.right);
}

// a box's topology: 8 vertices, 6 faces, 12 edges, 3 unique edge directions and face normals
void expect_box_topology(const ConvexHull& hull) {
  EXPECT_EQ(hull.vertices.size(), 8u);
  EXPECT_EQ(hull.faces.size(), 6u);
  EXPECT_EQ(hull.edges.size(), 12u);
  EXPECT_EQ(hull.unique_edge_directions.size(), 3u);
  EXPECT_EQ(hull.unique_face_normals.size(), 3u);
  expect_closed_convex(hull);
}

TEST(CollisionMesh, BoxHasThreeUniqueEdgeDirectionsAndNormals) {
  expect_box_topology(make_box_hull({0.5, 1.0, 2.0}));
}

TEST(CollisionMesh, QhullMergesCoplanarFacetsAndDropsInteriorPoints) {
  // a box's corners, points inside it and points in the middle of its faces
  std::vector<Vec3> points;
  for (int i = 0; i < 8; ++i) points.emplace_back(i & 1 ? 1 : -1, i & 2 ? 2 : -2, i & 4 ? 3 : -3);
  std::mt19937_64 rng(3);
  for (int i = 0; i < 50; ++i) points.push_back(random_vector(rng, 0.9));
  points.emplace_back(0.2, 0.3, 3.0);
  points.emplace_back(1.0, -0.5, 0.1);
  expect_box_topology(make_convex_hull(points));
}

TEST(CollisionMesh, RandomPointCloudsGiveClosedConvexHulls) {
  std::mt19937_64 rng(5);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<Vec3> points;
    for (int i = 0; i < 40; ++i) points.push_back(random_vector(rng, 1.0));
    const ConvexHull hull = make_convex_hull(points);
    expect_closed_convex(hull);
    // every input point is inside the hull
    for (const Vec3& p : points) EXPECT_LE(face_plane_distance(hull, Pose(), p), 1e-9);
  }
}

TEST(CollisionMesh, BadPointSetsAreRejectedWithTheReason) {
  auto message_of = [](std::vector<Vec3> points) {
    try {
      make_convex_hull(points);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(message_of({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}).find("at least 4"), std::string::npos);
  EXPECT_NE(message_of({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0.5, 0.2, 0}}).find("flat"),
            std::string::npos);
  EXPECT_NE(message_of({{0, 0, 0}, {1, 0, 0}, {0, NAN, 0}, {0, 0, 1}}).find("point 2"),
            std::string::npos);
  EXPECT_THROW(make_box_hull({1, 0, 1}), std::invalid_argument);
}

// ---- separating axes and manifolds ----

// every contact point lies on both surfaces: A's surface point is half the depth along the
// normal (inside B), B's half the depth against it; on a surface means on or inside every face
// plane and on one of them
void expect_points_on_both(const Manifold& m, const ConvexHull& a, const Pose& pa,
                           const ConvexHull& b, const Pose& pb, double tolerance) {
  for (std::uint8_t i = 0; i < m.count; ++i) {
    const ContactPoint& p = m.points[i];
    EXPECT_GE(p.depth, 0.0);
    EXPECT_NEAR(face_plane_distance(a, pa, p.point + 0.5 * p.depth * m.normal), 0.0, tolerance)
        << "point " << int(i) << " type " << int(p.feature.type);
    EXPECT_NEAR(face_plane_distance(b, pb, p.point - 0.5 * p.depth * m.normal), 0.0, tolerance)
        << "point " << int(i) << " type " << int(p.feature.type) << " depth " << p.depth;
  }
}

TEST(SeparatingAxes, TwoRotatedBoxesTestFifteenAxesAlignedBoxesThree) {
  const Vec3 h(0.5, 0.5, 0.5);
  const ConvexHull hull = make_box_hull(h);
  const std::span<const ConvexHull> hulls(&hull, 1);
  const Shape box = Shape::box(0, h);
  Manifold m;
  // overlapping, so no axis exits early
  const Pose a({0, 0, 0}, Quat::Identity());
  const Pose rotated({0.3, 0.2, 0.1}, Quat(Eigen::AngleAxisd(0.4, Vec3(1, 2, 3).normalized())));
  ASSERT_TRUE(collide(hulls, box, a, box, rotated, m));
  EXPECT_EQ(m.axes_tested, 15);
  const Pose aligned({0.3, 0.2, 0.1}, Quat::Identity());
  ASSERT_TRUE(collide(hulls, box, a, box, aligned, m));
  EXPECT_EQ(m.axes_tested, 3);
  // the general hull test prunes the same duplicates
  const Shape convex = Shape::convex(0);
  ASSERT_TRUE(collide(hulls, convex, a, convex, aligned, m));
  EXPECT_EQ(m.axes_tested, 3);
}

TEST(SeparatingAxes, BoxRestingOnBoxGivesFourPointsAtTheRightDepth) {
  const std::vector<ConvexHull> hulls = {make_box_hull({2, 0.5, 2}),
                                         make_box_hull({0.5, 0.5, 0.5})};
  const ConvexHull &big_hull = hulls[0], &small_hull = hulls[1];
  const Shape ground = Shape::box(0, {2, 0.5, 2});
  const Shape box = Shape::box(1, {0.5, 0.5, 0.5});
  const Pose below({0, 0, 0}, Quat::Identity());
  const Pose above({0.1, 0.99, -0.2}, Quat(Eigen::AngleAxisd(0.3, Vec3::UnitY())));
  for (const bool general : {false, true}) {
    Manifold m;
    const Shape a = general ? Shape::convex(0) : ground;
    const Shape b = general ? Shape::convex(1) : box;
    ASSERT_TRUE(collide(hulls, a, below, b, above, m));
    EXPECT_EQ(m.count, 4);
    EXPECT_NEAR(m.depth, 0.01, 1e-12);
    EXPECT_LT((m.normal - Vec3::UnitY()).norm(), 1e-12);
    for (int i = 0; i < m.count; ++i) {
      EXPECT_NEAR(m.points[i].depth, 0.01, 1e-12);
      EXPECT_NEAR(m.points[i].point.y(), 0.495, 1e-12);
    }
    expect_points_on_both(m, big_hull, below, small_hull, above, 1e-9);
  }
}

// B placed along a random direction at a random fraction of the distance where it would first
// touch A (bisection on the closed-form test): separated, touching and deep pairs in one draw
struct PosePair {
  Pose a, b;
};
PosePair random_pose_pair(std::mt19937_64& rng, std::span<const ConvexHull> hulls, const Shape& a,
                          const Shape& b, double fraction) {
  PosePair pair{Pose({0, 0, 0}, random_orientation(rng)), Pose({0, 0, 0}, random_orientation(rng))};
  const Vec3 direction = random_vector(rng, 1).normalized();
  double inside = 0.0, outside = 10.0;
  Manifold m;
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (inside + outside);
    pair.b.position = mid * direction;
    (collide(hulls, a, pair.a, b, pair.b, m) ? inside : outside) = mid;
  }
  pair.b.position = fraction * outside * direction;
  return pair;
}

TEST(SeparatingAxes, ClosedFormBoxTestAgreesWithTheGaussMapHullTest) {
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> fraction(0.3, 1.3), size(0.2, 1.0);
  int contacts = 0, edge_contacts = 0, compared_face_points = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    const Vec3 ha(size(rng), size(rng), size(rng)), hb(size(rng), size(rng), size(rng));
    const std::vector<ConvexHull> hulls = {make_box_hull(ha), make_box_hull(hb)};
    const ConvexHull &hull_a = hulls[0], &hull_b = hulls[1];
    const Shape box_a = Shape::box(0, ha), box_b = Shape::box(1, hb);
    const PosePair pose = random_pose_pair(rng, hulls, box_a, box_b, fraction(rng));
    Manifold closed_form, general;
    const bool touching = collide(hulls, box_a, pose.a, box_b, pose.b, closed_form);
    ASSERT_EQ(touching,
              collide_hulls(hulls, Shape::convex(0), pose.a, Shape::convex(1), pose.b, general))
        << "trial " << trial;
    if (!touching) continue;
    ++contacts;
    edge_contacts += closed_form.points[0].feature.type == ContactType::EdgeEdge;
    ASSERT_NEAR(closed_form.depth, general.depth, 1e-9) << "trial " << trial;
    ASSERT_LT((closed_form.normal - general.normal).norm(), 1e-6) << "trial " << trial;
    ASSERT_EQ(closed_form.count, general.count) << "trial " << trial;
    // below four no reduction chose among them: the clipped polygon's own points, in some order
    // (four may be a choice, which the two paths make in different coordinates)
    if (closed_form.count < 4) {
      for (int i = 0; i < closed_form.count; ++i) {
        double nearest = 1e300;
        for (int j = 0; j < general.count; ++j) {
          const Vec3 gap = closed_form.points[i].point - general.points[j].point;
          nearest = std::min(nearest, gap.norm());
        }
        EXPECT_LT(nearest, 1e-9) << "trial " << trial << " point " << i;
      }
      compared_face_points += closed_form.points[0].feature.type != ContactType::EdgeEdge;
    }
    expect_points_on_both(closed_form, hull_a, pose.a, hull_b, pose.b, 1e-9);
    expect_points_on_both(general, hull_a, pose.a, hull_b, pose.b, 1e-9);
  }
  EXPECT_GT(contacts, 1500);
  EXPECT_GT(edge_contacts, 100);
  EXPECT_GT(compared_face_points, 400);
}

// the penetration depth along a direction n, first → second: how far B must move along n
double overlap_along(const ConvexHull& a, const Pose& pa, const ConvexHull& b, const Pose& pb,
                     const Vec3& n) {
  double max_a = -1e300, min_b = 1e300;
  for (const Vec3& v : a.vertices) max_a = std::max(max_a, n.dot(pa.position + pa.rotation * v));
  for (const Vec3& v : b.vertices) min_b = std::min(min_b, n.dot(pb.position + pb.rotation * v));
  return max_a - min_b;
}

TEST(SeparatingAxes, DepthIsTheLeastOverlapOverSampledDirections) {
  // the SAT depth is the minimum over all directions: no sampled direction may beat it, and the
  // overlap along the reported normal is the reported depth
  std::mt19937_64 rng(23);
  std::vector<Vec3> cloud;
  for (int i = 0; i < 32; ++i) cloud.push_back(random_vector(rng, 0.6));
  std::vector<ConvexHull> hulls;
  hulls.push_back(make_convex_hull(cloud));
  cloud.clear();
  for (int i = 0; i < 32; ++i) cloud.push_back(random_vector(rng, 0.4));
  hulls.push_back(make_convex_hull(cloud));
  const ConvexHull &hull_a = hulls[0], &hull_b = hulls[1];
  const Shape a = Shape::convex(0), b = Shape::convex(1);
  std::uniform_real_distribution<double> fraction(0.2, 0.99);
  for (int trial = 0; trial < 200; ++trial) {
    const PosePair pose = random_pose_pair(rng, hulls, a, b, fraction(rng));
    Manifold m;
    ASSERT_TRUE(collide(hulls, a, pose.a, b, pose.b, m));
    const double along_normal = overlap_along(hull_a, pose.a, hull_b, pose.b, m.normal);
    EXPECT_NEAR(along_normal, m.depth, 1e-9);
    for (int k = 0; k < 500; ++k) {
      const Vec3 n = random_vector(rng, 1).normalized();
      // an edge axis may be chosen over a face axis at most this much deeper (kEdge…Tolerance)
      EXPECT_GE(overlap_along(hull_a, pose.a, hull_b, pose.b, n), m.depth * 0.98 - 1e-4 - 1e-9);
    }
    expect_points_on_both(m, hull_a, pose.a, hull_b, pose.b, 1e-9);
  }
}

// a non-finite pose has no meaningful answer, but the box test must still pick its axes, faces
// and edges in range (the debug build's bounds checks and sanitizers catch a stray index)
TEST(SeparatingAxes, NonFinitePosesKeepTheBoxTestInBounds) {
  const ConvexHull hull = make_box_hull({0.5, 0.5, 0.5});
  const std::span<const ConvexHull> hulls(&hull, 1);
  const Shape box = Shape::box(0, {0.5, 0.5, 0.5});
  const Pose a({0, 0, 0}, Quat(Eigen::AngleAxisd(0.3, Vec3(1, 2, 3).normalized())));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const Vec3& position : {Vec3(nan, 0, 0), Vec3(0.2, nan, 0.1), Vec3(nan, nan, nan)}) {
    const Pose b(position, Quat(Eigen::AngleAxisd(0.7, Vec3(3, 1, 2).normalized())));
    Manifold m;
    collide(hulls, box, a, box, b, m);
    EXPECT_LE(m.count, 4);
    EXPECT_LE(m.axes_tested, 15);
    for (int i = 0; i < m.count; ++i) EXPECT_LT(m.points[i].feature.reference, 12);
  }
}

TEST(SeparatingAxes, FeatureIdsPersistWhileTheFeaturesDo) {
  const ConvexHull hull = make_box_hull({0.5, 0.5, 0.5});
  const std::span<const ConvexHull> hulls(&hull, 1);
  const Shape box = Shape::box(0, {0.5, 0.5, 0.5});
  const Pose a({0, 0, 0}, Quat::Identity());
  Manifold before, after;
  Pose b({0.2, 0.98, 0.1}, Quat(Eigen::AngleAxisd(0.25, Vec3::UnitY())));
  ASSERT_TRUE(collide(hulls, box, a, box, b, before));
  b.position += Vec3(0.001, -0.0005, 0.002);
  ASSERT_TRUE(collide(hulls, box, a, box, b, after));
  ASSERT_EQ(before.count, after.count);
  for (int i = 0; i < before.count; ++i) {
    int matches = 0;
    for (int j = 0; j < after.count; ++j)
      matches += before.points[i].feature == after.points[j].feature;
    EXPECT_EQ(matches, 1) << "point " << i;
  }
}

// ---- round shapes and planes ----

TEST(RoundShapes, SpheresAgainstEveryShapeMatchClosedForms) {
  const ConvexHull hull = make_box_hull({1, 1, 1});
  const std::span<const ConvexHull> hulls(&hull, 1);
  const Shape sphere = Shape::sphere(0.5);
  Manifold m;
  // sphere–sphere: centres 0.8 apart along x
  ASSERT_TRUE(collide(hulls, sphere, Pose({0, 0, 0}, Quat::Identity()), sphere,
                      Pose({0.8, 0, 0}, Quat::Identity()), m));
  EXPECT_NEAR(m.depth, 0.2, 1e-12);
  EXPECT_LT((m.normal - Vec3::UnitX()).norm(), 1e-12);
  EXPECT_LT((m.points[0].point - Vec3(0.4, 0, 0)).norm(), 1e-12);
  // sphere above a box's corner: the normal runs from the corner to the centre
  for (const Shape& solid : {Shape::box(0, {1, 1, 1}), Shape::convex(0)}) {
    const Vec3 centre = Vec3(1, 1, 1) + 0.4 * Vec3(1, 1, 1).normalized();
    ASSERT_TRUE(collide(hulls, Shape::sphere(0.5), Pose(centre, Quat::Identity()), solid,
                        Pose({0, 0, 0}, Quat::Identity()), m));
    EXPECT_NEAR(m.depth, 0.1, 1e-12);
    EXPECT_LT((m.normal + Vec3(1, 1, 1).normalized()).norm(), 1e-12);
    // and the box first: the normal turns round
    ASSERT_TRUE(collide(hulls, solid, Pose({0, 0, 0}, Quat::Identity()), Shape::sphere(0.5),
                        Pose(centre, Quat::Identity()), m));
    EXPECT_LT((m.normal - Vec3(1, 1, 1).normalized()).norm(), 1e-12);
    // a centre inside the box leaves through the nearest face
    ASSERT_TRUE(collide(hulls, Shape::sphere(0.5), Pose({0.2, 0.9, 0.1}, Quat::Identity()), solid,
                        Pose({0, 0, 0}, Quat::Identity()), m));
    EXPECT_NEAR(m.depth, 0.6, 1e-12);
    EXPECT_LT((m.normal + Vec3::UnitY()).norm(), 1e-12);
    EXPECT_FALSE(collide(hulls, Shape::sphere(0.5), Pose({1.3, 1.3, 1.3}, Quat::Identity()), solid,
                         Pose({0, 0, 0}, Quat::Identity()), m));
    EXPECT_EQ(m.count, 0);
  }
}

TEST(Planes, BoxOnATiltedPlaneTouchesWithItsLowestVertices) {
  const ConvexHull hull = make_box_hull({0.5, 0.5, 0.5});
  const std::span<const ConvexHull> hulls(&hull, 1);
  const Quat tilt(Eigen::AngleAxisd(0.2, Vec3::UnitZ()));
  const Shape plane = Shape::plane(Vec3::UnitY(), 0.0);
  // the box sits on the plane tilted with it, sunk 1 cm
  const Pose plane_pose({0, 0, 0}, tilt);
  const Pose box_pose(tilt * Vec3(0, 0.49, 0), tilt);
  Manifold m;
  ASSERT_TRUE(collide(hulls, Shape::box(0, {0.5, 0.5, 0.5}), box_pose, plane, plane_pose, m));
  EXPECT_EQ(m.count, 4);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(m.points[i].depth, 0.01, 1e-12);
  EXPECT_LT((m.normal + tilt * Vec3::UnitY()).norm(), 1e-12);
  // a sphere resting on it, and a plane never meets a plane
  ASSERT_TRUE(collide(hulls, plane, plane_pose, Shape::sphere(0.3),
                      Pose(tilt * Vec3(0, 0.25, 0), tilt), m));
  EXPECT_NEAR(m.depth, 0.05, 1e-12);
  EXPECT_LT((m.normal - tilt * Vec3::UnitY()).norm(), 1e-12);
  EXPECT_FALSE(collide(hulls, plane, plane_pose, plane, plane_pose, m));
}


// Two equal boxes stacked face to face, each nudged by a tenth of a millimetre and turned by a
// tenth of a milliradian, overlap in an octagon whose corners crowd the square's: the four kept
// points must be one near each corner (a stack's manifold that loses a corner tips the box above,
// and one whose points wander loses its warm start). The reduction once took a second point at a
// corner already held whenever its first three ran clockwise: half of these manifolds.
TEST(BoxClip, EqualStackedBoxesKeepOnePointAtEachCorner) {
  const Vec3 half(0.5, 0.5, 0.5);
  const ConvexHull hull = make_box_hull(half);
  const std::span<const ConvexHull> hulls(&hull, 1);
  const Shape box = Shape::box(0, half);
  std::mt19937 rng(7);
  std::normal_distribution<double> normal(0.0, 1.0);
  auto nudged = [&](double height) {
    const Vec3 axis = Vec3(normal(rng), normal(rng), normal(rng)).normalized();
    return Pose(Vec3(1e-4 * normal(rng), height, 1e-4 * normal(rng)),
                Quat(Eigen::AngleAxisd(1e-4 * normal(rng), axis)));
  };
  int missing = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const Pose lower = nudged(0.5), upper = nudged(1.498);  // 2 mm deep: all four corners below
    Manifold m;
    ASSERT_TRUE(collide(hulls, box, lower, box, upper, m));
    ASSERT_EQ(m.count, 4);
    for (int corner = 0; corner < 4; ++corner) {
      const double x = corner & 1 ? 0.5 : -0.5, z = corner & 2 ? 0.5 : -0.5;
      bool found = false;
      for (int i = 0; i < 4; ++i)
        found |= std::abs(m.points[i].point.x() - x) < 0.01 &&
                 std::abs(m.points[i].point.z() - z) < 0.01;
      missing += !found;
    }
  }
  EXPECT_EQ(missing, 0);
}

// Two nearly aligned unit boxes of a pyramid, 10 µm apart along the upper box's own y axis
// (2·10⁻⁵ rad from the lower one's, half a metre sideways): apart, on the box path as on the hull
// path. The box path once skipped the upper box's face axes as duplicates of the lower's, found
// them touching, clipped nothing, and stood in a contact 0.98 m deep along the axis of two nearly
// parallel edges.
TEST(SeparatingAxes, NearlyParallelBoxesApartAlongTheSecondBoxsAxisDoNotTouch) {
  const Vec3 half(0.5, 0.5, 0.5);
  const ConvexHull hull = make_box_hull(half);
  const std::span<const ConvexHull> hulls(&hull, 1);
  const Pose a({5.515986, 6.494237, -0.006368},
               Quat(0.9999992, -0.0007194, -0.0001775, 0.0010387).normalized());
  const Pose b({6.020064, 7.495297, -0.007590},
               Quat(0.9999992, -0.0007185, -0.0001750, 0.0010269).normalized());
  Manifold m;
  EXPECT_FALSE(collide(hulls, Shape::box(0, half), a, Shape::box(0, half), b, m));
  EXPECT_FALSE(collide(hulls, Shape::convex(0), a, Shape::convex(0), b, m));
  // pressed 1 mm together along the upper box's y axis they touch, and no deeper than that
  const Pose pressed(b.position - 0.001 * b.rotation.col(1), Quat(b.rotation));
  ASSERT_TRUE(collide(hulls, Shape::box(0, half), a, Shape::box(0, half), pressed, m));
  EXPECT_LT(m.depth, 0.002);
  EXPECT_GT(m.normal.y(), 0.99);
}

// ---- shapes name their hulls by index ----

// a shape holds an index, not an address: the pool may grow and move between calls
TEST(HullPool, ShapesKeepTheirHullsWhenThePoolMoves) {
  std::vector<ConvexHull> hulls;
  hulls.push_back(make_box_hull({0.5, 0.5, 0.5}));
  const Shape box = Shape::box(0, {0.5, 0.5, 0.5}), convex = Shape::convex(0);
  const Pose a({0, 0, 0}, Quat::Identity());
  const Pose b({0.2, 0.98, 0.1}, Quat(Eigen::AngleAxisd(0.25, Vec3::UnitY())));
  Manifold before, after;
  ASSERT_TRUE(collide(hulls, box, a, convex, b, before));
  const ConvexHull* first = hulls.data();
  for (int i = 0; i < 64; ++i) hulls.push_back(make_box_hull({1, 1, 1}));
  ASSERT_NE(hulls.data(), first);  // moved
  ASSERT_TRUE(collide(hulls, box, a, convex, b, after));
  EXPECT_EQ(before.count, after.count);
  EXPECT_EQ(before.depth, after.depth);
  EXPECT_EQ(before.normal, after.normal);
  for (int i = 0; i < before.count; ++i) EXPECT_EQ(before.points[i].point, after.points[i].point);
  EXPECT_EQ(Shape::sphere(0.5).hull, kNoHull);
  EXPECT_EQ(Shape::plane(Vec3::UnitY(), 0.0).hull, kNoHull);
}

#ifndef NDEBUG
// an index outside the pool is the owner's bug: a debug build stops on it rather than read past
// the pool
TEST(HullPoolDeathTest, AnIndexOutsideThePoolAssertsInDebugBuilds) {
  const std::vector<ConvexHull> hulls = {make_box_hull({0.5, 0.5, 0.5})};
  const Pose a({0, 0, 0}, Quat::Identity()), b({0.5, 0.5, 0.5}, Quat::Identity());
  Manifold m;
  EXPECT_DEATH(collide(hulls, Shape::convex(1), a, Shape::convex(0), b, m), "Shape::hull");
  EXPECT_DEATH(collide(hulls, Shape::sphere(0.5), a, Shape::convex(kNoHull), b, m),
               "Shape::hull");
}
#endif

}  // namespace
}  // namespace rtp
