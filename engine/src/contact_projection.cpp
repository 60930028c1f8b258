// Overlap recovery by poses (ContactPipeline::project_overlaps; docs/solver.md, "Not while
// recovering"). Bodies spawned deep into one another are pushed apart by the soft step at most
// max_push_speed, so a 0.4 m overlap takes a dozen steps, and the relax passes that take the
// push's speed back let the weight above press some contacts deeper on the way. In a step
// recovering from such an overlap, a few Gauss–Seidel passes over the contacts' points first move
// the bodies apart by their poses alone, as a position solver does (Catto's nonlinear
// Gauss–Seidel in Box2D v2): each point by a share of its overlap beyond what the push-out
// removes in the step, no velocity changed, so no energy but the separation's potential energy
// is added. The rest, within the push-out's reach, is the soft step's as before.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "contacts.h"

namespace rtp {
inline namespace RTP_CONTACT_ISA_NAMESPACE {

namespace {
// a pass moves a point by this share of its overlap beyond the push-out's reach, and by at most
// kMostAPass (m): the values position solvers use (Box2D v2's Baumgarte share and largest
// correction), so a pile of boxes is taken apart over a few steps, not thrown in one
constexpr double kShare = 0.2;
constexpr double kMostAPass = 0.2;
}  // namespace

void ContactPipeline::project_overlaps(std::span<BodyState> states, double depth, int passes) {
  if (passes <= 0 || contacts_.empty()) return;
  // each body's move so far: a translation and a small rotation (its vector, rad), world
  std::vector<Vec3>& shift = projection_shift_;
  std::vector<Vec3>& turn = projection_turn_;
  shift.assign(states.size(), Vec3::Zero());
  turn.assign(states.size(), Vec3::Zero());
  // a point's separation after its bodies' moves, to first order in the rotations (its anchors
  // are from each centre of mass, world, at the step's start)
  auto separation = [&](const ContactConstraint& c, const ContactPointConstraint& p) {
    const Vec3 n = c.normal.cast<double>();
    const Vec3 on_a = shift[c.body_a] + turn[c.body_a].cross(p.anchor_a.cast<double>());
    const Vec3 on_b = shift[c.body_b] + turn[c.body_b].cross(p.anchor_b.cast<double>());
    return double(p.base_separation) + n.dot(on_b - on_a);
  };
  // in the contacts' order, on the calling thread: the same poses at any thread count. A contact
  // neither of whose bodies has moved keeps its separations, so after the first pass only the
  // contacts of moved bodies are visited (a large world with one deep overlap pays for that one)
  std::vector<std::uint8_t>& moved = projection_moved_;
  std::vector<std::uint32_t>& visit = projection_visit_;
  moved.assign(states.size(), 0);
  visit.resize(contacts_.size());
  for (std::size_t i = 0; i < visit.size(); ++i) visit[i] = std::uint32_t(i);
  for (int pass = 0; pass < passes; ++pass) {
    if (pass > 0)
      visit.erase(std::remove_if(visit.begin(), visit.end(),
                                 [&](std::uint32_t i) {
                                   return !moved[contacts_[i].body_a] && !moved[contacts_[i].body_b];
                                 }),
                  visit.end());
    for (const std::uint32_t i : visit) {
      const ContactConstraint& c = contacts_[i];
      const SolverMass& a = masses_[c.body_a];
      const SolverMass& b = masses_[c.body_b];
      const Vec3 n = c.normal.cast<double>();
      for (std::uint8_t j = 0; j < c.count; ++j) {
        const ContactPointConstraint& p = c.points[j];
        const double beyond = separation(c, p) + depth;  // < 0: deeper than the push-out reaches
        if (beyond >= 0.0) continue;
        const Vec3 arm_a = p.anchor_a.cast<double>().cross(n);
        const Vec3 arm_b = p.anchor_b.cast<double>().cross(n);
        const Vec3 spin_a = a.inverse_inertia * arm_a, spin_b = b.inverse_inertia * arm_b;
        // the separation's change per unit of the move along the normal (the point's inverse
        // effective mass, 1/kg: effective_mass()'s sum, written out since the move needs the
        // arms' spins too)
        const double k = a.inverse_mass + b.inverse_mass + arm_a.dot(spin_a) + arm_b.dot(spin_b);
        if (!(k > 0.0)) continue;
        const double move = std::min(kShare * -beyond, kMostAPass) / k;  // kg m
        shift[c.body_a] -= a.inverse_mass * move * n;
        turn[c.body_a] -= move * spin_a;
        shift[c.body_b] += b.inverse_mass * move * n;
        turn[c.body_b] += move * spin_b;
        // (a static body has no inverse mass nor inertia: it never moves)
        if (a.inverse_mass > 0.0 || !spin_a.isZero()) moved[c.body_a] = 1;
        if (b.inverse_mass > 0.0 || !spin_b.isZero()) moved[c.body_b] = 1;
      }
    }
  }
  // every point's separation as its bodies moved (the solve pushes out the rest), then the
  // poses; the deepest overlap stays the narrow phase's (the step's start, as the world reports)
  for (ContactConstraint& c : contacts_)
    if (moved[c.body_a] || moved[c.body_b])
      for (std::uint8_t j = 0; j < c.count; ++j)
        c.points[j].base_separation = float(separation(c, c.points[j]));
  for (std::size_t i = 0; i < states.size(); ++i) {
    if (!moved[i] || masses_[i].inverse_mass == 0.0) continue;
    states[i].position += shift[i];
    const double angle = turn[i].norm();
    if (angle > 0.0)
      states[i].orientation =
          (Quat(Eigen::AngleAxisd(angle, turn[i] / angle)) * states[i].orientation).normalized();
  }
}

}  // namespace RTP_CONTACT_ISA_NAMESPACE
}  // namespace rtp
