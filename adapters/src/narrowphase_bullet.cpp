// Bullet's narrow phases on the narrowphase sets: btGjkPairDetector with EPA for penetration
// (what btConvexConvexAlgorithm runs for any convex pair) and btBoxBoxDetector (ODE's dBoxBox,
// what Bullet's dispatcher runs for two boxes).
#include <BulletCollision/CollisionDispatch/btBoxBoxDetector.h>
#include <BulletCollision/NarrowPhaseCollision/btGjkEpaPenetrationDepthSolver.h>
#include <BulletCollision/NarrowPhaseCollision/btGjkPairDetector.h>
#include <BulletCollision/NarrowPhaseCollision/btVoronoiSimplexSolver.h>
#include <btBulletCollisionCommon.h>

#include "bullet_version.h"
#include "physbench/narrowphase.h"

namespace physbench {
namespace {

btVector3 to_bullet(const rtp::Vec3& v) {
  return {btScalar(v.x()), btScalar(v.y()), btScalar(v.z())};
}

btTransform to_bullet(const rtp::Pose& pose) {
  const rtp::Mat3& r = pose.rotation;
  const btMatrix3x3 basis(btScalar(r(0, 0)), btScalar(r(0, 1)), btScalar(r(0, 2)),
                          btScalar(r(1, 0)), btScalar(r(1, 1)), btScalar(r(1, 2)),
                          btScalar(r(2, 0)), btScalar(r(2, 1)), btScalar(r(2, 2)));
  return btTransform(basis, to_bullet(pose.position));
}

// the deepest point Bullet reports, and how many
struct DeepestPoint : btDiscreteCollisionDetectorInterface::Result {
  int points = 0;
  btScalar depth = 0;  // Bullet's sign: negative when penetrating
  btVector3 normal_on_b{0, 0, 0};
  void setShapeIdentifiersA(int, int) override {}
  void setShapeIdentifiersB(int, int) override {}
  void addContactPoint(const btVector3& normal_on_b_in_world, const btVector3&,
                       btScalar point_depth) override {
    if (points++ == 0 || point_depth < depth)
      depth = point_depth, normal_on_b = normal_on_b_in_world;
  }
};

enum class BulletMethod : std::uint8_t { GjkEpa, BoxBox };

class BulletNarrowphase final : public NarrowphasePeer {
 public:
  BulletNarrowphase(const NarrowphaseSet& set, BulletMethod method) : method_(method) {
    // every shape exact: no collision margin (Bullet's boxes and hulls default to 4 cm)
    for (const rtp::Shape& shape : set.shapes) {
      switch (shape.kind) {
        case rtp::ShapeKind::Sphere:
          shapes_.push_back(std::make_unique<btSphereShape>(btScalar(shape.radius)));
          break;
        case rtp::ShapeKind::Box: {
          auto box = std::make_unique<btBoxShape>(to_bullet(shape.half_extents));
          box->setMargin(0);
          shapes_.push_back(std::move(box));
          break;
        }
        case rtp::ShapeKind::Hull: {
          auto hull = std::make_unique<btConvexHullShape>();
          for (const rtp::Vec3& v : rtp::hull_of(shape, set.hulls).vertices)
            hull->addPoint(to_bullet(v), false);
          hull->recalcLocalAabb();
          hull->setMargin(0);
          shapes_.push_back(std::move(hull));
          break;
        }
        case rtp::ShapeKind::Plane:
          throw std::invalid_argument("bullet narrowphase: sets hold no planes");
      }
    }
    for (const NarrowphasePair& pair : set.pairs)
      pairs_.push_back(
          {pair.shape_a, pair.shape_b, to_bullet(pair.pose_a), to_bullet(pair.pose_b)});
  }

  PeerContact collide(std::size_t index) override {
    const Pair& pair = pairs_[index];
    btDiscreteCollisionDetectorInterface::ClosestPointInput input;
    input.m_transformA = pair.transform_a;
    input.m_transformB = pair.transform_b;
    DeepestPoint result;
    PeerContact contact;
    if (method_ == BulletMethod::BoxBox) {
      btBoxBoxDetector detector(static_cast<const btBoxShape*>(shapes_[pair.a].get()),
                                static_cast<const btBoxShape*>(shapes_[pair.b].get()));
      detector.getClosestPoints(input, result, nullptr);
      contact.touching = result.points > 0;
    } else {
      // the distance apart too, not only penetration
      input.m_maximumDistanceSquared = BT_LARGE_FLOAT;
      simplex_.reset();
      btGjkPairDetector detector(shapes_[pair.a].get(), shapes_[pair.b].get(), &simplex_, &epa_);
      detector.getClosestPoints(input, result, nullptr);
      contact.touching = result.points > 0 && result.depth <= 0;
      contact.distance_known = result.points > 0;
    }
    contact.points = result.points;
    contact.depth = -double(result.depth);
    // Bullet's normal is B's, pointing at A; ours runs from A to B
    contact.normal =
        -rtp::Vec3(result.normal_on_b.x(), result.normal_on_b.y(), result.normal_on_b.z());
    return contact;
  }

 private:
  struct Pair {
    std::uint32_t a, b;
    btTransform transform_a, transform_b;
  };
  BulletMethod method_;
  std::vector<std::unique_ptr<btConvexShape>> shapes_;
  std::vector<Pair> pairs_;
  btVoronoiSimplexSolver simplex_;
  btGjkEpaPenetrationDepthSolver epa_;
};

class BulletTriangleBatch final : public TriangleBatch {
 public:
  explicit BulletTriangleBatch(const std::vector<TriangleQuery>& queries) {
    for (const TriangleQuery& q : queries)
      queries_.push_back({to_bullet(q.point), to_bullet(q.a), to_bullet(q.b), to_bullet(q.c)});
  }
  double run(std::span<const std::uint32_t> order) override {
    double sum = 0.0;
    btSubSimplexClosestResult result;
    for (const std::uint32_t i : order) {
      const Query& q = queries_[i];
      solver_.closestPtPointTriangle(q.point, q.a, q.b, q.c, result);
      sum += double((q.point - result.m_closestPointOnSimplex).length());
    }
    return sum;
  }
  rtp::Vec3 closest(std::size_t i) override {
    const Query& q = queries_[i];
    btSubSimplexClosestResult result;
    solver_.closestPtPointTriangle(q.point, q.a, q.b, q.c, result);
    const btVector3& c = result.m_closestPointOnSimplex;
    return {c.x(), c.y(), c.z()};
  }

 private:
  struct Query {
    btVector3 point, a, b, c;
  };
  std::vector<Query> queries_;
  btVoronoiSimplexSolver solver_;
};

}  // namespace

std::vector<NarrowphasePeerEntry> bullet_narrowphases() {
  const Setting margins{"margins", "0 on boxes and hulls; spheres as btSphereShape",
                        "the exact shapes rtp sees (Bullet's default margin is 4 cm)"};
  NarrowphasePeerEntry gjk;
  gjk.name = "bullet/gjk-epa";
  gjk.version = bullet_version("float");
  gjk.settings = {
      {"detector", "btGjkPairDetector, btVoronoiSimplexSolver, btGjkEpaPenetrationDepthSolver",
       "what btConvexConvexAlgorithm runs for a convex pair"},
      margins,
      {"maximum distance", "unlimited", "so that it reports the distance apart too"}};
  gjk.unsupported = [](const NarrowphaseSet&) { return std::optional<std::string>(); };
  gjk.create = [](const NarrowphaseSet& set) {
    return std::make_unique<BulletNarrowphase>(set, BulletMethod::GjkEpa);
  };

  NarrowphasePeerEntry box;
  box.name = "bullet/box-box";
  box.version = bullet_version("float");
  box.settings = {{"detector", "btBoxBoxDetector (ODE's dBoxBox)",
                   "what Bullet's dispatcher runs for two boxes"},
                  margins};
  box.unsupported = [](const NarrowphaseSet& set) -> std::optional<std::string> {
    if (set.shapes_kind != NarrowphaseShapes::BoxBox)
      return "unsupported: btBoxBoxDetector handles two boxes only";
    return std::nullopt;
  };
  box.create = [](const NarrowphaseSet& set) {
    return std::make_unique<BulletNarrowphase>(set, BulletMethod::BoxBox);
  };
  return {gjk, box};
}

std::unique_ptr<TriangleBatch> make_bullet_triangle_batch(
    const std::vector<TriangleQuery>& queries) {
  return std::make_unique<BulletTriangleBatch>(queries);
}

}  // namespace physbench
