#include "physbench/narrowphase.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>

namespace physbench {
namespace {

rtp::Quat random_orientation(std::mt19937_64& random) {
  std::normal_distribution<double> normal;
  rtp::Quat q(normal(random), normal(random), normal(random), normal(random));
  q.normalize();
  return q;
}

rtp::Vec3 random_direction(std::mt19937_64& random) {
  std::normal_distribution<double> normal;
  rtp::Vec3 v(normal(random), normal(random), normal(random));
  return v.normalized();
}

// 32 points on an ellipsoid: every one is a vertex of their hull
constexpr int kHullPoints = 32;
std::vector<rtp::Vec3> ellipsoid_points(std::mt19937_64& random) {
  std::uniform_real_distribution<double> semi_axis(0.2, 0.6);
  const rtp::Vec3 axes(semi_axis(random), semi_axis(random), semi_axis(random));
  std::vector<rtp::Vec3> points;
  for (int i = 0; i < kHullPoints; ++i)
    points.push_back(random_direction(random).cwiseProduct(axes));
  return points;
}

// a bound on the distance from a shape's origin to its surface (m)
double bounding_radius(std::span<const rtp::ConvexHull> hulls, const rtp::Shape& shape) {
  switch (shape.kind) {
    case rtp::ShapeKind::Sphere:
      return shape.radius;
    case rtp::ShapeKind::Box:
      return shape.half_extents.norm();
    case rtp::ShapeKind::Hull: {
      double r = 0.0;
      for (const rtp::Vec3& v : rtp::hull_of(shape, hulls).vertices) r = std::max(r, v.norm());
      return r;
    }
    case rtp::ShapeKind::Plane:
      break;
  }
  throw std::invalid_argument("narrowphase sets hold no planes");
}

// the penetration along a unit direction n, first → second: the overlap of the two shapes'
// extents on n (the minimum over all n is the penetration depth)
double overlap_along(std::span<const rtp::ConvexHull> hulls, const rtp::Shape& shape_a,
                     const rtp::Pose& a, const rtp::Shape& shape_b, const rtp::Pose& b,
                     const rtp::Vec3& n) {
  auto support = [hulls](const rtp::Shape& s, const rtp::Pose& pose, const rtp::Vec3& d) {
    if (s.kind == rtp::ShapeKind::Sphere) return d.dot(pose.position) + s.radius;
    double best = -std::numeric_limits<double>::infinity();
    for (const rtp::Vec3& v : rtp::hull_of(s, hulls).vertices)
      best = std::max(best, d.dot(pose.position + pose.rotation * v));
    return best;
  };
  return support(shape_a, a, n) + support(shape_b, b, -n);
}

// the exact verdict: the largest separation over every candidate axis of two polyhedra (all
// face normals, all edge-pair cross products, both signs — no pruning), or the centre's distance
// from the hull minus the radius for a sphere; positive when apart, ≤ 0 when touching
double exact_separation(std::span<const rtp::ConvexHull> hulls, const rtp::Shape& a,
                        const rtp::Pose& pose_a, const rtp::Shape& b, const rtp::Pose& pose_b) {
  if (b.kind == rtp::ShapeKind::Sphere) return exact_separation(hulls, b, pose_b, a, pose_a);
  const rtp::ConvexHull& hull_b = rtp::hull_of(b, hulls);
  auto world = [](const rtp::Pose& pose, const rtp::Vec3& v) {
    return rtp::Vec3(pose.position + pose.rotation * v);
  };
  if (a.kind == rtp::ShapeKind::Sphere) {
    // the centre's distance from the hull: inside, the nearest face plane; outside, the nearest
    // point of any face (each face a fan of triangles)
    const rtp::Vec3& c = pose_a.position;
    const double plane = rtp::face_plane_distance(hull_b, pose_b, c);
    if (plane <= 0.0) return plane - a.radius;
    double nearest = std::numeric_limits<double>::infinity();
    for (const rtp::HullFace& f : hull_b.faces) {
      const rtp::Vec3 apex = world(pose_b, hull_b.vertices[hull_b.face_vertices[f.first]]);
      for (std::uint32_t i = 1; i + 1 < f.count; ++i) {
        const rtp::Vec3 p = world(pose_b, hull_b.vertices[hull_b.face_vertices[f.first + i]]);
        const rtp::Vec3 q = world(pose_b, hull_b.vertices[hull_b.face_vertices[f.first + i + 1]]);
        nearest =
            std::min(nearest, (c - rtp::closest_point_on_triangle(c, apex, p, q).point).norm());
      }
    }
    return nearest - a.radius;
  }
  const rtp::ConvexHull& hull_a = rtp::hull_of(a, hulls);
  double largest = -std::numeric_limits<double>::infinity();
  auto axis = [&](const rtp::Vec3& n) {
    largest = std::max(largest, -overlap_along(hulls, a, pose_a, b, pose_b, n));
    largest = std::max(largest, -overlap_along(hulls, a, pose_a, b, pose_b, -n));
  };
  for (const rtp::HullFace& f : hull_a.faces) axis(pose_a.rotation * f.normal);
  for (const rtp::HullFace& f : hull_b.faces) axis(pose_b.rotation * f.normal);
  for (const rtp::HullEdge& ea : hull_a.edges)
    for (const rtp::HullEdge& eb : hull_b.edges) {
      const rtp::Vec3 da = pose_a.rotation * (hull_a.vertices[ea.head] - hull_a.vertices[ea.tail]);
      const rtp::Vec3 db = pose_b.rotation * (hull_b.vertices[eb.head] - hull_b.vertices[eb.tail]);
      const rtp::Vec3 n = da.cross(db);
      if (n.norm() > 1e-12 * da.norm() * db.norm()) axis(n.normalized());
    }
  return largest;
}

// signed distance of a point from a shape's surface where the point is inside or on it; a lower
// bound outside (what "on the surface within tolerance" needs)
double surface_distance(std::span<const rtp::ConvexHull> hulls, const rtp::Shape& shape,
                        const rtp::Pose& pose, const rtp::Vec3& p) {
  if (shape.kind == rtp::ShapeKind::Sphere) return (p - pose.position).norm() - shape.radius;
  return rtp::face_plane_distance(rtp::hull_of(shape, hulls), pose, p);
}

}  // namespace

std::string name_of(NarrowphaseShapes shapes) {
  switch (shapes) {
    case NarrowphaseShapes::BoxBox:
      return "box-box";
    case NarrowphaseShapes::HullHull:
      return "hull-hull";
    case NarrowphaseShapes::SphereHull:
      return "sphere-hull";
    case NarrowphaseShapes::BoxHull:
      return "box-hull";
  }
  return "?";
}

std::string name_of(NarrowphaseRegime regime) {
  switch (regime) {
    case NarrowphaseRegime::Separated:
      return "separated";
    case NarrowphaseRegime::Touching:
      return "touching";
    case NarrowphaseRegime::Deep:
      return "deep";
    case NarrowphaseRegime::NearlyParallel:
      return "nearly-parallel";
  }
  return "?";
}

std::string NarrowphaseSet::name() const { return name_of(shapes_kind) + "/" + name_of(regime); }

NarrowphaseSet make_narrowphase_set(NarrowphaseShapes shapes, NarrowphaseRegime regime,
                                    std::size_t count, std::uint64_t seed) {
  if (regime == NarrowphaseRegime::NearlyParallel && shapes != NarrowphaseShapes::BoxBox)
    throw std::invalid_argument("narrowphase: the nearly-parallel regime is for box-box pairs");
  NarrowphaseSet set;
  set.shapes_kind = shapes;
  set.regime = regime;
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> half_extent(0.1, 0.5), radius(0.1, 0.4);

  auto add_box = [&] {
    const rtp::Vec3 h(half_extent(random), half_extent(random), half_extent(random));
    set.shapes.push_back(rtp::Shape::box(std::uint32_t(set.hulls.size()), h));
    set.hulls.push_back(rtp::make_box_hull(h));
  };
  auto add_hull = [&] {
    set.shapes.push_back(rtp::Shape::convex(std::uint32_t(set.hulls.size())));
    set.hulls.push_back(rtp::make_convex_hull(ellipsoid_points(random)));
  };
  auto add_sphere = [&] { set.shapes.push_back(rtp::Shape::sphere(radius(random))); };

  std::uniform_real_distribution<double> separated(1.02, 1.5), touching(0.98, 1.02), deep(0.3, 0.9),
      nearly(0.97, 1.0), small_angle(0.0, 1e-3);
  rtp::Manifold manifold;
  for (std::size_t i = 0; i < count; ++i) {
    NarrowphasePair pair;
    pair.shape_a = std::uint32_t(set.shapes.size());
    switch (shapes) {
      case NarrowphaseShapes::BoxBox:
        add_box(), add_box();
        break;
      case NarrowphaseShapes::HullHull:
        add_hull(), add_hull();
        break;
      case NarrowphaseShapes::SphereHull:
        add_sphere(), add_hull();
        break;
      case NarrowphaseShapes::BoxHull:
        add_box(), add_hull();
        break;
    }
    pair.shape_b = pair.shape_a + 1;
    const rtp::Shape& a = set.shapes[pair.shape_a];
    const rtp::Shape& b = set.shapes[pair.shape_b];
    const rtp::Quat orientation_a = random_orientation(random);
    rtp::Quat orientation_b = random_orientation(random);
    if (regime == NarrowphaseRegime::NearlyParallel)
      orientation_b = orientation_a *
                      rtp::Quat(Eigen::AngleAxisd(small_angle(random), random_direction(random)));
    pair.pose_a = rtp::Pose(rtp::Vec3::Zero(), orientation_a);
    pair.pose_b = rtp::Pose(rtp::Vec3::Zero(), orientation_b);

    // the touching distance along a random direction, by bisection on the verdict
    const rtp::Vec3 direction = random_direction(random);
    double inside = 0.0,
           outside = 1.01 * (bounding_radius(set.hulls, a) + bounding_radius(set.hulls, b));
    for (int step = 0; step < 32; ++step) {
      const double middle = 0.5 * (inside + outside);
      pair.pose_b.position = middle * direction;
      const bool touching = rtp::collide(set.hulls, a, pair.pose_a, b, pair.pose_b, manifold);
      (touching ? inside : outside) = middle;
    }
    double fraction = 1.0;
    switch (regime) {
      case NarrowphaseRegime::Separated:
        fraction = separated(random);
        break;
      case NarrowphaseRegime::Touching:
        fraction = touching(random);
        break;
      case NarrowphaseRegime::Deep:
        fraction = deep(random);
        break;
      case NarrowphaseRegime::NearlyParallel:
        fraction = nearly(random);
        break;
    }
    pair.pose_b.position = fraction * outside * direction;
    set.pairs.push_back(pair);
  }
  return set;
}

PeerContact rtp_contact(const rtp::Manifold& manifold, bool touching) {
  return {touching, touching ? manifold.depth : 0.0, manifold.normal, manifold.count};
}

NarrowphaseAgreement compare_narrowphase(const NarrowphaseSet& set, NarrowphasePeer& peer,
                                         const NarrowphaseTolerances& tolerances) {
  NarrowphaseAgreement agreement;
  rtp::Manifold manifold;
  for (std::size_t i = 0; i < set.pairs.size(); ++i) {
    const NarrowphasePair& pair = set.pairs[i];
    const rtp::Shape& a = set.shapes[pair.shape_a];
    const rtp::Shape& b = set.shapes[pair.shape_b];
    const bool touching = rtp::collide(set.hulls, a, pair.pose_a, b, pair.pose_b, manifold);
    const PeerContact theirs = peer.collide(i);
    ++agreement.pairs;
    bool failed = false, refuted = false;

    // every contact point on both surfaces: the first's half the depth along the normal
    for (std::uint8_t k = 0; k < manifold.count; ++k) {
      const rtp::ContactPoint& p = manifold.points[k];
      ++agreement.points;
      const double on_a =
          surface_distance(set.hulls, a, pair.pose_a, p.point + 0.5 * p.depth * manifold.normal);
      const double on_b =
          surface_distance(set.hulls, b, pair.pose_b, p.point - 0.5 * p.depth * manifold.normal);
      if (std::abs(on_a) <= tolerances.surface && std::abs(on_b) <= tolerances.surface)
        ++agreement.points_on_both;
      else
        failed = true;
    }

    // the verdict, outside the band around touching (the peer's distance where it gives one,
    // else rtp's depth)
    const double distance_to_touching = theirs.touching || theirs.distance_known
                                            ? std::abs(theirs.depth)
                                            : std::abs(manifold.depth);
    if (distance_to_touching < tolerances.verdict_band && (theirs.touching || touching)) {
      ++agreement.in_band;
    } else if (touching == theirs.touching) {
      ++agreement.verdict_agree;
    } else if (  // the exact separation sides with rtp, and the peer's own figure is off it by
                 // more than the band (where the peer gives none, the exact one is beyond it)
        const double exact = exact_separation(set.hulls, a, pair.pose_a, b, pair.pose_b);
        (exact <= 0.0) == touching &&
        std::abs(exact - (theirs.touching || theirs.distance_known ? -theirs.depth : 0.0)) >=
            tolerances.verdict_band) {
      refuted = true;
    } else {
      failed = true;
    }

    // depth and normal where both see a contact beyond the band
    if (touching && theirs.touching && theirs.depth >= tolerances.verdict_band) {
      ++agreement.both_deep;
      const double depth_error = std::abs(manifold.depth - theirs.depth);
      agreement.worst_depth_error = std::max(agreement.worst_depth_error, depth_error);
      const double depth_tolerance =
          tolerances.depth_absolute + tolerances.depth_relative * theirs.depth;
      // rtp's answer is exact when its depth is the overlap along its own normal and the peer's
      // normal allows no less; a peer that disagrees with an exact answer is wrong
      const double along_ours =
          overlap_along(set.hulls, a, pair.pose_a, b, pair.pose_b, manifold.normal);
      const double along_theirs =
          overlap_along(set.hulls, a, pair.pose_a, b, pair.pose_b, theirs.normal);
      const bool ours_exact =
          std::abs(along_ours - manifold.depth) <= 1e-9 * (1.0 + manifold.depth) &&
          manifold.depth <= along_theirs + depth_tolerance;
      if (depth_error <= depth_tolerance)
        ++agreement.depth_agree;
      else if (ours_exact)
        refuted = true;
      else
        failed = true;
      const double angle = std::acos(std::clamp(manifold.normal.dot(theirs.normal), -1.0, 1.0)) *
                           180.0 / std::numbers::pi;
      if (angle <= tolerances.normal_degrees) {
        ++agreement.normal_agree;
        agreement.worst_normal_degrees = std::max(agreement.worst_normal_degrees, angle);
      } else if (std::abs(along_theirs - manifold.depth) <= depth_tolerance) {
        ++agreement.normal_tie;
      } else if (ours_exact) {
        refuted = true;
      } else {
        agreement.worst_normal_degrees = std::max(agreement.worst_normal_degrees, angle);
        failed = true;
      }
    }
    if (failed)
      agreement.disagreements.push_back(i);
    else if (refuted)
      ++agreement.peer_refuted;
  }
  return agreement;
}

namespace {

class RtpNarrowphase final : public NarrowphasePeer {
 public:
  RtpNarrowphase(const NarrowphaseSet& set, bool boxes_as_hulls) : set_(set) {
    shapes_ = set.shapes;
    if (boxes_as_hulls)
      for (rtp::Shape& s : shapes_)
        if (s.kind == rtp::ShapeKind::Box) s = rtp::Shape::convex(s.hull);
  }
  PeerContact collide(std::size_t index) override {
    const NarrowphasePair& p = set_.pairs[index];
    const bool touching =
        rtp::collide(set_.hulls, shapes_[p.shape_a], p.pose_a, shapes_[p.shape_b], p.pose_b,
                     manifold_);
    return rtp_contact(manifold_, touching);
  }

 private:
  const NarrowphaseSet& set_;
  std::vector<rtp::Shape> shapes_;
  rtp::Manifold manifold_;
};

class RtpTriangleBatch final : public TriangleBatch {
 public:
  explicit RtpTriangleBatch(const std::vector<TriangleQuery>& queries) : queries_(queries) {}
  double run(std::span<const std::uint32_t> order) override {
    double sum = 0.0;
    for (const std::uint32_t i : order) {
      const TriangleQuery& q = queries_[i];
      sum += (q.point - rtp::closest_point_on_triangle(q.point, q.a, q.b, q.c).point).norm();
    }
    return sum;
  }
  rtp::Vec3 closest(std::size_t i) override {
    const TriangleQuery& q = queries_[i];
    return rtp::closest_point_on_triangle(q.point, q.a, q.b, q.c).point;
  }

 private:
  std::vector<TriangleQuery> queries_;
};

}  // namespace

std::vector<NarrowphasePeerEntry> rtp_narrowphases() {
  NarrowphasePeerEntry table;
  table.name = "rtp/sat";
  table.version = "this build";
  table.settings = {{"dispatch",
                     "collide(): boxes by the closed-form test, hulls by the Gauss-map SAT",
                     "rtp's narrow phase as a world would call it"}};
  table.unsupported = [](const NarrowphaseSet&) { return std::optional<std::string>(); };
  table.create = [](const NarrowphaseSet& set) {
    return std::make_unique<RtpNarrowphase>(set, false);
  };
  NarrowphasePeerEntry general = table;
  general.name = "rtp/sat-hull";
  general.settings = {{"dispatch", "boxes as general hulls (Gauss-map SAT, clipping of hull faces)",
                       "what the closed form saves"}};
  general.unsupported = [](const NarrowphaseSet& set) -> std::optional<std::string> {
    if (set.shapes_kind != NarrowphaseShapes::BoxBox)
      return "only box-box sets have boxes to convert";
    return std::nullopt;
  };
  general.create = [](const NarrowphaseSet& set) {
    return std::make_unique<RtpNarrowphase>(set, true);
  };
  return {table, general};
}

std::vector<TriangleQuery> make_triangle_queries(std::size_t count, std::uint64_t seed) {
  // unit-scale triangles and points around them: every Voronoi region is met
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  auto point = [&](double scale) -> rtp::Vec3 {
    return rtp::Vec3(u(random), u(random), u(random)) * scale;
  };
  std::vector<TriangleQuery> queries;
  while (queries.size() < count) {
    TriangleQuery q{point(2.0), point(1.0), point(1.0), point(1.0)};
    if ((q.b - q.a).cross(q.c - q.a).norm() > 0.05) queries.push_back(q);
  }
  return queries;
}

std::unique_ptr<TriangleBatch> make_rtp_triangle_batch(const std::vector<TriangleQuery>& queries) {
  return std::make_unique<RtpTriangleBatch>(queries);
}

#ifndef PHYSBENCH_HAVE_BULLET
std::vector<NarrowphasePeerEntry> bullet_narrowphases() { return {}; }
std::unique_ptr<TriangleBatch> make_bullet_triangle_batch(const std::vector<TriangleQuery>&) {
  return nullptr;
}
#endif

std::vector<NarrowphasePeerEntry> narrowphase_peers() { return bullet_narrowphases(); }

}  // namespace physbench
