// Accuracy metrics: a trajectory against a reference, and the invariants a scene keeps.
//
// Definitions (docs/metrics.md):
//   position error      |x − x_ref| of the worst probed body (m)
//   orientation error   angle of q_ref⁻¹ q of the worst probed body (rad)
//   energy change       (E(t) − E(0)) / (KE(0) + spring PE(0)), signed; energy drift is its size
//                       E = kinetic + gravitational + spring potential
//   linear momentum     |P(t) − P(0)| (kg m/s)
//   angular momentum    |L(t) − L(0)| / |L(0)| about the world origin (absolute when L(0) = 0)
#pragma once

#include <optional>
#include <vector>

#include "physbench/scene.h"
#include "physbench/simulate.h"

namespace physbench {

struct ErrorSeries {
  std::vector<double> time;
  // one entry per sample; empty when the scene does not ask for the metric
  std::vector<double> position_error, orientation_error, energy_change, linear_momentum_drift,
      angular_momentum_drift;
};

struct SeriesSummary {
  double rms = 0.0, max = 0.0, final = 0.0;
};

struct ErrorSummary {
  std::optional<SeriesSummary> position, orientation, energy, linear_momentum, angular_momentum;
  std::optional<double> energy_change_final;  // signed: > 0 gained, < 0 lost
};

// How a conservative scene behaves, from its energy in play e(t) = 1 + energy change:
// "unstable" when the second half of the run peaks more than twice as high as the first (the
// energy grows) or e ever exceeds 20 (bounded only by something like a velocity clamp),
// "over-damped" when the second half stays under half the start although nothing dissipates, else
// "stable" (a symplectic method's bounded wobble is stable). "" when the scene has damping or no
// energy metric.
std::string stability_of(const Scene& scene, const ErrorSeries& series);

// reference may be null when the scene asks only for invariants; samples are matched by index
// and must share their times
ErrorSeries compare(const Scene& scene, const Trajectory& run, const Trajectory* reference);
ErrorSummary summarise(const ErrorSeries& series);

// the closed-form free-flight trajectory of every probed body's centre of mass
Trajectory ballistic_reference(const Scene& scene, const Trajectory& sampled_at);

// the closed-form motion of one body on one damped spring to a world anchor, along the spring:
// m s'' = −k (s − L₀) − c s' + m g·u, under-, critically or over-damped
Trajectory oscillator_reference(const Scene& scene, const Trajectory& sampled_at);

// ballistic or oscillator, whichever the scene names; throws for the other kinds
Trajectory analytic_reference(const Scene& scene, const Trajectory& sampled_at);
bool has_analytic_reference(const Scene& scene);

// the scene as the converged reference runs it: dt / divisor
Scene refined(const Scene& scene, int divisor);

double orientation_angle(const Quat& a, const Quat& b);

}  // namespace physbench
