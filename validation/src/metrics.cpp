// Accuracy metrics and the contact scenes' judges (metrics.h defines them). Over 800 lines because
// every judge reads the trajectories through the same few private helpers (the body on its plane,
// support extents, slots); docs/metrics.md is their reference.
#include "physbench/metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>
#include <stdexcept>

#include "physbench/overlaps.h"

namespace physbench {

namespace {

struct Invariants {
  double energy = 0.0, kinetic = 0.0, spring_potential = 0.0;
  Vec3 linear_momentum = Vec3::Zero(), angular_momentum = Vec3::Zero();
};

Invariants invariants_of(const Scene& scene, const std::vector<int>& bodies, const Sample& sample) {
  Invariants inv;
  std::vector<const SampledState*> state_of(scene.bodies.size(), nullptr);
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    const SampledState& s = sample.bodies[i];
    if (bodies[i] >= static_cast<int>(scene.bodies.size())) {
      // a probed particle: a point mass in gravity and the attractors' softened potential
      const ParticleSetSpec& p = *scene.particles;
      const double kinetic = 0.5 * p.mass * s.linear_velocity.squaredNorm();
      double potential = -p.mass * scene.gravity.dot(s.position);
      for (const ParticleAttractor& a : p.attractors)
        potential -= p.mass * a.strength /
                     std::sqrt((a.position - s.position).squaredNorm() + p.softening * p.softening);
      inv.kinetic += kinetic;
      inv.energy += kinetic + potential;
      inv.linear_momentum += p.mass * s.linear_velocity;
      inv.angular_momentum += s.position.cross(p.mass * s.linear_velocity);
      continue;
    }
    const BodySpec& spec = scene.bodies[bodies[i]];
    state_of[bodies[i]] = &s;
    if (spec.mass == 0.0) continue;
    const Mat3 rotation = s.orientation.normalized().toRotationMatrix();
    const Mat3 inertia_world =
        rotation * principal_inertia(spec.shape, spec.mass).asDiagonal() * rotation.transpose();
    const Vec3 spin_momentum = inertia_world * s.angular_velocity;
    const double kinetic = 0.5 * spec.mass * s.linear_velocity.squaredNorm() +
                           0.5 * s.angular_velocity.dot(spin_momentum);
    inv.kinetic += kinetic;
    inv.energy += kinetic - spec.mass * scene.gravity.dot(s.position);
    inv.linear_momentum += spec.mass * s.linear_velocity;
    inv.angular_momentum += spin_momentum + s.position.cross(spec.mass * s.linear_velocity);
  }
  // spring potential, for springs whose moving ends are all probed
  for (const SpringSpec& spring : scene.springs) {
    const SampledState* a = state_of[spring.body_a];
    if (!a) continue;
    const Vec3 pa = a->position + a->orientation * spring.local_point_a;
    Vec3 pb = spring.point_b;
    if (spring.body_b >= 0) {
      const SampledState* b = state_of[spring.body_b];
      if (!b) continue;
      pb = b->position + b->orientation * spring.point_b;
    }
    const double extension = (pa - pb).norm() - spring.rest_length;
    inv.spring_potential += 0.5 * spring.stiffness * extension * extension;
    inv.energy += 0.5 * spring.stiffness * extension * extension;
  }
  return inv;
}

}  // namespace

double body_energy(const Scene& scene, const std::vector<int>& bodies, const Sample& sample) {
  std::vector<int> rigid;
  Sample only;
  only.time = sample.time;
  for (std::size_t i = 0; i < bodies.size() && i < sample.bodies.size(); ++i)
    if (bodies[i] < static_cast<int>(scene.bodies.size())) {
      rigid.push_back(bodies[i]);
      only.bodies.push_back(sample.bodies[i]);
    }
  return invariants_of(scene, rigid, only).energy;
}

namespace {

bool wants(const Scene& scene, Metric metric) {
  for (Metric m : scene.probe.metrics)
    if (m == metric) return true;
  return false;
}

SeriesSummary summary_of(const std::vector<double>& values) {
  SeriesSummary s;
  double squares = 0.0;
  for (double v : values) {
    squares += v * v;
    s.max = std::max(s.max, v);
    if (std::isnan(v)) s.max = v;
  }
  s.rms = std::sqrt(squares / static_cast<double>(values.size()));
  s.final = values.back();
  return s;
}

// the world's up: against gravity, or y without gravity
Vec3 up_of(const Scene& scene) {
  return scene.gravity.norm() > 0.0 ? Vec3(-scene.gravity.normalized()) : Vec3::UnitY();
}

}  // namespace

double orientation_angle(const Quat& a, const Quat& b) {
  const Quat relative = a.normalized().conjugate() * b.normalized();
  // robust near zero, unlike 2 acos(w); |w| takes the shorter of q and −q
  return 2.0 * std::atan2(relative.vec().norm(), std::abs(relative.w()));
}

ErrorSeries compare(const Scene& scene, const Trajectory& run, const Trajectory* reference) {
  const bool position = wants(scene, Metric::Position);
  const bool orientation = wants(scene, Metric::Orientation);
  if ((position || orientation) && !reference)
    throw std::invalid_argument("compare: the scene needs a reference");
  if (reference && reference->samples.size() < run.samples.size())
    throw std::invalid_argument("compare: the reference has fewer samples than the run");

  ErrorSeries series;
  if (run.samples.empty()) return series;
  const Invariants initial = invariants_of(scene, run.bodies, run.samples.front());
  // the energy in play: kinetic plus spring, not the gravitational part, whose zero is arbitrary
  const double in_play = initial.kinetic + initial.spring_potential;
  const double energy_scale = in_play > 0.0 ? in_play : 1.0;
  const double angular_scale =
      initial.angular_momentum.norm() > 0.0 ? initial.angular_momentum.norm() : 1.0;

  const bool drift = wants(scene, Metric::StackDrift);
  std::optional<OverlapGauge> gauge;
  if (wants(scene, Metric::Penetration)) gauge.emplace(scene, run.bodies);
  const Vec3 up = up_of(scene);

  for (std::size_t k = 0; k < run.samples.size(); ++k) {
    const Sample& s = run.samples[k];
    series.time.push_back(s.time);
    if (drift) {
      double widest = 0.0;
      for (std::size_t b = 0; b < s.bodies.size(); ++b) {
        const Vec3 moved = s.bodies[b].position - run.samples.front().bodies[b].position;
        widest = std::max(widest, (moved - moved.dot(up) * up).norm());
        if (!std::isfinite(moved.squaredNorm())) widest = std::nan("");
      }
      series.stack_drift.push_back(widest);
    }
    if (gauge) series.penetration.push_back(gauge->deepest(s));
    if (position || orientation) {
      const Sample& r = reference->samples[k];
      if (std::abs(r.time - s.time) > 1e-9 * std::max(1.0, s.time))
        throw std::invalid_argument("compare: sample times differ from the reference's");
      double worst_position = 0.0, worst_orientation = 0.0;
      for (std::size_t b = 0; b < s.bodies.size(); ++b) {
        worst_position =
            std::max(worst_position, (s.bodies[b].position - r.bodies[b].position).norm());
        worst_orientation = std::max(
            worst_orientation, orientation_angle(r.bodies[b].orientation, s.bodies[b].orientation));
      }
      if (position) series.position_error.push_back(worst_position);
      if (orientation) series.orientation_error.push_back(worst_orientation);
    }
    const Invariants now = invariants_of(scene, run.bodies, s);
    if (wants(scene, Metric::Energy))
      series.energy_change.push_back((now.energy - initial.energy) / energy_scale);
    if (wants(scene, Metric::LinearMomentum))
      series.linear_momentum_drift.push_back(
          (now.linear_momentum - initial.linear_momentum).norm());
    if (wants(scene, Metric::AngularMomentum))
      series.angular_momentum_drift.push_back(
          (now.angular_momentum - initial.angular_momentum).norm() / angular_scale);
  }
  return series;
}

ErrorSummary summarise(const ErrorSeries& series) {
  ErrorSummary summary;
  if (!series.position_error.empty()) summary.position = summary_of(series.position_error);
  if (!series.orientation_error.empty()) summary.orientation = summary_of(series.orientation_error);
  if (!series.energy_change.empty()) {
    std::vector<double> drift;
    for (double change : series.energy_change) drift.push_back(std::abs(change));
    summary.energy = summary_of(drift);
    summary.energy_change_final = series.energy_change.back();
  }
  if (!series.linear_momentum_drift.empty())
    summary.linear_momentum = summary_of(series.linear_momentum_drift);
  if (!series.angular_momentum_drift.empty())
    summary.angular_momentum = summary_of(series.angular_momentum_drift);
  if (!series.stack_drift.empty()) summary.stack_drift = summary_of(series.stack_drift);
  if (!series.penetration.empty()) summary.penetration = summary_of(series.penetration);
  return summary;
}

namespace {

// The torque-free symmetric top in closed form (Goldstein, Classical Mechanics, §5.6; Landau &
// Lifshitz, Mechanics, §33): the angular momentum L is fixed in space, and the body turns about
// L at φ' = |L| / I⊥ while spinning about its own symmetry axis e₃ at ψ' = ω₃ (I⊥ − I₃) / I⊥:
//   R(t) = Rot(L̂, φ' t) · R(0) · Rot(e₃, ψ' t)
// which gives ω = φ' L̂ + ψ' R e₃ = I_world⁻¹ L at every t. Returns R(t) and ω(t).
Quat torque_free_top(const BodySpec& b, int axis, double t, Vec3& angular_velocity) {
  const Vec3 inertia = principal_inertia(b.shape, b.mass);
  const double perpendicular = inertia[(axis + 1) % 3], along = inertia[axis];
  const Mat3 rotation = b.orientation.toRotationMatrix();
  const Vec3 momentum = rotation * inertia.asDiagonal() * rotation.transpose() * b.angular_velocity;
  const Vec3 e3 = Vec3::Unit(axis);
  const double spin = (b.orientation.conjugate() * b.angular_velocity)[axis];  // ω₃, constant
  const double precession = momentum.norm() / perpendicular;
  const double body_spin = spin * (perpendicular - along) / perpendicular;
  const Vec3 axis_of_momentum = momentum.norm() > 0.0 ? Vec3(momentum.normalized()) : Vec3::UnitX();
  const Quat q = (Quat(Eigen::AngleAxisd(precession * t, axis_of_momentum)) * b.orientation *
                  Quat(Eigen::AngleAxisd(body_spin * t, e3)))
                     .normalized();
  angular_velocity = precession * axis_of_momentum + body_spin * (q * e3);
  return q;
}

}  // namespace

Trajectory ballistic_reference(const Scene& scene, const Trajectory& sampled_at) {
  Trajectory reference;
  reference.bodies = sampled_at.bodies;
  for (const Sample& at : sampled_at.samples) {
    Sample s;
    s.time = at.time;
    for (int index : sampled_at.bodies) {
      const BodySpec& b = scene.bodies[index];
      SampledState state;
      if (b.mass > 0.0) {
        state.position =
            b.position + b.linear_velocity * at.time + 0.5 * scene.gravity * at.time * at.time;
        state.linear_velocity = b.linear_velocity + scene.gravity * at.time;
      } else {
        state.position = b.position;
      }
      state.orientation = b.orientation;
      if (b.mass > 0.0)
        if (const auto axis = symmetry_axis(principal_inertia(b.shape, b.mass)))
          state.orientation = torque_free_top(b, *axis, at.time, state.angular_velocity);
      s.bodies.push_back(state);
    }
    reference.samples.push_back(std::move(s));
  }
  return reference;
}

Trajectory oscillator_reference(const Scene& scene, const Trajectory& sampled_at) {
  const SpringSpec& spring = scene.springs.at(0);
  const int index = spring.body_a;
  const BodySpec& b = scene.bodies[index];
  const Vec3 u = (b.position - spring.point_b).normalized();
  const double m = b.mass, k = spring.stiffness, c = spring.damping;
  // y = s − s*, with s* the equilibrium length under gravity
  const double equilibrium = spring.rest_length + m * scene.gravity.dot(u) / k;
  const double y0 = (b.position - spring.point_b).norm() - equilibrium;
  const double v0 = b.linear_velocity.dot(u);
  const double omega0 = std::sqrt(k / m), zeta = c / (2.0 * std::sqrt(k * m));

  // y(t) and y'(t) for the three damping regimes
  auto solve = [&](double t, double& y, double& v) {
    if (zeta < 1.0 - 1e-9) {
      const double wd = omega0 * std::sqrt(1.0 - zeta * zeta), decay = std::exp(-zeta * omega0 * t);
      const double A = y0, B = (v0 + zeta * omega0 * y0) / wd;
      y = decay * (A * std::cos(wd * t) + B * std::sin(wd * t));
      v = decay * ((-A * wd + B * -zeta * omega0) * std::sin(wd * t) +
                   (B * wd - zeta * omega0 * A) * std::cos(wd * t));
    } else if (zeta > 1.0 + 1e-9) {
      const double root = omega0 * std::sqrt(zeta * zeta - 1.0);
      const double r1 = -zeta * omega0 + root, r2 = -zeta * omega0 - root;
      const double A = (v0 - r2 * y0) / (r1 - r2), B = y0 - A;
      y = A * std::exp(r1 * t) + B * std::exp(r2 * t);
      v = A * r1 * std::exp(r1 * t) + B * r2 * std::exp(r2 * t);
    } else {
      const double A = y0, B = v0 + omega0 * y0, decay = std::exp(-omega0 * t);
      y = (A + B * t) * decay;
      v = (B - omega0 * (A + B * t)) * decay;
    }
  };

  Trajectory reference;
  reference.bodies = sampled_at.bodies;
  for (const Sample& at : sampled_at.samples) {
    double y = 0.0, v = 0.0;
    solve(at.time, y, v);
    Sample s;
    s.time = at.time;
    SampledState state;
    state.position = spring.point_b + (equilibrium + y) * u;
    state.linear_velocity = v * u;
    state.orientation = b.orientation;  // not part of the closed form
    s.bodies.push_back(state);
    reference.samples.push_back(std::move(s));
  }
  return reference;
}

Trajectory orbit_reference(const Scene& scene, const Trajectory& sampled_at) {
  // a circular orbit: the start turns about r × v at ω = √(s / r³) (softening ε ≪ r neglected)
  const ParticleSetSpec& p = *scene.particles;
  const Vec3 centre = p.attractors[0].position;
  const Vec3 r0 = p.spawn_min - centre, v0 = p.velocity_min;
  const double omega = std::sqrt(p.attractors[0].strength / std::pow(r0.norm(), 3));
  const Vec3 axis = r0.cross(v0).normalized();
  Trajectory reference;
  reference.bodies = sampled_at.bodies;
  for (const Sample& at : sampled_at.samples) {
    const Eigen::AngleAxisd turn(omega * at.time, axis);
    Sample s;
    s.time = at.time;
    s.bodies.push_back({centre + turn * r0, Quat::Identity(), turn * v0, Vec3::Zero()});
    reference.samples.push_back(std::move(s));
  }
  return reference;
}

Trajectory bounce_reference(const Scene& scene, const Trajectory& sampled_at) {
  // a drop from height h onto the plane: parabolic flights between impacts, each leaving at e
  // times the speed it arrived with, so the n-th apex is e^(2n) h
  const ParticleSetSpec& p = *scene.particles;
  const Vec3 n = p.planes[0].normal;
  const double g = scene.gravity.norm(), e = p.restitution;
  const double h = (p.spawn_min - p.planes[0].point).dot(n);
  const Vec3 foot = p.spawn_min - h * n;
  Trajectory reference;
  reference.bodies = sampled_at.bodies;
  for (const Sample& at : sampled_at.samples) {
    // walk the flights to the one holding t: the first falls from rest, later ones rise from the
    // plane
    double t = at.time, height = 0.0, speed = 0.0;
    const double fall = std::sqrt(2.0 * h / g);
    if (t < fall) {
      height = h - 0.5 * g * t * t;
      speed = -g * t;
    } else {
      t -= fall;
      double launch = e * g * fall;  // speed off the plane after the first impact
      while (launch > 1e-9 && t > 2.0 * launch / g) {
        t -= 2.0 * launch / g;
        launch *= e;
      }
      if (launch > 1e-9) {
        height = launch * t - 0.5 * g * t * t;
        speed = launch - g * t;
      }
    }
    Sample s;
    s.time = at.time;
    s.bodies.push_back({foot + height * n, Quat::Identity(), speed * n, Vec3::Zero()});
    reference.samples.push_back(std::move(s));
  }
  return reference;
}

bool has_analytic_reference(const Scene& scene) {
  return scene.reference.kind == ReferenceKind::Bounce ||
         scene.reference.kind == ReferenceKind::Orbit ||
         scene.reference.kind == ReferenceKind::Ballistic ||
         scene.reference.kind == ReferenceKind::Oscillator;
}

Trajectory analytic_reference(const Scene& scene, const Trajectory& sampled_at) {
  if (scene.reference.kind == ReferenceKind::Ballistic)
    return ballistic_reference(scene, sampled_at);
  if (scene.reference.kind == ReferenceKind::Oscillator)
    return oscillator_reference(scene, sampled_at);
  if (scene.reference.kind == ReferenceKind::Orbit) return orbit_reference(scene, sampled_at);
  if (scene.reference.kind == ReferenceKind::Bounce) return bounce_reference(scene, sampled_at);
  throw std::invalid_argument(std::string("no closed form for reference kind ") +
                              to_string(scene.reference.kind));
}

std::string stability_of(const Scene& scene, const ErrorSeries& series) {
  if (series.energy_change.size() < 4) return "";
  // contacts dissipate and correct by design: a contact scene is judged by its verdict instead
  if (scene.has_contacts()) return "";
  for (const SpringSpec& s : scene.springs)
    if (s.damping > 0.0) return "";
  const std::size_t half = series.energy_change.size() / 2;
  double first = 0.0, second = 0.0;
  for (std::size_t k = 0; k < series.energy_change.size(); ++k) {
    const double in_play = 1.0 + series.energy_change[k];
    if (!std::isfinite(in_play)) return "unstable";
    (k < half ? first : second) = std::max(k < half ? first : second, in_play);
  }
  // growing, or ever ten-odd times the energy it started with (bounded only by a clamp, say)
  if (second > 2.0 * first || std::max(first, second) > 20.0) return "unstable";
  if (second < 0.5) return "over-damped";
  return "stable";
}

namespace {

std::string metres(double value) {
  std::ostringstream out;
  out.precision(3);
  out << value << " m";
  return out.str();
}

// the static plane or box bodies of a scene, and its dynamic ones, by scene index
std::vector<int> bodies_where(const Scene& scene, bool dynamic, std::optional<ShapeKind> kind) {
  std::vector<int> found;
  for (int i = 0; i < static_cast<int>(scene.bodies.size()); ++i)
    if ((scene.bodies[i].mass > 0.0) == dynamic && (!kind || scene.bodies[i].shape.kind == *kind))
      found.push_back(i);
  return found;
}

// how far a shape reaches from its centre along a world direction
double support_extent(const BodySpec& b, const Quat& orientation, const Vec3& direction) {
  if (b.shape.kind == ShapeKind::Sphere) return b.shape.radius;
  if (b.shape.kind == ShapeKind::Plane) return 0.0;
  return (orientation.normalized().conjugate() * direction).cwiseAbs().dot(b.shape.half_extents);
}

// where a probed scene body sits in the samples, or -1
int slot_of(const Trajectory& run, int body) {
  const auto at = std::find(run.bodies.begin(), run.bodies.end(), body);
  return at == run.bodies.end() ? -1 : static_cast<int>(at - run.bodies.begin());
}

// the fastest probed body at any sample, and the RMS speed of all of them over the last second
void judge_speeds(const Trajectory& run, ContactSummary& out) {
  double fastest = 0.0, squares = 0.0;
  long counted = 0;
  const double last_second = run.samples.back().time - 1.0;
  for (const Sample& s : run.samples)
    for (const SampledState& b : s.bodies) {
      const double speed = b.linear_velocity.norm();
      fastest = std::max(fastest, speed);
      if (s.time >= last_second - 1e-9) {
        squares += speed * speed;
        ++counted;
      }
    }
  out.speed_max = fastest;
  if (counted > 0 && run.samples.back().time >= 1.0 - 1e-9)
    out.rest_speed_rms = std::sqrt(squares / static_cast<double>(counted));
}

void judge_stack(const Scene& scene, const Trajectory& run, const ErrorSeries& series,
                 ContactSummary& out) {
  const Vec3 up = up_of(scene);
  // the top body: the probed dynamic body that starts highest
  int top = -1;
  for (std::size_t b = 0; b < run.bodies.size(); ++b)
    if (top < 0 || run.samples.front().bodies[b].position.dot(up) >
                       run.samples.front().bodies[std::size_t(top)].position.dot(up))
      top = static_cast<int>(b);
  if (top < 0) return;
  out.top_height_change =
      (run.samples.back().bodies[top].position - run.samples.front().bodies[top].position).dot(up);
  judge_speeds(run, out);
  // a planar scene's drift in its plane (along its horizontal, x) and out of it (z), apart: a 3D
  // engine's stack may lean out of a plane nothing holds it to
  if (scene.planar) {
    double in_plane = 0.0, out_of_plane = 0.0;
    for (const Sample& s : run.samples)
      for (std::size_t b = 0; b < run.bodies.size(); ++b) {
        const Vec3 moved = s.bodies[b].position - run.samples.front().bodies[b].position;
        const Vec3 level = moved - moved.dot(up) * up;
        in_plane = std::max(in_plane, std::abs(level.x()));
        out_of_plane = std::max(out_of_plane, std::abs(level.z()));
      }
    out.drift_in_plane = in_plane;
    out.drift_out_of_plane = out_of_plane;
  }

  double drift = 0.0;
  for (double d : series.stack_drift) drift = std::isnan(d) ? d : std::max(drift, d);
  const double height = *out.top_height_change;
  const double sunk = series.penetration.empty() ? 0.0 : series.penetration.back();
  // a stack started overlapping rises as the overlap is undone: its height is not judged
  const bool started_overlapping =
      !series.penetration.empty() && series.penetration.front() > 1e-3;
  // The top's drop scales with the stack: n contacts under it, each as deep as the deepest at
  // the end, let it sink n times that without a box falling (a 100-row pyramid at 5 mm a contact
  // drops 0.5 m standing); a drop beyond that and half a box fell. Told apart in the message: a
  // collapse where some body turned over 0.5 rad toppled, one where none did slid
  const SampledState& top_start = run.samples.front().bodies[std::size_t(top)];
  const BodySpec& top_body = scene.bodies[std::size_t(run.bodies[std::size_t(top)])];
  double lowest = top_start.position.dot(up);
  for (const SampledState& b : run.samples.front().bodies) lowest = std::min(lowest, b.position.dot(up));
  const double body_height = 2.0 * support_extent(top_body, top_start.orientation, up);
  const double contacts_under = 1.0 + std::round((top_start.position.dot(up) - lowest) / body_height);
  const double sink_allowance = contacts_under * std::max(sunk, 0.0);
  double turned = 0.0;
  for (std::size_t b = 0; b < run.bodies.size(); ++b)
    turned = std::max(turned, orientation_angle(run.samples.front().bodies[b].orientation,
                                                run.samples.back().bodies[b].orientation));
  std::ostringstream why;
  if (!(drift <= kCollapsedBeyond) || height < -(kCollapsedBeyond + sink_allowance)) {
    out.verdict = "collapsed";
    why << "collapsed (" << (turned > kToppledBeyond ? "toppled" : "slid") << "): drift "
        << metres(drift) << ", top height change " << metres(height) << " (collapsed beyond "
        << metres(kCollapsedBeyond) << " of drift, or of drop past what "
        << static_cast<int>(contacts_under) << " contacts at the final depth allow)";
  } else if (sunk > kSinksBeyond) {
    out.verdict = "sinks";
    why << "sinks: final penetration " << metres(sunk) << " (> " << metres(kSinksBeyond) << ")";
  } else if (drift > kStandsWithin) {
    out.verdict = "drifts";
    why << "drifts: drift " << metres(drift) << ", top height change " << metres(height)
        << " (stands within " << metres(kStandsWithin) << ")";
  } else if (std::abs(height) > kStandsWithin && !started_overlapping) {
    out.verdict = "settles";
    why << "settles: top height change " << metres(height) << " (stands within "
        << metres(kStandsWithin) << "), drift " << metres(drift);
  } else {
    out.verdict = "stands";
  }
  out.message = why.str();
}

// the one dynamic body of a scene on its one plane, as the bounce and slope judges read them
struct BodyOnPlane {
  const BodySpec& body;
  const BodySpec& plane;
  int slot;  // the body's place in the trajectory's samples
  Vec3 n;    // the plane's normal
};

std::optional<BodyOnPlane> body_on_plane(const Scene& scene, const Trajectory& run) {
  const int body = bodies_where(scene, true, std::nullopt).at(0);
  const int plane = bodies_where(scene, false, ShapeKind::Plane).at(0);
  const int slot = slot_of(run, body);
  if (slot < 0) return std::nullopt;
  return BodyOnPlane{scene.bodies[body], scene.bodies[plane], slot,
                     scene.bodies[plane].orientation * Vec3::UnitY()};
}

void judge_bounce(const Scene& scene, const Trajectory& run, ContactSummary& out) {
  const auto found = body_on_plane(scene, run);
  if (!found) return;
  const auto& [b, plane, slot, n] = *found;
  const double g = -scene.gravity.dot(n);
  auto clearance = [&](const SampledState& s) {
    return (s.position - plane.position).dot(n) - support_extent(b, s.orientation, n);
  };
  const double h0 = clearance(run.samples.front().bodies[std::size_t(slot)]);
  const double e = pair_restitution(b, plane);
  // apexes: where the normal speed turns from rising to falling, each estimated from both
  // neighbouring samples as clearance + v²/2g (exact between samples of a ballistic flight)
  std::vector<double> apexes;
  for (std::size_t k = 0; k + 1 < run.samples.size(); ++k) {
    const SampledState& now = run.samples[k].bodies[std::size_t(slot)];
    const SampledState& next = run.samples[k + 1].bodies[std::size_t(slot)];
    const double v0 = now.linear_velocity.dot(n), v1 = next.linear_velocity.dot(n);
    if (!(v0 > 0.0 && v1 <= 0.0)) continue;
    const double apex = 0.5 * (clearance(now) + v0 * v0 / (2.0 * g) + clearance(next) +
                               v1 * v1 / (2.0 * g));
    if (apex > 1e-3) apexes.push_back(apex);  // a rise under 1 mm is contact jitter, not flight
  }
  // the closed form's apexes inside the run: the first 5 where they decay, every one at e = 1
  // (the question is then whether the bounce keeps its energy over time)
  const double end = run.samples.back().time - run.samples.front().time;
  double at = std::sqrt(2.0 * h0 / g);  // the first landing
  const int most = e >= 1.0 ? std::numeric_limits<int>::max() : kMaxApexes;
  double worst = 0.0;
  for (int i = 1; i <= most; ++i) {
    const double expected = std::pow(e, 2.0 * i) * h0;
    if (expected < kApexFloor) break;
    at += std::sqrt(2.0 * expected / g);  // up to apex i
    if (at > end) break;
    at += std::sqrt(2.0 * expected / g);  // and down
    const double measured = i <= static_cast<int>(apexes.size()) ? apexes[std::size_t(i - 1)] : 0.0;
    out.apex_relative_errors.push_back((measured - expected) / expected);
    worst = std::max(worst, std::abs(out.apex_relative_errors.back()));
  }
  if (!out.apex_relative_errors.empty()) out.apex_relative_error_max = worst;
  // the closed form is for a box that stays flat: one that turned has tumbled
  double turned = 0.0;
  for (const Sample& s : run.samples)
    turned = std::max(turned, orientation_angle(b.orientation, s.bodies[std::size_t(slot)].orientation));
  if (turned > kTumbledBeyond) {
    out.verdict = "tumbled";
    std::ostringstream why;
    why.precision(2);
    why << "tumbled: turned " << turned * 180.0 / M_PI << "° (the closed form is for a flat drop)";
    out.message = why.str();
  } else if (!out.apex_relative_errors.empty() && static_cast<int>(apexes.size()) <
                                               static_cast<int>(out.apex_relative_errors.size())) {
    out.verdict = "no bounce";
    out.message = "no bounce: " + std::to_string(apexes.size()) + " apex(es) where the closed form has " +
                  std::to_string(out.apex_relative_errors.size()) + " above " + metres(kApexFloor);
  } else if (e >= 1.0 && out.apex_relative_error_max) {
    // e = 1: every apex at the release height
    if (*out.apex_relative_error_max <= kElasticApexWithin) {
      out.verdict = "keeps height";
    } else {
      const auto worst_apex = std::max_element(
          out.apex_relative_errors.begin(), out.apex_relative_errors.end(),
          [](double x, double y) { return std::abs(x) < std::abs(y); });
      out.verdict = *worst_apex > 0.0 ? "gains height" : "loses height";
      std::ostringstream why;
      why.precision(3);
      why << out.verdict << ": apex " << (worst_apex - out.apex_relative_errors.begin()) + 1
          << " of " << out.apex_relative_errors.size() << " off the release height by "
          << 100.0 * *worst_apex << " % (e = 1: within " << 100.0 * kElasticApexWithin << " %)";
      out.message = why.str();
    }
  }
}

// A sphere on a plane (Coulomb friction μ, gravity g into it): its contact point slips at
// u = v + ω × (−R n), and friction μ m g against the slip brings it to rolling, v_roll =
// v₀ − u₀ I / (I + m R²) (5/7 of v₀ for a solid sphere launched without spin), at
// t_roll = |u₀| / (μ g (1 + m R² / I)); then it rolls at v_roll for good
void judge_rolling(const Scene& scene, const Trajectory& run, ContactSummary& out) {
  const auto found = body_on_plane(scene, run);
  if (!found) return;
  const auto& [b, plane, slot, n] = *found;
  const double g = -scene.gravity.dot(n), mu = pair_friction(b, plane), r = b.shape.radius;
  const double inertia = principal_inertia(b.shape, b.mass).x();
  const double share = inertia / (inertia + b.mass * r * r);
  auto in_plane = [&](const Vec3& v) { return Vec3(v - v.dot(n) * n); };
  auto slip = [&](const Vec3& v, const Vec3& w) { return in_plane(v + w.cross(-r * n)); };
  const Vec3 u0 = slip(b.linear_velocity, b.angular_velocity);
  const Vec3 rolling = in_plane(b.linear_velocity) - share * u0;
  const double v_roll = rolling.norm();
  if (!(v_roll > 0.0)) return;
  const SampledState& last = run.samples.back().bodies[std::size_t(slot)];
  const double v_end = in_plane(last.linear_velocity).norm();
  out.roll_speed_error = (v_end - v_roll) / v_roll;
  const double slip_end = slip(last.linear_velocity, last.angular_velocity).norm();
  // the time the slip fell below the share of v_roll the verdict allows, between samples
  if (u0.norm() > kRollsWithin * v_roll && mu > 0.0 && g > 0.0) {
    const double t_roll = u0.norm() / (mu * g * (1.0 + b.mass * r * r / inertia));
    const double t0 = run.samples.front().time;
    for (const Sample& s : run.samples) {
      const SampledState& x = s.bodies[std::size_t(slot)];
      if (slip(x.linear_velocity, x.angular_velocity).norm() <= kRollsWithin * v_roll) {
        out.roll_time_error = (s.time - t0 - t_roll) / t_roll;
        break;
      }
    }
  }
  std::ostringstream why;
  why.precision(3);
  if (slip_end > kRollsWithin * v_roll) {
    out.verdict = "slips";
    why << "slips: the contact point still slides at " << slip_end << " m/s at the end (rolling "
        << "within " << 100.0 * kRollsWithin << " % of " << v_roll << " m/s)";
  } else if (std::abs(*out.roll_speed_error) > kRollsWithin) {
    out.verdict = *out.roll_speed_error < 0.0 ? "rolls slow" : "rolls fast";
    why << out.verdict << ": " << v_end << " m/s where the closed form rolls at " << v_roll
        << " m/s (" << 100.0 * *out.roll_speed_error << " %; within " << 100.0 * kRollsWithin
        << " %)";
  } else {
    out.verdict = "rolls";
  }
  out.message = why.str();
}

// A row of equal spheres along the line of the one that moves, at rest and each touching the
// next, struck by it. Both classical answers keep momentum and energy: "sequential" (the striker
// and the row stop, the last ball leaves at the striker's speed v₀: impacts one after another),
// "simultaneous" (Newton's law on every contact at once: the k balls of the row leave together at
// 2 v₀ / (k + 1), the striker at v₀ (1 − k) / (k + 1)). The final velocities are matched to each,
// within 5 % of v₀ (RMS over the balls)
void judge_cradle(const Scene& scene, const Trajectory& run, ContactSummary& out) {
  const std::vector<int> balls = bodies_where(scene, true, ShapeKind::Sphere);
  if (balls.size() < 3 || balls.size() != bodies_where(scene, true, std::nullopt).size()) return;
  const BodySpec& first = scene.bodies[balls[0]];
  int striker = -1;
  for (int i : balls) {
    const BodySpec& b = scene.bodies[i];
    if (b.mass != first.mass || b.shape.radius != first.shape.radius ||
        b.angular_velocity.norm() != 0.0)
      return;
    if (b.linear_velocity.norm() == 0.0) continue;
    if (striker >= 0) return;  // one moves
    striker = i;
  }
  if (striker < 0) return;
  const double v0 = scene.bodies[striker].linear_velocity.norm();
  const Vec3 u = scene.bodies[striker].linear_velocity / v0;
  // the row in order along u, each ball touching the next on the striker's line, ahead of it
  std::vector<int> row;
  for (int i : balls)
    if (i != striker) row.push_back(i);
  std::sort(row.begin(), row.end(), [&](int a, int b) {
    return scene.bodies[a].position.dot(u) < scene.bodies[b].position.dot(u);
  });
  const double diameter = 2.0 * first.shape.radius;
  const Vec3 start = scene.bodies[striker].position;
  for (std::size_t k = 0; k < row.size(); ++k) {
    const Vec3 offset = scene.bodies[row[k]].position - start;
    if ((offset - offset.dot(u) * u).norm() > 1e-9 * diameter || offset.dot(u) <= 0.0) return;
    if (k > 0 && std::abs((scene.bodies[row[k]].position - scene.bodies[row[k - 1]].position)
                              .norm() - diameter) > 1e-9 * diameter)
      return;
  }
  const double count = static_cast<double>(row.size());
  auto miss = [&](auto answer) {  // RMS over the balls of |v − answer| / v₀
    double squares = 0.0;
    for (int i : balls) {
      const int slot = slot_of(run, i);
      if (slot < 0) return std::numeric_limits<double>::infinity();
      squares += (run.samples.back().bodies[std::size_t(slot)].linear_velocity - answer(i) * u)
                     .squaredNorm();
    }
    return std::sqrt(squares / static_cast<double>(balls.size())) / v0;
  };
  const double sequential = miss([&](int i) { return i == row.back() ? v0 : 0.0; });
  const double simultaneous = miss([&](int i) {
    return i == striker ? v0 * (1.0 - count) / (count + 1.0) : 2.0 * v0 / (count + 1.0);
  });
  constexpr double kAnswerWithin = 0.05;
  out.cradle_answer = sequential <= kAnswerWithin     ? "sequential"
                      : simultaneous <= kAnswerWithin ? "simultaneous"
                                                      : "other";
}

// Bodies that meet elastically (e = 1, μ = 0, no gravity): the energy at the end against the
// start, and for a row of equal spheres, one struck, which classical answer the engine gave
void judge_elastic(const Scene& scene, const Trajectory& run, const ErrorSeries& series,
                   ContactSummary& out) {
  judge_cradle(scene, run, out);
  if (series.energy_change.empty()) return;
  const double change = series.energy_change.back();
  std::ostringstream why;
  why.precision(3);
  if (!std::isfinite(change) || std::abs(change) > kElasticWithin) {
    out.verdict = !(change <= 0.0) ? "gains energy" : "loses energy";
    why << out.verdict << ": " << 100.0 * change << " % of the energy at the start by the end"
        << " (e = 1, μ = 0: kept within " << 100.0 * kElasticWithin << " %)";
  } else {
    out.verdict = "elastic";
  }
  out.message = why.str();
}

void judge_incline(const Scene& scene, const Trajectory& run, ContactSummary& out) {
  const auto found = body_on_plane(scene, run);
  if (!found) return;
  const auto& [b, plane, slot, n] = *found;
  const Vec3 along = scene.gravity - scene.gravity.dot(n) * n;
  if (along.norm() < 1e-12 * scene.gravity.norm()) return;  // a level plane has no downhill
  const Vec3 downhill = along.normalized();
  const double g = scene.gravity.norm(), mu = pair_friction(b, plane);
  const double sin_theta = along.norm() / g, cos_theta = -scene.gravity.dot(n) / g;
  out.slide_acceleration_expected =
      sin_theta <= mu * cos_theta ? 0.0 : g * (sin_theta - mu * cos_theta);
  // s(t) along the slope; least squares for s = c0 + c1 t + a t² / 2 (normal equations)
  Eigen::Matrix3d normal_matrix = Eigen::Matrix3d::Zero();
  Eigen::Vector3d right = Eigen::Vector3d::Zero();
  const Vec3 start = run.samples.front().bodies[std::size_t(slot)].position;
  double s = 0.0;
  for (const Sample& sample : run.samples) {
    s = (sample.bodies[std::size_t(slot)].position - start).dot(downhill);
    const Eigen::Vector3d basis(1.0, sample.time, 0.5 * sample.time * sample.time);
    normal_matrix += basis * basis.transpose();
    right += basis * s;
  }
  out.slide_distance = s;
  if (run.samples.size() >= 3) out.slide_acceleration = normal_matrix.ldlt().solve(right)[2];
  const double expected = *out.slide_acceleration_expected;
  if (expected > 0.0 && out.slide_acceleration)
    out.slide_acceleration_error = (*out.slide_acceleration - expected) / expected;
  const bool moved = std::abs(s) > kMovedBeyond;
  out.verdict = moved ? "slides" : "stays";
  if (moved != (expected > 0.0)) {
    out.verdict += expected > 0.0 ? ", should slide" : ", should stay";
    out.message = out.verdict + ": the closed form " + (expected > 0.0 ? "slides" : "stays") +
                  " (moved " + metres(s) + ")";
  }
}

void judge_exchange(const Scene& scene, const Trajectory& run, ContactSummary& out) {
  const std::vector<int> pair = bodies_where(scene, true, std::nullopt);
  const int sa = slot_of(run, pair[0]), sb = slot_of(run, pair[1]);
  if (sa < 0 || sb < 0) return;
  const BodySpec& a = scene.bodies[pair[0]];
  const BodySpec& b = scene.bodies[pair[1]];
  // a 1D collision along the line of centres, with the pair's restitution
  const Vec3 u = (b.position - a.position).normalized();
  const double ua = a.linear_velocity.dot(u), ub = b.linear_velocity.dot(u);
  const double approach = ua - ub;
  if (approach <= 0.0) return;  // they never meet
  const double e = pair_restitution(a, b), m = a.mass + b.mass;
  const double ua_after = (a.mass * ua + b.mass * ub + b.mass * e * (ub - ua)) / m;
  const double ub_after = (a.mass * ua + b.mass * ub + a.mass * e * (ua - ub)) / m;
  const Vec3 va = a.linear_velocity + (ua_after - ua) * u;
  const Vec3 vb = b.linear_velocity + (ub_after - ub) * u;
  const Sample& last = run.samples.back();
  out.exchange_error = std::max((last.bodies[std::size_t(sa)].linear_velocity - va).norm(),
                                (last.bodies[std::size_t(sb)].linear_velocity - vb).norm()) /
                       approach;
}

void judge_tunnelling(const Scene& scene, const Trajectory& run, ContactSummary& out) {
  const int body = bodies_where(scene, true, std::nullopt).at(0);
  const int slot = slot_of(run, body);
  if (slot < 0) return;
  const BodySpec& b = scene.bodies[body];
  const Vec3 heading = b.linear_velocity.normalized();
  // the wall: the static box straight ahead, nearest first
  int wall = -1;
  double nearest = 0.0;
  for (int w : bodies_where(scene, false, ShapeKind::Box)) {
    const Vec3 offset = scene.bodies[w].position - b.position;
    const double ahead = offset.dot(heading);
    if (ahead <= 0.0) continue;
    const double aside = (offset - ahead * heading).norm();
    if (aside > scene.bodies[w].shape.half_extents.maxCoeff() * std::sqrt(3.0)) continue;
    if (wall < 0 || ahead < nearest) {
      wall = w;
      nearest = ahead;
    }
  }
  if (wall < 0) return;
  const BodySpec& w = scene.bodies[wall];
  const double wall_reach = support_extent(w, w.orientation, heading);
  const double near_face = nearest - wall_reach, far_face = nearest + wall_reach;
  const SampledState& end = run.samples.back().bodies[std::size_t(slot)];
  const double travelled = (end.position - b.position).dot(heading);
  const double reach = support_extent(b, end.orientation, heading);
  out.tunnelled = travelled - reach > far_face;
  if (*out.tunnelled) {
    out.verdict = "tunnelled";
    out.message = "tunnelled: ended " + metres(travelled - reach - far_face) +
                  " beyond the wall's far face";
  } else if (travelled > near_face && travelled < far_face) {
    out.verdict = "stuck";
    out.message = "stuck: its centre ends inside the wall";
  } else {
    out.verdict = "stopped";
  }
}

}  // namespace

Container container_of(const Scene& scene) {
  Container c;
  const Vec3 g = scene.gravity;
  g.cwiseAbs().maxCoeff(&c.up_axis);
  c.up_sign = g[c.up_axis] < 0.0 ? 1.0 : -1.0;
  const std::vector<int> walls = bodies_where(scene, false, ShapeKind::Box);
  Vec3 centre = Vec3::Zero();
  for (int w : walls) centre += scene.bodies[w].position;
  centre /= static_cast<double>(walls.size());
  c.low = Vec3::Constant(-std::numeric_limits<double>::infinity());
  c.high = Vec3::Constant(std::numeric_limits<double>::infinity());
  c.rim = -std::numeric_limits<double>::infinity();
  for (int w : walls) {
    const BodySpec& b = scene.bodies[w];
    // world-aligned (validate() checks it): the box's faces are at position ± half extents
    for (int axis = 0; axis < 3; ++axis) {
      const double low = b.position[axis] - b.shape.half_extents[axis];
      const double high = b.position[axis] + b.shape.half_extents[axis];
      if (axis == c.up_axis) {
        c.rim = std::max(c.rim, c.up_sign > 0.0 ? high * c.up_sign : low * c.up_sign);
        continue;
      }
      // a wall wholly on one side of the centre bounds the inside there
      if (low > centre[axis])
        c.high[axis] = std::min(c.high[axis], low);
      else if (high < centre[axis])
        c.low[axis] = std::max(c.low[axis], high);
    }
  }
  return c;
}

bool Container::holds(const Vec3& x) const {
  if (!std::isfinite(x.squaredNorm())) return false;
  for (int axis = 0; axis < 3; ++axis)
    if (axis != up_axis && (x[axis] < low[axis] || x[axis] > high[axis])) return false;
  return x[up_axis] * up_sign <= rim;
}

namespace {

void judge_confined(const Scene& scene, const Trajectory& run, const ErrorSeries& series,
                    ContactSummary& out) {
  const Container c = container_of(scene);
  judge_speeds(run, out);
  long escaped = 0;
  for (const SampledState& b : run.samples.back().bodies) escaped += !c.holds(b.position);
  out.escaped = escaped;
  const double sunk = series.penetration.empty() ? 0.0 : series.penetration.back();
  if (escaped > 0) {
    out.verdict = "escaped";
    out.message = "escaped: " + std::to_string(escaped) + " of " +
                  std::to_string(run.bodies.size()) +
                  " bodies ended outside the container (beyond a wall or above the rim at " +
                  metres(c.rim) + ")";
  } else if (sunk > kSinksBeyond) {
    out.verdict = "sinks";
    out.message = "sinks: final penetration " + metres(sunk) + " (> " + metres(kSinksBeyond) + ")";
  } else if (out.rest_speed_rms && *out.rest_speed_rms > kRestlessBeyond) {
    std::ostringstream why;
    why.precision(3);
    why << "unsettled: RMS speed over the last second " << *out.rest_speed_rms << " m/s (> "
        << kRestlessBeyond << ")";
    out.verdict = "unsettled";
    out.message = why.str();
  } else {
    out.verdict = "contained";
  }
}

}  // namespace

bool verdict_is_failure(const std::string& verdict) {
  return verdict == "collapsed" || verdict == "sinks" || verdict == "drifts" ||
         verdict == "settles" || verdict == "tumbled" || verdict == "slides, should stay" ||
         verdict == "stays, should slide" ||
         verdict == "tunnelled" || verdict == "stuck" || verdict == "no bounce" ||
         verdict == "exploded" || verdict == "escaped" || verdict == "unsettled" ||
         verdict == "gains height" || verdict == "loses height" || verdict == "slips" ||
         verdict == "rolls slow" || verdict == "rolls fast" || verdict == "gains energy" ||
         verdict == "loses energy";
}

ContactSummary contact_summary(const Scene& scene, const Trajectory& run,
                               const ErrorSeries& series) {
  ContactSummary out;
  if (run.samples.empty() || run.bodies.empty()) return out;
  if (wants(scene, Metric::Energy) && scene.has_contacts()) {
    const double start = invariants_of(scene, run.bodies, run.samples.front()).energy;
    double added = 0.0;
    for (const Sample& s : run.samples)
      added = std::max(added, invariants_of(scene, run.bodies, s).energy - start);
    out.energy_added_max = added;
  }
  if (wants(scene, Metric::StackDrift)) judge_stack(scene, run, series, out);
  if (wants(scene, Metric::BounceApex)) judge_bounce(scene, run, out);
  if (wants(scene, Metric::Incline)) judge_incline(scene, run, out);
  if (wants(scene, Metric::Exchange)) judge_exchange(scene, run, out);
  if (wants(scene, Metric::Tunnelling)) judge_tunnelling(scene, run, out);
  if (wants(scene, Metric::Confined)) judge_confined(scene, run, series, out);
  if (wants(scene, Metric::Rolling)) judge_rolling(scene, run, out);
  if (wants(scene, Metric::Elastic)) judge_elastic(scene, run, series, out);
  return out;
}

bool energy_can_only_fall(const Scene& scene, const ErrorSeries& series) {
  if (!scene.impulses.empty() || scene.particles) return false;
  for (const BodySpec& b : scene.bodies)
    if (b.restitution > 1.0) return false;
  // bodies started overlapping are pushed apart: the overlap's energy is released
  return series.penetration.empty() || !(series.penetration.front() > 1e-3);
}

double energy_scale(const Scene& scene) {
  double scale = 0.0;
  const double g = scene.gravity.norm();
  const Vec3 up = g > 0.0 ? Vec3(-scene.gravity / g) : Vec3::Zero();
  auto reach = [](const BodySpec& b) {
    return b.shape.kind == ShapeKind::Sphere ? b.shape.radius
           : b.shape.kind == ShapeKind::Box  ? b.shape.half_extents.norm()
                                             : 0.0;
  };
  // the lowest point of anything in the scene along up (a plane's surface, a shape's reach down)
  double floor = std::numeric_limits<double>::infinity();
  for (const BodySpec& b : scene.bodies) floor = std::min(floor, b.position.dot(up) - reach(b));
  for (const BodySpec& b : scene.bodies) {
    if (!(b.mass > 0.0)) continue;
    const Vec3 inertia = principal_inertia(b.shape, b.mass);
    const Vec3 w = b.orientation.conjugate() * b.angular_velocity;
    scale += 0.5 * b.mass * b.linear_velocity.squaredNorm() +
             0.5 * w.dot(inertia.cwiseProduct(w));
    // its weight times how far its centre could fall and its own size: the energy it could
    // trade in the scene (a first-order integrator's sampled energy runs ahead of the true one
    // by m g v dt / 2 in a fall: 3.7 % of a 1 m drop's at 60 Hz)
    scale += b.mass * g * (b.position.dot(up) - floor + reach(b));
  }
  for (const SpringSpec& s : scene.springs) {
    const Vec3 a = scene.bodies[s.body_a].position +
                   scene.bodies[s.body_a].orientation * s.local_point_a;
    const Vec3 b = s.body_b < 0 ? s.point_b
                                : Vec3(scene.bodies[s.body_b].position +
                                       scene.bodies[s.body_b].orientation * s.point_b);
    const double stretch = (a - b).norm() - s.rest_length;
    scale += 0.5 * s.stiffness * stretch * stretch;
  }
  return scale;
}

Scene refined(const Scene& scene, int divisor) {
  Scene fine = scene;
  fine.dt = scene.dt / divisor;
  return fine;
}

}  // namespace physbench
