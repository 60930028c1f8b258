#include "rtp/world.h"

#include <cassert>
#include <cmath>
#include <chrono>
#include <stdexcept>

#include "contact_stages.h"
#include "threads.h"

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

// Hooke plus damping along the line between the ends, on end a (N); a spring of zero length has
// no direction and pulls along nothing
Vec3 spring_force_on_a(const SpringDef& spring, const Vec3& point_a, const Vec3& velocity_a,
                       const Vec3& point_b, const Vec3& velocity_b) {
  const Vec3 delta = point_a - point_b;
  const double length = delta.norm();
  if (length <= 1e-12) return Vec3::Zero();
  const Vec3 direction = delta / length;
  const double extension_rate = direction.dot(velocity_a - velocity_b);
  return -(spring.stiffness * (length - spring.rest_length) + spring.damping * extension_rate) *
         direction;
}

}  // namespace

World::World(Vec3 gravity, Integrator integrator, ContactSettings contacts)
    : gravity_(gravity),
      integrator_(integrator),
      contact_settings_(contacts),
      governor_(contacts.threads, contacts.adaptive_threads),
      active_threads_(std::max(1, contacts.threads)) {
  if (contacts.substeps < 1 || contacts.velocity_iterations < 0 || contacts.relax_iterations < 0 ||
      contacts.max_relax_iterations < 0 || contacts.recovery_relax_iterations < 0 ||
      contacts.recovery_position_iterations < 0 ||
      contacts.restitution_iterations < 0 ||
      contacts.local_iterations < 1 || contacts.threads < 1)
    throw std::invalid_argument("rtp: contact substeps must be >= 1 and iterations >= 0");
  if (!(contacts.speculative_distance >= 0.0) || !(contacts.linear_slop >= 0.0) ||
      !(contacts.contact_hertz >= 0.0) || !(contacts.damping_ratio >= 0.0) ||
      !(contacts.max_push_speed > 0.0) || !(contacts.relax_tolerance >= 0.0) ||
      !std::isfinite(contacts.relax_tolerance) || !(contacts.restitution_tolerance >= 0.0) ||
      !std::isfinite(contacts.restitution_tolerance) ||
      !(contacts.contact_hold_distance >= 0.0) || !std::isfinite(contacts.contact_hold_distance) ||
      !(contacts.bounds_margin >= 0.0) || !std::isfinite(contacts.bounds_margin))
    throw std::invalid_argument("rtp: contact distances, stiffness and speeds must be >= 0");
  contact_isa_ = &contact_isa(contacts.instruction_set);
}

const char* World::contact_instruction_set() const { return contact_isa_->name; }

World::~World() = default;
World::World(World&&) noexcept = default;
World& World::operator=(World&&) noexcept = default;

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
  if (def.shape.kind == BodyShape::Plane && def.mass > 0.0)
    throw std::invalid_argument("rtp: a plane must be static (mass 0)");
  // the first body with a shape makes the contact pipeline, and every body before it joins
  if (def.shape.kind != BodyShape::None && !pipeline_) {
    pipeline_.reset(contact_isa_->make(contact_settings_));
    for (std::size_t i = 0; i < states_.size(); ++i)
      pipeline_->add_body(BodyId(i), ShapeDef{}, 0.0, 0.0, masses_[i].inverse_mass == 0.0);
  }
  if (pipeline_)
    pipeline_->add_body(BodyId(states_.size()), def.shape, def.friction, def.restitution,
                        def.mass == 0.0);
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
    const Vec3 force_on_a = spring_force_on_a(spring, point_a, velocity_a, point_b, velocity_b);
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
  if (pipeline_) {
    step_with_contacts(dt);
    return;
  }
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

namespace {

// The step's stages timed back to back: each runs and adds to its profile entry the time since
// the last one ended, one clock read a stage, not two (a four-box scene's step read the clock
// some 80 times, 6 % of its time by `perf`). Every part of the step after the clock starts is in
// some stage (writing the results out is `store`), so the stages sum to the step's own clock.
class StageClock {
 public:
  StageClock() : last_(Clock::now()) {}
  template <class Stage>
  void operator()(double& seconds, Stage&& stage) {
    stage();
    const auto now = Clock::now();
    seconds += std::chrono::duration<double>(now - last_).count();
    last_ = now;
  }

 private:
  Clock::time_point last_;
};

}  // namespace

void World::integrate_velocities(double h) {
  // gravity and springs on the velocities (semi-implicit Euler's kick); springs read the poses
  // of this substep and the solver's velocities
  std::vector<SolverBody>& bodies = pipeline_->bodies();
  const std::vector<SolverMass>& masses = pipeline_->masses();
  const Eigen::Vector3f kick = (h * gravity_).cast<float>();
  const std::ptrdiff_t n = std::ptrdiff_t(states_.size());
  parallel_for(active_threads_, n, n >= 2048, [&](std::ptrdiff_t i) {
    if (masses[i].inverse_mass > 0.0) bodies[i].linear_velocity += kick;
  });
  auto velocity_at = [&](BodyId body, const Vec3& point) -> Vec3 {
    return bodies[body].linear_velocity.cast<double>() +
           bodies[body].angular_velocity.cast<double>().cross(point - states_[body].position);
  };
  for (const SpringDef& spring : springs_) {
    const BodyState& a = states_[spring.body_a];
    const Vec3 point_a = world_point(a, spring.local_point_a);
    const Vec3 velocity_a = velocity_at(spring.body_a, point_a);
    Vec3 point_b = spring.point_b, velocity_b = Vec3::Zero();
    if (spring.body_b != kWorldAnchor) {
      point_b = world_point(states_[spring.body_b], spring.point_b);
      velocity_b = velocity_at(spring.body_b, point_b);
    }
    const Vec3 impulse_on_a =
        h * spring_force_on_a(spring, point_a, velocity_a, point_b, velocity_b);
    auto push = [&](BodyId body, const Vec3& point, const Vec3& impulse) {
      bodies[body].linear_velocity += (masses[body].inverse_mass * impulse).cast<float>();
      bodies[body].angular_velocity +=
          (masses[body].inverse_inertia * (point - states_[body].position).cross(impulse))
              .cast<float>();
    };
    push(spring.body_a, point_a, impulse_on_a);
    if (spring.body_b != kWorldAnchor) push(spring.body_b, point_b, -impulse_on_a);
  }
}

void World::load_pose_lanes() {
  const std::size_t n = states_.size();
  const std::size_t groups = (n + kPoseGroup - 1) / kPoseGroup;
  pose_lanes_.resize(groups * kPoseDoubles);  // allocates only when the body count grows
  // a group of bodies at a time on the threads, each writing its own groups' lanes (serial, the
  // two copies took about 1.5 % of a two-thread step at pyramid-100 while the other thread waited)
  parallel_for(active_threads_, std::ptrdiff_t(groups), n >= 2048, [&](std::ptrdiff_t group) {
    const std::size_t first = std::size_t(group) * kPoseGroup;
    const std::size_t last = std::min(n, first + kPoseGroup);
    for (std::size_t i = first; i < last; ++i) {
      double* lanes = pose_lanes_.data() + (i / kPoseGroup) * kPoseDoubles + i % kPoseGroup;
      const BodyState& s = states_[i];
      for (int k = 0; k < 3; ++k) lanes[k * kPoseGroup] = s.position[k];
      lanes[3 * kPoseGroup] = s.orientation.w(), lanes[4 * kPoseGroup] = s.orientation.x();
      lanes[5 * kPoseGroup] = s.orientation.y(), lanes[6 * kPoseGroup] = s.orientation.z();
    }
  });
  poses_in_lanes_ = true;
}

void World::store_pose_lanes() {
  const std::ptrdiff_t n = std::ptrdiff_t(states_.size());
  parallel_for(active_threads_, n, n >= 2048, [&](std::ptrdiff_t i) {
    const double* lanes = pose_lanes_.data() + (i / kPoseGroup) * kPoseDoubles + i % kPoseGroup;
    BodyState& s = states_[i];
    for (int k = 0; k < 3; ++k) s.position[k] = lanes[k * kPoseGroup];
    s.orientation = Quat(lanes[3 * kPoseGroup], lanes[4 * kPoseGroup], lanes[5 * kPoseGroup],
                         lanes[6 * kPoseGroup]);
  });
  poses_in_lanes_ = false;
}

void World::integrate_positions(double h) {
  // positions by the new velocities, orientations by the exponential map, in the contact
  // pipeline's copy for the core's instruction set (ContactStages::integrate_positions)
  if (!poses_in_lanes_) load_pose_lanes();
  pipeline_->integrate_positions(pose_lanes_, states_.size(), h);
  // the springs read this substep's poses from the states
  if (!springs_.empty()) store_pose_lanes();
}

void World::store_momenta() {
  // back to the momentum form: P = m v, L = I(q) ω with the step's final orientation
  const std::vector<SolverBody>& bodies = pipeline_->bodies();
  // each body by itself, on the threads
  const std::ptrdiff_t n = std::ptrdiff_t(states_.size());
  parallel_for(active_threads_, n, n >= 2048, [&](std::ptrdiff_t i) {
    const BodyMass& m = masses_[i];
    if (m.inverse_mass == 0.0) return;
    BodyState& s = states_[i];
    s.linear_momentum = bodies[i].linear_velocity.cast<double>() / m.inverse_mass;
    const Mat3 rotation = s.orientation.toRotationMatrix();
    s.angular_momentum = rotation * m.inverse_inertia_body.cwiseInverse().asDiagonal() *
                         rotation.transpose() * bodies[i].angular_velocity.cast<double>();
  });
}

void World::step_with_contacts(double dt) {
  // the seed's labs in order (docs/solver.md): contacts found at the step's start, then the
  // solver's scheme. Soft step: per substep kick, warm start, biased solve, drift, relax; one
  // restitution pass at the end. Sequential impulse and seed: one kick, the iterations, one drift.
  const auto start = Clock::now();
  profile_ = StepProfile{};
  ContactStages& contacts = *pipeline_;
  const ContactSettings& settings = contact_settings_;
  active_threads_ = governor_.next();
  contacts.set_threads(active_threads_);
  StageClock timed;
  timed(profile_.prepare, [&] { contacts.load_bodies(states_, masses_); });
  timed(profile_.bounds, [&] { contacts.update_bounds(states_, dt); });
  timed(profile_.broad_phase, [&] { contacts.find_pairs(); });
  timed(profile_.narrow_phase, [&] { contacts.collide_pairs(states_, dt, gravity_); });
  // a step whose deepest overlap is more than the soft step's push-out can remove in it is
  // recovering from an overlap (boxes spawned into each other): the poses are moved apart first,
  // down to the push-out's reach, and the substeps' relax passes are a fixed number (below)
  const bool soft = settings.solver == ContactSolver::SoftStep;
  const bool recovering = soft && contacts.deepest_penetration() > settings.max_push_speed * dt;
  // (timed with prepare: the step's profile has no stage of its own for the position passes)
  if (recovering && settings.recovery_position_iterations > 0)
    timed(profile_.prepare, [&] {
      contacts.project_overlaps(states_, settings.max_push_speed * dt,
                                settings.recovery_position_iterations);
    });
  timed(profile_.prepare, [&] {
    contacts.prepare(gravity_, soft ? dt / settings.substeps : dt);
  });
  switch (settings.solver) {
    case ContactSolver::SoftStep: {
      const double h = dt / settings.substeps;
      // recovering, the biased solve adds push velocity every substep, so relax passes cannot
      // settle it: it runs a fixed number of them, enough to take most of the push-out's speed
      // back (docs/solver.md, "The ring": "Not while recovering")
      for (int substep = 0; substep < settings.substeps; ++substep) {
        // the kick and the warm start; after the first substep, without springs, in one pass
        // over the bodies (ContactPipeline::next_substep: gravity is the only force then)
        if (substep > 0 && springs_.empty()) {
          timed(profile_.warm_start,
                [&] { contacts.next_substep((h * gravity_).cast<float>()); });
        } else {
          if (substep > 0) timed(profile_.warm_start, [&] { contacts.end_substep(); });
          timed(profile_.integrate, [&] { integrate_velocities(h); });
          timed(profile_.warm_start, [&] { contacts.warm_start(substep == 0); });
        }
        // Gauss–Seidel carries each pass's order into its answer: forwards every substep, a large
        // pyramid leans steadily one way (its top walked 6 cm in 10 s); alternating, it does not
        const bool backwards = settings.alternate_order && substep % 2 == 1;
        timed(profile_.solve, [&] { contacts.solve(h, true, backwards); });
        timed(profile_.integrate_positions, [&] { integrate_positions(h); });
        timed(profile_.relax, [&] {
          // relax_iterations passes, then more while the last one still moved a point's normal
          // velocity by over the tolerance, up to max_relax_iterations; recovering, a fixed
          // recovery_relax_iterations
          const double tolerance = settings.relax_tolerance;
          const int least = recovering ? settings.recovery_relax_iterations
                                       : settings.relax_iterations;
          const int most =
              recovering ? least : std::max(least, settings.max_relax_iterations);
          for (int i = 0; i < most; ++i) {
            // (the passes before the last of the minimum track nothing: nothing reads it)
            const bool last_needed = i + 1 >= least;
            const bool settled =
                contacts.solve(h, false, backwards, last_needed && most > least ? tolerance : 0.0);
            ++profile_.relax_passes;
            if (last_needed && (settled || tolerance <= 0.0)) break;
          }
        });
      }
      // the impulses carried to the next step's warm start are the solve's: a bounce's is an
      // impact, and carried it would push the bodies apart once more (a struck row of balls
      // then gained 15 % of its energy at Box2D's settings)
      timed(profile_.store, [&] { contacts.store_impulses(); });
      timed(profile_.restitution, [&] { contacts.restitution(); });
      break;
    }
    case ContactSolver::SequentialImpulse:
      timed(profile_.integrate, [&] { integrate_velocities(dt); });
      timed(profile_.warm_start, [&] { contacts.warm_start(); });
      timed(profile_.solve, [&] {
        for (int i = 0; i < settings.velocity_iterations; ++i) contacts.solve(dt, true);
      });
      timed(profile_.store, [&] { contacts.store_impulses(); });
      timed(profile_.restitution, [&] { contacts.restitution(); });
      timed(profile_.integrate_positions, [&] { integrate_positions(dt); });
      break;
    case ContactSolver::Seed:
      timed(profile_.integrate, [&] { integrate_velocities(dt); });
      timed(profile_.solve, [&] { contacts.solve_seed(dt); });
      timed(profile_.integrate_positions, [&] { integrate_positions(dt); });
      timed(profile_.store, [&] { contacts.store_impulses(); });
      break;
  }
  if (poses_in_lanes_) timed(profile_.store, [&] { store_pose_lanes(); });
  // the seed's lab 5 has no continuous collision: its variant keeps that weakness, measured
  if (settings.solver != ContactSolver::Seed)
    timed(profile_.continuous,
          [&] { profile_.swept_stops = contacts.sweep_fast_bodies(states_); });
  timed(profile_.store, [&] { store_momenta(); });
  profile_.contact_pairs = contacts.contact_count();
  profile_.contact_points = contacts.point_count();
  profile_.matched_points = contacts.matched_points();
  profile_.reused_pairs = contacts.reused_pairs();
  profile_.reused_manifolds = contacts.reused_manifolds();
  profile_.held_contacts = contacts.held_contacts();
  profile_.reordered_contacts = contacts.reordered_contacts();
  profile_.pairs_kept = contacts.pairs_kept();
  profile_.total = seconds_since(start);
  profile_.threads = active_threads_;
  governor_.record(active_threads_, profile_.total);
}

double World::deepest_penetration() const {
  return pipeline_ ? pipeline_->deepest_penetration() : 0.0;
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
