// The seed's contact solver, lab 5 as it is written: one contact at a time, in double, nothing
// carried from step to step (docs/solver.md, "The three solvers"; the `seed` variant keeps this
// weakness so it can be measured).
#include <algorithm>
#include <cmath>
#include <vector>

#include "contacts.h"

namespace rtp {
inline namespace RTP_CONTACT_ISA_NAMESPACE {

void ContactPipeline::solve_seed(double dt) {
  // The seed's lab 5 as it is written: each iteration applies at every penetrating point the
  // impulse magnitude j = (−(1 + e) v_n + β/dt · max(depth − slop, 0)) / (n·K n) when it is
  // positive (Hecker, "Physics, Part 3: Collision Response", 1997; the penetration "penalty"
  // impulse), and a friction impulse against the sliding velocity up to μ j. Nothing
  // accumulates and nothing is carried to the next step: this is the weakness the seed admits.
  const double penalty_rate = settings_.baumgarte / dt;
  // a pair has converged when no impulse of an iteration changes a velocity by 10 µm/s
  const double converged_velocity = 1e-5;
  std::vector<bool>& converged = seed_converged_;
  converged.assign(contacts_.size(), false);
  for (int iteration = 0; iteration < settings_.velocity_iterations; ++iteration) {
    bool any = false;
    for (std::uint32_t index : colour_order_) {
      if (converged[index]) continue;
      const ContactConstraint& c = contacts_[index];
      const SolverMass& mass_a = masses_[c.body_a];
      const SolverMass& mass_b = masses_[c.body_b];
      // the pair's velocities in double while its points are solved
      Vec3 va = bodies_[c.body_a].linear_velocity.cast<double>();
      Vec3 wa = bodies_[c.body_a].angular_velocity.cast<double>();
      Vec3 vb = bodies_[c.body_b].linear_velocity.cast<double>();
      Vec3 wb = bodies_[c.body_b].angular_velocity.cast<double>();
      // the contact's numbers in double too (they are kept in single precision)
      const Vec3 normal = c.normal.cast<double>();
      const Vec3 tangent[2] = {c.tangent[0].cast<double>(), c.tangent[1].cast<double>()};
      Vec3 ra, rb;  // the point's anchors
      auto velocity = [&](const Vec3& d) {
        return d.dot((vb + wb.cross(rb)) - (va + wa.cross(ra)));
      };
      auto apply = [&](const Vec3& impulse) {
        va -= mass_a.inverse_mass * impulse;
        wa -= mass_a.inverse_inertia * ra.cross(impulse);
        vb += mass_b.inverse_mass * impulse;
        wb += mass_b.inverse_inertia * rb.cross(impulse);
      };
      double largest_change = 0.0;
      for (std::uint8_t i = 0; i < c.count; ++i) {
        const ContactPointConstraint& p = c.points[i];
        const double depth = -p.base_separation;
        // the seed's narrow phase reports touching shapes only: no speculative points
        if (depth < 0.0) continue;
        ra = p.anchor_a.cast<double>();
        rb = p.anchor_b.cast<double>();
        const double normal_mass = effective_mass(ra, rb, normal, mass_a, mass_b);
        const double vn = velocity(normal);
        const double j =
            normal_mass * (-(1.0 + c.restitution) * vn +
                           penalty_rate * std::max(depth - settings_.linear_slop, 0.0));
        if (j <= 0.0) continue;
        apply(j * normal);
        largest_change = std::max(largest_change, j / std::max(normal_mass, 1e-300));
        // friction against the sliding velocity, at most μ j
        const double v0 = velocity(tangent[0]);
        const double v1 = velocity(tangent[1]);
        const double speed = std::sqrt(v0 * v0 + v1 * v1);
        if (speed > 0.0) {
          const Vec3 direction = (v0 * tangent[0] + v1 * tangent[1]) / speed;
          const double mass = effective_mass(ra, rb, direction, mass_a, mass_b);
          apply(-std::min(speed * mass, double(c.friction) * j) * direction);
        }
      }
      if (mass_a.inverse_mass > 0.0) {
        bodies_[c.body_a].linear_velocity = va.cast<float>();
        bodies_[c.body_a].angular_velocity = wa.cast<float>();
      }
      if (mass_b.inverse_mass > 0.0) {
        bodies_[c.body_b].linear_velocity = vb.cast<float>();
        bodies_[c.body_b].angular_velocity = wb.cast<float>();
      }
      if (largest_change < converged_velocity) converged[index] = true;
      any = true;
    }
    if (!any) break;
  }
}

}  // namespace RTP_CONTACT_ISA_NAMESPACE
}  // namespace rtp
