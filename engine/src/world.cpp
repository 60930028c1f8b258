#include "rtp/world.h"

#include <cassert>
#include <chrono>
#include <stdexcept>

namespace rtp {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

Vec3 derived_velocity(const BodyState& s, const BodyMass& m) {
  return s.linear_momentum * m.inverse_mass;
}

// Runge-Kutta stages carry quaternions off the unit sphere by O((ω h)²); the rotation they
// stand for is that of the normalised quaternion, and using the raw one would cost RK4 its order
Vec3 derived_angular_velocity(const BodyState& s, const BodyMass& m) {
  return world_inverse_inertia(s.orientation.normalized(), m.inverse_inertia_body) *
         s.angular_momentum;
}

Vec3 world_point(const BodyState& s, const Vec3& local_point) {
  return s.position + s.orientation.normalized() * local_point;
}

}  // namespace

World::World(Vec3 gravity, Integrator integrator) : gravity_(gravity), integrator_(integrator) {}

BodyId World::add_body(const BodyDef& def) {
  if (!(def.mass >= 0.0)) throw std::invalid_argument("rtp: body mass must be >= 0");
  BodyMass mass;
  BodyState state;
  state.position = def.position;
  state.orientation = def.orientation.normalized();
  if (def.mass > 0.0) {
    if (!(def.principal_inertia.array() > 0.0).all())
      throw std::invalid_argument("rtp: a dynamic body needs positive principal inertia");
    mass.inverse_mass = 1.0 / def.mass;
    mass.inverse_inertia_body = def.principal_inertia.cwiseInverse();
    state.linear_momentum = def.mass * def.linear_velocity;
    // L = I_world ω with I_world = R I_body Rᵀ
    const Mat3 rotation = state.orientation.toRotationMatrix();
    state.angular_momentum =
        rotation * def.principal_inertia.asDiagonal() * rotation.transpose() * def.angular_velocity;
  } else {
    state.linear_momentum.setZero();
    state.angular_momentum.setZero();
  }
  states_.push_back(state);
  masses_.push_back(mass);
  // scratch grows with the world, never inside a step
  for (auto* buffer : {&k1_, &k2_, &k3_, &k4_}) buffer->resize(states_.size());
  stage_state_.resize(states_.size());
  return static_cast<BodyId>(states_.size() - 1);
}

void World::add_spring(const SpringDef& def) {
  if (def.body_a >= states_.size() || (def.body_b != kWorldAnchor && def.body_b >= states_.size()))
    throw std::invalid_argument("rtp: spring attached to a body that does not exist");
  springs_.push_back(def);
}

Vec3 World::velocity(BodyId body) const { return derived_velocity(states_[body], masses_[body]); }

Vec3 World::angular_velocity(BodyId body) const {
  return derived_angular_velocity(states_[body], masses_[body]);
}

double World::mass(BodyId body) const {
  return masses_[body].inverse_mass > 0.0 ? 1.0 / masses_[body].inverse_mass : 0.0;
}

Mat3 World::inertia_world(BodyId body) const {
  const BodyMass& m = masses_[body];
  if (m.inverse_mass == 0.0) return Mat3::Zero();
  const Mat3 rotation = states_[body].orientation.toRotationMatrix();
  return rotation * m.inverse_inertia_body.cwiseInverse().asDiagonal() * rotation.transpose();
}

void World::apply_impulse(BodyId body, const Vec3& impulse, const Vec3& world_point) {
  if (masses_[body].inverse_mass == 0.0) return;
  BodyState& s = states_[body];
  s.linear_momentum += impulse;
  s.angular_momentum += (world_point - s.position).cross(impulse);
}

void World::evaluate(const std::vector<BodyState>& states, std::vector<BodyRate>& rates) const {
  // gravity and the kinematic rates of every body
  for (std::size_t i = 0; i < states.size(); ++i) {
    const BodyState& s = states[i];
    const BodyMass& m = masses_[i];
    BodyRate& r = rates[i];
    if (m.inverse_mass == 0.0) {
      r.velocity.setZero();
      r.force.setZero();
      r.orientation_rate.coeffs().setZero();
      r.torque.setZero();
      continue;
    }
    r.velocity = derived_velocity(s, m);
    r.orientation_rate = quaternion_rate(derived_angular_velocity(s, m), s.orientation);
    r.force = gravity_ / m.inverse_mass;
    r.torque.setZero();
  }

  // springs: Hooke plus damping along the line, torque r × F on each end
  for (const SpringDef& spring : springs_) {
    const BodyState& a = states[spring.body_a];
    const Vec3 point_a = world_point(a, spring.local_point_a);
    const Vec3 velocity_a =
        rates[spring.body_a].velocity +
        derived_angular_velocity(a, masses_[spring.body_a]).cross(point_a - a.position);
    Vec3 point_b = spring.point_b;
    Vec3 velocity_b = Vec3::Zero();
    if (spring.body_b != kWorldAnchor) {
      const BodyState& b = states[spring.body_b];
      point_b = world_point(b, spring.point_b);
      velocity_b = rates[spring.body_b].velocity +
                   derived_angular_velocity(b, masses_[spring.body_b]).cross(point_b - b.position);
    }
    const Vec3 delta = point_a - point_b;
    const double length = delta.norm();
    // a spring of zero length has no direction: it pulls along nothing
    if (length <= 1e-12) continue;
    const Vec3 direction = delta / length;
    const double extension_rate = direction.dot(velocity_a - velocity_b);
    const Vec3 force_on_a =
        -(spring.stiffness * (length - spring.rest_length) + spring.damping * extension_rate) *
        direction;
    if (masses_[spring.body_a].inverse_mass > 0.0) {
      rates[spring.body_a].force += force_on_a;
      rates[spring.body_a].torque += (point_a - a.position).cross(force_on_a);
    }
    if (spring.body_b != kWorldAnchor && masses_[spring.body_b].inverse_mass > 0.0) {
      rates[spring.body_b].force -= force_on_a;
      rates[spring.body_b].torque -= (point_b - states[spring.body_b].position).cross(force_on_a);
    }
  }
}

void World::advance(const std::vector<BodyState>& base, const std::vector<BodyRate>& rates,
                    double h, std::vector<BodyState>& out) const {
  for (std::size_t i = 0; i < base.size(); ++i) {
    out[i].position = base[i].position + h * rates[i].velocity;
    out[i].linear_momentum = base[i].linear_momentum + h * rates[i].force;
    out[i].orientation.coeffs() =
        base[i].orientation.coeffs() + h * rates[i].orientation_rate.coeffs();
    out[i].angular_momentum = base[i].angular_momentum + h * rates[i].torque;
  }
}

void World::normalise_orientations() {
  for (BodyState& s : states_) s.orientation.normalize();
}

void World::kick_and_translate(double dt) {
  // momenta from the forces at the start of the step, then positions from the new velocities
  evaluate(states_, k1_);
  for (std::size_t i = 0; i < states_.size(); ++i) {
    BodyState& s = states_[i];
    const BodyMass& m = masses_[i];
    if (m.inverse_mass == 0.0) continue;
    s.linear_momentum += dt * k1_[i].force;
    s.angular_momentum += dt * k1_[i].torque;
    s.position += dt * derived_velocity(s, m);
  }
}

void World::integrate_semi_implicit_euler(double dt) {
  kick_and_translate(dt);
  // the orientation turns by the exponential map, a rotation of |ω| dt about the new ω, which is
  // exact for a fixed axis where q += ½ ω q dt is not
  for (std::size_t i = 0; i < states_.size(); ++i) {
    BodyState& s = states_[i];
    if (masses_[i].inverse_mass == 0.0) continue;
    const Vec3 w = derived_angular_velocity(s, masses_[i]);
    const double angle = w.norm() * dt;
    if (angle > 0.0) s.orientation = Quat(Eigen::AngleAxisd(angle, w / w.norm())) * s.orientation;
  }
  normalise_orientations();
}

void World::integrate_symplectic(double dt) {
  kick_and_translate(dt);
  for (std::size_t i = 0; i < states_.size(); ++i) {
    BodyState& s = states_[i];
    const BodyMass& m = masses_[i];
    if (m.inverse_mass == 0.0) continue;
    // drift: the torque-free rotation H = Σ Lᵢ² / 2Iᵢ split into one rotation about each principal
    // axis, composed symmetrically X(h/2) Y(h/2) Z(h) Y(h/2) X(h/2). Each part is exact: the body
    // turns about body axis i by θ = h Lᵢ / Iᵢ while the body-frame momentum turns by −θ, so the
    // world-frame L never changes (Dullweber, Leimkuhler & McLachlan, J. Chem. Phys. 107, 1997).
    Vec3 body_momentum = s.orientation.conjugate() * s.angular_momentum;
    auto turn = [&](int axis, double h) {
      const double angle = h * body_momentum[axis] * m.inverse_inertia_body[axis];
      const Eigen::AngleAxisd rotation(angle, Vec3::Unit(axis));
      s.orientation = s.orientation * Quat(rotation);
      body_momentum = Eigen::AngleAxisd(-angle, Vec3::Unit(axis)) * body_momentum;
    };
    turn(0, 0.5 * dt);
    turn(1, 0.5 * dt);
    turn(2, dt);
    turn(1, 0.5 * dt);
    turn(0, 0.5 * dt);
  }
  normalise_orientations();
}

void World::integrate_midpoint(double dt) {
  evaluate(states_, k1_);
  advance(states_, k1_, 0.5 * dt, stage_state_);
  evaluate(stage_state_, k2_);
  advance(states_, k2_, dt, states_);
  normalise_orientations();
}

void World::integrate_runge_kutta4(double dt) {
  // classic RK4; every stage re-evaluates forces, including springs, at its own state
  evaluate(states_, k1_);
  advance(states_, k1_, 0.5 * dt, stage_state_);
  evaluate(stage_state_, k2_);
  advance(states_, k2_, 0.5 * dt, stage_state_);
  evaluate(stage_state_, k3_);
  advance(states_, k3_, dt, stage_state_);
  evaluate(stage_state_, k4_);
  const double w = dt / 6.0;
  for (std::size_t i = 0; i < states_.size(); ++i) {
    BodyState& s = states_[i];
    s.position +=
        w * (k1_[i].velocity + 2.0 * (k2_[i].velocity + k3_[i].velocity) + k4_[i].velocity);
    s.linear_momentum += w * (k1_[i].force + 2.0 * (k2_[i].force + k3_[i].force) + k4_[i].force);
    s.orientation.coeffs() +=
        w * (k1_[i].orientation_rate.coeffs() +
             2.0 * (k2_[i].orientation_rate.coeffs() + k3_[i].orientation_rate.coeffs()) +
             k4_[i].orientation_rate.coeffs());
    s.angular_momentum +=
        w * (k1_[i].torque + 2.0 * (k2_[i].torque + k3_[i].torque) + k4_[i].torque);
  }
  normalise_orientations();
}

void World::step(double dt) {
  const auto start = Clock::now();
  // apply forces and integrate: forces are evaluated inside the integrator, once per stage
  switch (integrator_) {
    case Integrator::SemiImplicitEuler:
      integrate_semi_implicit_euler(dt);
      break;
    case Integrator::Midpoint:
      integrate_midpoint(dt);
      break;
    case Integrator::RungeKutta4:
      integrate_runge_kutta4(dt);
      break;
    case Integrator::Symplectic:
      integrate_symplectic(dt);
      break;
  }
  profile_.integrate = seconds_since(start);
  profile_.total = profile_.integrate;
}

double World::mechanical_energy() const {
  double energy = 0.0;
  for (std::size_t i = 0; i < states_.size(); ++i) {
    const BodyState& s = states_[i];
    const BodyMass& m = masses_[i];
    if (m.inverse_mass == 0.0) continue;
    const Vec3 v = derived_velocity(s, m);
    const Vec3 w = derived_angular_velocity(s, m);
    energy += 0.5 * s.linear_momentum.dot(v) + 0.5 * s.angular_momentum.dot(w);
    energy -= gravity_.dot(s.position) / m.inverse_mass;
  }
  for (const SpringDef& spring : springs_) {
    const BodyState& a = states_[spring.body_a];
    const Vec3 point_a = world_point(a, spring.local_point_a);
    Vec3 point_b = spring.point_b;
    if (spring.body_b != kWorldAnchor) {
      const BodyState& b = states_[spring.body_b];
      point_b = world_point(b, spring.point_b);
    }
    const double extension = (point_a - point_b).norm() - spring.rest_length;
    energy += 0.5 * spring.stiffness * extension * extension;
  }
  return energy;
}

}  // namespace rtp
