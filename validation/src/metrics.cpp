#include "physbench/metrics.h"

#include <cmath>
#include <stdexcept>

namespace physbench {

namespace {

struct Invariants {
  double energy = 0.0, kinetic = 0.0, spring_potential = 0.0;
  Vec3 linear_momentum = Vec3::Zero(), angular_momentum = Vec3::Zero();
};

Invariants invariants_of(const Scene& scene, const std::vector<int>& bodies, const Sample& sample) {
  Invariants inv;
  std::vector<const BodyState*> state_of(scene.bodies.size(), nullptr);
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    const BodyState& s = sample.bodies[i];
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
    const BodyState* a = state_of[spring.body_a];
    if (!a) continue;
    const Vec3 pa = a->position + a->orientation * spring.local_point_a;
    Vec3 pb = spring.point_b;
    if (spring.body_b >= 0) {
      const BodyState* b = state_of[spring.body_b];
      if (!b) continue;
      pb = b->position + b->orientation * spring.point_b;
    }
    const double extension = (pa - pb).norm() - spring.rest_length;
    inv.spring_potential += 0.5 * spring.stiffness * extension * extension;
    inv.energy += 0.5 * spring.stiffness * extension * extension;
  }
  return inv;
}

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

  for (std::size_t k = 0; k < run.samples.size(); ++k) {
    const Sample& s = run.samples[k];
    series.time.push_back(s.time);
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
      BodyState state;
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
    BodyState state;
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

Scene refined(const Scene& scene, int divisor) {
  Scene fine = scene;
  fine.dt = scene.dt / divisor;
  return fine;
}

}  // namespace physbench
