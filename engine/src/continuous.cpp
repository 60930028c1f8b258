// Continuous collision against static shapes (docs/solver.md, "Fast bodies"): a body that moved
// more than its motion margin this step is swept from its start pose to its end one, and stopped
// where it first comes within the speculative distance of a static shape.
#include "contacts.h"

#include <algorithm>
#include <cmath>

namespace rtp {
inline namespace RTP_CONTACT_ISA_NAMESPACE {

std::size_t ContactPipeline::sweep_fast_bodies(std::span<BodyState> states) {
  // Conservative sampling of the sweep: the grown shape at poses no further apart than half its
  // thickness covers every point the moving shape passes through (a turn is sampled by its
  // surface's arc, |Δθ| reach), so the first sample that touches a static shape brackets the
  // first touch, and bisection narrows the bracket to a 2⁻¹² share of the step. A body already
  // touching at the step's start is left to its contacts. Dynamic pairs are not swept (both
  // bodies move; they tunnel past each other at such speeds, as docs/solver.md states).
  std::size_t stopped = 0;
  Manifold manifold;
  for (const FastBody& fast : fast_) {
    const BodyShapeData& data = shapes_[fast.id];
    BodyState& end = states[fast.id];
    const Vec3 travel = end.position - fast.position;
    const double turn = fast.orientation.angularDistance(end.orientation);
    const double motion = travel.norm() + turn * data.reach;
    if (!(motion > settings_.motion_margin_share * data.thinnest)) continue;
    auto pose_at = [&](double t) {
      return Pose(fast.position + t * travel, fast.orientation.slerp(t, end.orientation));
    };
    // the swept shape's bounds: the centre's path grown by the farthest surface point
    const double grown_reach = data.reach + 0.5 * settings_.speculative_distance;
    Aabb swept;
    for (int k = 0; k < 3; ++k) {
      // floats rounded outwards by a part in 10⁶: the test must not miss a wall by rounding
      const double low = std::min(fast.position[k], end.position[k]) - grown_reach;
      const double high = std::max(fast.position[k], end.position[k]) + grown_reach;
      swept.min[k] = float(low - 1e-6 * (std::abs(low) + 1.0));
      swept.max[k] = float(high + 1e-6 * (std::abs(high) + 1.0));
    }
    const int samples = int(std::ceil(motion / (0.5 * data.thinnest)));
    double first_touch = 1.0;  // the earliest clear time before a touch, over the static shapes
    bool touched = false;
    for (BodyId other : static_shaped_) {
      const BodyShapeData& wall = shapes_[other];
      if (wall.kind != BodyShape::Plane && !overlaps(swept, bounds_[other])) continue;
      const Pose wall_pose = pose_of(states[other]);
      auto touches = [&](double t) {
        return collide(hulls_, data.shape, pose_at(t), wall.shape, wall_pose, manifold);
      };
      if (touches(0.0)) continue;  // touching at the start: the step's own contact
      for (int k = 1; k <= samples; ++k) {
        const double t = double(k) / samples;
        if (t - 1.0 / samples >= first_touch) break;  // an earlier wall stops it first
        if (!touches(t)) continue;
        double clear = double(k - 1) / samples, hit = t;
        for (int i = 0; i < 12; ++i) {
          const double mid = 0.5 * (clear + hit);
          (touches(mid) ? hit : clear) = mid;
        }
        if (clear < first_touch) first_touch = clear, touched = true;
        break;
      }
    }
    if (!touched) continue;
    end.position = fast.position + first_touch * travel;
    end.orientation = fast.orientation.slerp(first_touch, end.orientation).normalized();
    ++stopped;
  }
  return stopped;
}

}  // namespace RTP_CONTACT_ISA_NAMESPACE
}  // namespace rtp
