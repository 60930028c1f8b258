// Where the sampled bodies of a contact scene overlap, by rtp's narrow phase on the scene's true
// shapes (so no engine's skin or margin hides or adds depth): the penetration metric
// (metrics.cpp) reads the deepest pair of each sample, and the replay viewer's pose files
// (harness/src/poses.cpp, docs/viewer.md) each body's deepest pair and every contact point.
// Every engine's run is measured the same way, from its poses alone.
#pragma once

#include <memory>
#include <vector>

#include "physbench/scene.h"
#include "physbench/simulate.h"

namespace physbench {

// one point of a contact manifold
struct OverlapPoint {
  Vec3 point = Vec3::Zero();  // world, midway between the two surfaces (m)
  double depth = 0.0;         // penetration along the contact normal (m), ≥ 0
};

struct Overlaps {
  double deepest = 0.0;             // the worst pair's depth (m): the penetration metric's sample
  std::vector<double> body_depth;   // per probed column: the deepest pair it is in (m), else 0
  std::vector<OverlapPoint> points;  // every touching pair's manifold points
};

// Dynamic bodies take their sampled pose, static ones the scene's; unprobed dynamic bodies and
// particles are left out. Pairs are found by a sweep of bounding boxes along x; planes are tested
// against every body. A pair's depth is the separating axis depth or its deepest point, whichever
// is larger, and for two boxes never more than their least overlap along a face normal (rtp's box
// path has been seen to answer 0.98 m for two nearly aligned boxes 1 mm apart, docs/metrics.md);
// a point's depth keeps the same bound.
class OverlapGauge {
 public:
  OverlapGauge(const Scene& scene, const std::vector<int>& probed);
  ~OverlapGauge();
  OverlapGauge(OverlapGauge&&) noexcept;

  // everything at one sample; out's buffers are reused
  void measure(const Sample& sample, Overlaps& out) const;
  // the worst pair only (no points kept)
  double deepest(const Sample& sample) const;

 private:
  struct Parts;
  std::unique_ptr<Parts> parts_;
};

}  // namespace physbench
