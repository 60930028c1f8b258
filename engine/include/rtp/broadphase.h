// rtp broad phase (the seed's lab 3): which pairs of axis-aligned bounding boxes overlap.
//
// Three variants behind one small interface, all exact (no fattened boxes, no missed pairs):
//   SeedSap         the seed's sweep and prune: endpoints on three axes kept sorted between
//                   frames by insertion sort, a table counting on how many axes each pair
//                   overlaps, read over the n(n−1)/2 triangle each update. The baseline; its
//                   table takes n²/2 bytes, so it refuses more than kSeedSapMaxProxies boxes.
//   IncrementalSap  the seed's next step: the same sorted axes, but a pair is added or removed
//                   when a min and a max endpoint swap during the insertion sort (Baraff 1992,
//                   Bullet's btAxisSweep3), kept in a hashed set instead of the n² table.
//   BoxPruning      for every scene, coherent or not, and very large ones: the boxes bucketed
//                   into slabs across y, each slab ordered on x and swept, testing y and z for
//                   several boxes at once with SIMD (Terdiman, "Box pruning", 2002). While the
//                   scene is coherent the slabs are kept between updates and each slab's order
//                   is repaired by insertion sort (few swaps: a slab holds a few hundred boxes),
//                   boxes that changed slabs dropped or merged in; otherwise (boxes added or
//                   removed, a quarter of them changing slabs, the layout outgrown) every box is
//                   ordered from scratch by Boost's radix-hybrid spreadsort and dealt out again.
//
// Touching counts: intervals are closed, so boxes that share a face, an edge or a corner
// overlap (as in Bullet, ODE and Box2D). In a sorted axis a min endpoint goes before a max
// endpoint of equal value, which makes the order and the closed-interval test agree.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string_view>
#include <vector>

#include "rtp/math.h"

namespace rtp {

// an axis-aligned box (m), 24 bytes
struct Aabb {
  std::array<float, 3> min{}, max{};
};
static_assert(sizeof(Aabb) == 24);

// closed intervals on all three axes: touching boxes overlap
inline bool overlaps(const Aabb& a, const Aabb& b) {
  return a.min[0] <= b.max[0] && b.min[0] <= a.max[0] && a.min[1] <= b.max[1] &&
         b.min[1] <= a.max[1] && a.min[2] <= b.max[2] && b.min[2] <= a.max[2];
}

// whether box `inner` lies within `outer` (closed: a shared face counts)
inline bool contains(const Aabb& outer, const Aabb& inner) {
  return outer.min[0] <= inner.min[0] && outer.min[1] <= inner.min[1] &&
         outer.min[2] <= inner.min[2] && inner.max[0] <= outer.max[0] &&
         inner.max[1] <= outer.max[1] && inner.max[2] <= outer.max[2];
}

// the bounds of a convex shape's vertices (body frame) at a pose: tight under rotation
Aabb bounds_of_points(const std::vector<Vec3>& body_vertices, const Vec3& position,
                      const Quat& orientation);
// the bounds of a box of half extents h at a pose, |R| h about the centre (as tight as the box)
Aabb bounds_of_box(const Vec3& half_extents, const Vec3& position, const Quat& orientation);
Aabb bounds_of_sphere(const Vec3& centre, double radius);

// a handle to one box in a broad phase; reused after the box is removed
using ProxyId = std::uint32_t;

// an overlapping pair, a < b
struct ProxyPair {
  ProxyId a, b;
  // one 64-bit number per pair, for hashed sets
  std::uint64_t key() const { return std::uint64_t(a) << 32 | b; }
  friend bool operator==(const ProxyPair&, const ProxyPair&) = default;
  friend auto operator<=>(const ProxyPair&, const ProxyPair&) = default;
};

enum class BroadPhaseKind : std::uint8_t { SeedSap, IncrementalSap, BoxPruning };
std::string_view name_of(BroadPhaseKind kind);

class BroadPhase {
 public:
  virtual ~BroadPhase() = default;
  // boxes added, moved or removed take effect at the next update()
  virtual ProxyId add(const Aabb& box) = 0;
  virtual void move(ProxyId id, const Aabb& box) = 0;
  virtual void remove(ProxyId id) = 0;
  // brings the pair set up to date with every box's current bounds
  virtual void update() = 0;
  // every overlapping pair of live boxes once, a < b, in no particular order
  virtual const std::vector<ProxyPair>& pairs() const = 0;
  // update() may share its work among this many threads (OpenMP; the pairs found are the same).
  // A variant without a parallel update ignores it
  virtual void set_threads(int /*threads*/) {}
};

// the seed's pair table is n²/2 bytes: 2·10⁸ at this count
inline constexpr std::size_t kSeedSapMaxProxies = 20000;

std::unique_ptr<BroadPhase> make_broad_phase(BroadPhaseKind kind);

// every overlapping pair of the boxes whose alive flag is set (all, when alive is empty), by
// testing all n(n−1)/2 of them, sorted: the reference the tests hold each variant to
std::vector<ProxyPair> brute_force_pairs(const std::vector<Aabb>& boxes,
                                         const std::vector<bool>& alive = {});

}  // namespace rtp
