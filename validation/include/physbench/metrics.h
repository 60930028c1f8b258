// Accuracy metrics: a trajectory against a reference, and the invariants a scene keeps.
//
// Definitions (docs/metrics.md):
//   position error      |x − x_ref| of the worst probed body (m)
//   orientation error   angle of q_ref⁻¹ q of the worst probed body (rad)
//   energy change       (E(t) − E(0)) / (KE(0) + spring PE(0)), signed; energy drift is its size
//                       E = kinetic + gravitational + spring potential
//   linear momentum     |P(t) − P(0)| (kg m/s)
//   angular momentum    |L(t) − L(0)| / |L(0)| about the world origin (absolute when L(0) = 0)
// and the contact metrics (contact_summary below), all from the sampled poses.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "physbench/scene.h"
#include "physbench/simulate.h"

namespace physbench {

struct ErrorSeries {
  std::vector<double> time;
  // one entry per sample; empty when the scene does not ask for the metric
  std::vector<double> position_error, orientation_error, energy_change, linear_momentum_drift,
      angular_momentum_drift;
  // contact scenes: the largest horizontal displacement of any probed dynamic body from its
  // start (m), and the deepest overlap of any two bodies' true shapes by rtp's narrow phase (m)
  std::vector<double> stack_drift, penetration;
};

struct SeriesSummary {
  double rms = 0.0, max = 0.0, final = 0.0;
};

struct ErrorSummary {
  std::optional<SeriesSummary> position, orientation, energy, linear_momentum, angular_momentum,
      stack_drift, penetration;
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

// ---- contact scenes (docs/metrics.md, "Contact") ----

// the verdict's thresholds
inline constexpr double kStandsWithin = 0.01;  // m: drift and top-height change of a stack that stands
inline constexpr double kCollapsedBeyond = 0.5;  // m: drift, or top drop past the sinking, of a
                                                 // collapsed stack
inline constexpr double kToppledBeyond = 0.5;  // rad: a collapsed stack where a body turned this far
                                               // toppled; one where none did slid
inline constexpr double kSinksBeyond = 0.02;     // m: final penetration of a stack that sinks
inline constexpr double kMovedBeyond = 0.01;     // m: an incline block that moved
inline constexpr double kApexFloor = 0.02;       // m: closed-form apexes below this are not judged
inline constexpr int kMaxApexes = 5;  // judged at most (e < 1); at e = 1 every one the run holds
inline constexpr double kElasticApexWithin = 0.02;  // e = 1: every apex within this of h0
inline constexpr double kRollsWithin = 0.01;  // rolling: final speed, and slip, within this share
inline constexpr double kElasticWithin = 0.01;  // elastic: energy kept within this share
// An energy guard (every engine, every scene whose energy can only fall: docs/metrics.md):
// mechanical energy that rises above its start by more than this share of the scene's energy
// scale reads `diverged`
inline constexpr double kEnergyGainTolerance = 0.05;
inline constexpr double kTumbledBeyond = 0.1;  // rad: a dropped box that turned this far tumbled
inline constexpr double kRestlessBeyond = 0.05;  // m/s: a pile's RMS speed, last second, not at rest

// Everything a contact scene's question asks for, from the sampled poses. A value that cannot be
// computed stays empty (nullopt), never zero.
struct ContactSummary {
  // stack_drift
  std::optional<double> top_height_change;
  // planar scenes: the largest drift of any probed body along the plane's horizontal (x), and out
  // of the plane (z), over the run (m)
  std::optional<double> drift_in_plane, drift_out_of_plane;  // the initially highest body, final − start along up (m)
  std::optional<double> speed_max;          // fastest probed body at any sample (m/s)
  std::optional<double> rest_speed_rms;     // RMS speed of all probed bodies over the last second (m/s)
  // energy (absolute: a resting stack has no energy in play to divide by)
  std::optional<double> energy_added_max;  // max over time of E(t) − E(0), at least 0 (J)
  // bounce_apex: (measured − e^(2n) h0) / (e^(2n) h0) for each judged apex; −1: no such apex
  std::vector<double> apex_relative_errors;
  std::optional<double> apex_relative_error_max;  // of the absolute values
  // incline: along the slope, downhill positive
  std::optional<double> slide_distance;                // final displacement (m)
  std::optional<double> slide_acceleration;            // least-squares fit s = c0 + c1 t + a t²/2
  std::optional<double> slide_acceleration_expected;   // g (sin θ − μ cos θ), or 0 when tan θ ≤ μ
  std::optional<double> slide_acceleration_error;      // relative, when the closed form slides
  // exchange: max over both bodies |v(T) − v_closed_form| / |approach speed|
  std::optional<double> exchange_error;
  // rolling: the final speed against the closed form's rolling speed, (v − v_roll) / v_roll, and
  // the time the slip stopped against the closed form's, (t − t_roll) / t_roll (when it slides)
  std::optional<double> roll_speed_error, roll_time_error;
  // elastic: which classical answer a row of touching equal spheres, one struck, ended in:
  // "sequential" (the last ball leaves at the striker's speed), "simultaneous" (the row leaves as
  // one, the striker rebounds), "other"; empty where the scene is not such a row
  std::string cradle_answer;
  // tunnelling: the body ended wholly beyond the wall's far face
  std::optional<bool> tunnelled;
  // confined: probed bodies whose centre ends outside the container (beyond a wall's inner face
  // or above the rim)
  std::optional<long> escaped;
  // stands, settles, drifts, sinks, collapsed, tumbled, no bounce, stays, slides, "slides, should
  // stay", "stays, should slide", tunnelled, stopped, stuck, contained, escaped, unsettled, ""
  // (no verdict)
  std::string verdict;
  std::string message;  // why, for any verdict that is a failure of the scene's question
};

ContactSummary contact_summary(const Scene& scene, const Trajectory& run,
                               const ErrorSeries& series);

// A container of static world-aligned boxes (walls) on a floor, as the confined metric reads it:
// along each horizontal world axis the inside runs between the inner faces of the walls wholly on
// either side of the walls' mean centre (unbounded where there is none), and up to the rim, the
// highest wall top along −g.
struct Container {
  int up_axis = 1;       // the world axis along gravity
  double up_sign = 1.0;  // +1 when up is +axis
  Vec3 low, high;        // the inside along the horizontal axes (the up entries unused)
  double rim = 0.0;      // the highest wall top, as up_sign · coordinate
  bool holds(const Vec3& centre) const;
};
Container container_of(const Scene& scene);

// The energy guard's terms: whether the scene's mechanical energy can only fall (restitution at
// most 1, no scheduled impulses, no particles, no bodies started overlapping), and its energy
// scale: the kinetic and spring energy at the start plus, for each dynamic body, its weight
// times the height of its centre above the scene's lowest point and its own reach (J)
bool energy_can_only_fall(const Scene& scene, const ErrorSeries& series);
double energy_scale(const Scene& scene);

// the mechanical energy (J) of a sample's probed bodies (kinetic, linear and about the centre of
// mass, plus gravitational −m g·x) and of the springs whose moving ends are probed; probed particles
// are left out. What the report's energy chart draws, as E(t) − E(0)
double body_energy(const Scene& scene, const std::vector<int>& bodies, const Sample& sample);

// whether a verdict is a failure the row's message must name (collapsed, sinks, tunnelled, …)
bool verdict_is_failure(const std::string& verdict);

// the scene as the converged reference runs it: dt / divisor
Scene refined(const Scene& scene, int divisor);

double orientation_angle(const Quat& a, const Quat& b);

}  // namespace physbench
