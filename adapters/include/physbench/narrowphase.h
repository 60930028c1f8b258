// The narrow-phase pair sets, built once here for the validation tests and the benchmark, and
// the peers that answer them. Only the narrow phase runs (model only what the scene needs): each
// engine is handed the same shapes at the same poses and says whether they touch, along which
// normal and how deep.
//
// A set holds pairs of one shape kind in one regime. Poses are random (uniform orientations);
// the second shape is placed along a random direction at a fraction of the distance where the
// two first touch, found by bisection on rtp's verdict (the verdict comparison is meaningful all
// the same: a wrong touching distance would show as disagreements in the touching regime).
#pragma once

#include <rtp/collision.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "physbench/engine.h"

namespace physbench {

enum class NarrowphaseShapes : std::uint8_t {
  BoxBox,      // boxes, half extents 0.1–0.5 m
  HullHull,    // 32-vertex hulls: points on ellipsoids of semi-axes 0.2–0.6 m
  SphereHull,  // a sphere of radius 0.1–0.4 m against a 32-vertex hull
  BoxHull,     // a box against a 32-vertex hull
};
enum class NarrowphaseRegime : std::uint8_t {
  Separated,       // 1.02–1.5 × the touching distance
  Touching,        // 0.98–1.02 ×: within a few millimetres either way
  Deep,            // 0.3–0.9 ×
  NearlyParallel,  // boxes only: the second is the first's orientation turned < 1 mrad,
                   // 0.97–1.0 × (face on face, the hardest case for parallel-axis pruning)
};
std::string name_of(NarrowphaseShapes shapes);
std::string name_of(NarrowphaseRegime regime);

struct NarrowphasePair {
  std::uint32_t shape_a = 0, shape_b = 0;  // into NarrowphaseSet::shapes
  rtp::Pose pose_a, pose_b;
};

struct NarrowphaseSet {
  NarrowphaseShapes shapes_kind = NarrowphaseShapes::BoxBox;
  NarrowphaseRegime regime = NarrowphaseRegime::Touching;
  std::vector<rtp::ConvexHull> hulls;  // the pool the shapes' hull indices refer to
  std::vector<rtp::Shape> shapes;
  std::vector<NarrowphasePair> pairs;
  std::string name() const;  // "box-box/touching"
};

// count pairs of the kind in the regime; NearlyParallel only for BoxBox (std::invalid_argument
// otherwise)
NarrowphaseSet make_narrowphase_set(NarrowphaseShapes shapes, NarrowphaseRegime regime,
                                    std::size_t count, std::uint64_t seed);

// one engine's answer for one pair
struct PeerContact {
  bool touching = false;
  double depth = 0.0;                    // penetration (m); negative: the distance apart
  rtp::Vec3 normal = rtp::Vec3::Zero();  // unit, first shape → second
  int points = 0;
  bool distance_known = false;  // depth is also the distance apart when not touching (GJK)
};

// a peer narrow phase: prepared once per set (shapes and transforms converted), then asked per
// pair
class NarrowphasePeer {
 public:
  virtual ~NarrowphasePeer() = default;
  virtual PeerContact collide(std::size_t pair) = 0;
};

struct NarrowphasePeerEntry {
  std::string name;  // "bullet/gjk-epa", "bullet/box-box"
  std::string version;
  std::vector<Setting> settings;
  // why it cannot answer this set, if it cannot
  std::function<std::optional<std::string>(const NarrowphaseSet&)> unsupported;
  std::function<std::unique_ptr<NarrowphasePeer>(const NarrowphaseSet&)> create;
};

// every peer narrow phase this build has (none without Bullet)
std::vector<NarrowphasePeerEntry> narrowphase_peers();
std::vector<NarrowphasePeerEntry> bullet_narrowphases();
// rtp behind the same interface, for the benchmark: "rtp/sat" (collide(): the table, so boxes
// take the closed form) and "rtp/sat-hull" (boxes as general hulls, box-box sets only)
std::vector<NarrowphasePeerEntry> rtp_narrowphases();

// lab 4.1's query, for the benchmark: a point and a triangle
struct TriangleQuery {
  rtp::Vec3 point, a, b, c;
};
std::vector<TriangleQuery> make_triangle_queries(std::size_t count, std::uint64_t seed);

// one engine's closest-point-on-triangle over a batch of queries, prepared once
class TriangleBatch {
 public:
  virtual ~TriangleBatch() = default;
  // answers every query once, in the given order (a permutation of the queries' indices);
  // returns the sum of the distances (so the work cannot be elided)
  virtual double run(std::span<const std::uint32_t> order) = 0;
  // the closest point of one query (untimed: for checking)
  virtual rtp::Vec3 closest(std::size_t query) = 0;
};
std::unique_ptr<TriangleBatch> make_rtp_triangle_batch(const std::vector<TriangleQuery>& queries);
// Bullet's btVoronoiSimplexSolver::closestPtPointTriangle; nullptr in a build without Bullet
std::unique_ptr<TriangleBatch> make_bullet_triangle_batch(
    const std::vector<TriangleQuery>& queries);

// rtp's answer in the peers' terms
PeerContact rtp_contact(const rtp::Manifold& manifold, bool touching);

// The tolerances of the comparison, stated once: the report prints them.
struct NarrowphaseTolerances {
  // pairs whose peer distance is within this of zero are not compared for the verdict: single
  // precision GJK/EPA and the placement noise live there (m)
  double verdict_band = 1e-3;
  // depths agree within this plus this fraction of the depth (covers the 2 % face preference)
  double depth_absolute = 1e-3;
  double depth_relative = 0.025;
  // normals agree within this angle — or tie: the overlap along the peer's normal is within the
  // depth tolerance of rtp's depth, so both are least-penetration directions
  double normal_degrees = 1.0;
  // a contact point lies on a surface within this (m)
  double surface = 1e-9;
};

struct NarrowphaseAgreement {
  std::size_t pairs = 0;
  std::size_t in_band = 0;         // not compared for the verdict
  std::size_t verdict_agree = 0;   // of pairs − in_band
  std::size_t both_deep = 0;       // both touching, peer depth beyond the band
  std::size_t depth_agree = 0;     // of both_deep
  std::size_t normal_agree = 0;    // of both_deep: within the angle
  std::size_t normal_tie = 0;      // of both_deep: another least-penetration direction
  std::size_t points = 0;          // rtp's contact points over all pairs
  std::size_t points_on_both = 0;  // of points: on both surfaces
  // disagreements the exact check settles for rtp (see compare_narrowphase): counted apart,
  // not failed
  std::size_t peer_refuted = 0;
  double worst_depth_error = 0.0;          // m, over both_deep
  double worst_normal_degrees = 0.0;       // over both_deep, ties excluded
  std::vector<std::size_t> disagreements;  // pairs with a verdict, depth or normal failure
};

// compares rtp with a peer over a whole set (rtp's manifolds computed here). A disagreement is
// settled by exact geometry that shares no code with rtp's separating axis test: the overlap of
// the two shapes' extents along a direction (from their vertices, or centre and radius), and for
// the verdict a separating axis test over every face normal and every edge-pair cross product,
// unpruned. Where the exact check sides with rtp the pair counts as peer_refuted; anywhere else as
// a disagreement.
NarrowphaseAgreement compare_narrowphase(const NarrowphaseSet& set, NarrowphasePeer& peer,
                                         const NarrowphaseTolerances& tolerances = {});

}  // namespace physbench
