// The broadphase scene and the broad phases that run it. Only the broad phase runs in every
// engine (model only what the scene needs): N unit boxes move by a motion written here once,
// every engine is handed the same axis-aligned boxes each frame, and its pair set is compared
// with the exact one.
#pragma once

#include <rtp/broadphase.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "physbench/engine.h"

namespace physbench {

enum class BroadphaseMotion : std::uint8_t {
  Coherent,        // small random velocities, reflecting walls: few endpoints swap per frame
  Reshuffled,      // new uniform positions every frame: no coherence at all
  Line,            // every box on one line, overlapping its neighbours: one axis sorts, two don't
  AllOverlapping,  // every box overlaps every other: n(n−1)/2 pairs
};
std::string name_of(BroadphaseMotion motion);
std::optional<BroadphaseMotion> broadphase_motion_named(const std::string& name);

struct BroadphaseScene {
  std::size_t count = 10000;
  BroadphaseMotion motion = BroadphaseMotion::Coherent;
  double mean_overlap = 1.0;  // expected partners per box (Coherent, Reshuffled): sizes the cube
  double speed = 0.05;        // largest per-axis step per frame, in box sizes (Coherent, Line)
  bool planar = false;        // all boxes share z: the same pairs in 2D and in 3D (for Box2D)
  std::uint64_t seed = 1;
};

// the boxes of the scene frame by frame
class BroadphaseFrames {
 public:
  explicit BroadphaseFrames(const BroadphaseScene& scene);
  const std::vector<rtp::Aabb>& boxes() const { return boxes_; }
  void advance();
  double cube_side() const { return side_; }  // m

 private:
  void place_all();
  BroadphaseScene scene_;
  double side_ = 0.0;
  std::mt19937_64 random_;
  std::vector<rtp::Aabb> boxes_;
  std::vector<std::array<float, 3>> velocity_;  // m per frame
};

// the exact pair set of boxes by index (a sort on x and a plain sweep), sorted
std::vector<rtp::ProxyPair> exact_pairs(const std::vector<rtp::Aabb>& boxes);

// One engine's broad phase, driven with boxes by index.
class BroadphaseEngine {
 public:
  virtual ~BroadphaseEngine() = default;
  // inserts every box (from scratch)
  virtual void build(const std::vector<rtp::Aabb>& boxes) = 0;
  // moves every box to its new bounds and brings the pairs up to date; returns how many pairs
  // the engine reports (the timed operation)
  virtual std::size_t update(const std::vector<rtp::Aabb>& boxes) = 0;
  // the pairs of the last update by box index, a < b (untimed: for checking)
  virtual std::vector<rtp::ProxyPair> pairs() const = 0;
};

struct BroadphaseEntry {
  std::string name;    // "rtp/incremental-sap", "bullet/dbvt", …
  std::string engine;  // "rtp", "bullet", …
  std::string version;
  std::vector<Setting> settings;  // what the adapter sets, and why (shown in the report)
  // why this broad phase cannot run the scene (too many boxes for it, not planar, …), if so
  std::function<std::optional<std::string>(const BroadphaseScene&)> unsupported;
  std::function<std::unique_ptr<BroadphaseEngine>()> create;
};

// every broad phase this build has: rtp's variants, then the peers'
std::vector<BroadphaseEntry> broadphase_engines();

// per-engine lists, each defined beside its engine's code
std::vector<BroadphaseEntry> rtp_broadphases();
std::vector<BroadphaseEntry> bullet_broadphases();
std::vector<BroadphaseEntry> ode_broadphases();
std::vector<BroadphaseEntry> box2d_broadphases();

// How a pair set compares with the exact one: a missing pair is a failure; extra pairs (fattened
// boxes) are counted, not failed.
struct PairAgreement {
  std::size_t exact = 0, reported = 0, missing = 0, extra = 0;
};
PairAgreement compare_pairs(std::vector<rtp::ProxyPair> reported,
                            const std::vector<rtp::ProxyPair>& exact);

}  // namespace physbench
