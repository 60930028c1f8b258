// rtp world: rigid bodies in momentum form, springs, and a fixed-step integrator.
//
// The state of a body is the seed's primary set — position, linear momentum, orientation
// quaternion, angular momentum — from which velocity, angular velocity and the world-frame
// inverse inertia are derived. Integrating momenta rather than velocities keeps angular
// momentum of a torque-free body exactly constant under every integrator, and it is what
// lets RK4 re-evaluate forces at every stage from a consistent state (Baraff, "Physically
// Based Modeling", SIGGRAPH 2001 course notes, §2; Fiedler, "Physics in 3D").
#pragma once

#include <cstdint>
#include <vector>

#include "rtp/math.h"

namespace rtp {

enum class Integrator : std::uint8_t {
  SemiImplicitEuler,  // momenta first, then positions from the new velocities (symplectic)
  Midpoint,           // second order: derivatives at the half step
  RungeKutta4,        // fourth order: four force evaluations per step
  Symplectic,         // kick, then the free rotation by splitting about the principal axes
                      // (Dullweber, Leimkuhler, McLachlan 1997): second order for free bodies,
                      // energy error bounded, angular momentum exact, one force evaluation
};

// a body to create; principal axes of inertia are the body's axes
struct BodyDef {
  Vec3 position = Vec3::Zero();           // centre of mass, world (m)
  Quat orientation = Quat::Identity();    // body to world
  Vec3 linear_velocity = Vec3::Zero();    // world (m/s)
  Vec3 angular_velocity = Vec3::Zero();   // world (rad/s)
  double mass = 1.0;                      // kg; 0 makes the body static
  Vec3 principal_inertia = Vec3::Ones();  // body frame diagonal (kg m²)
};

// the primary state the integrators advance (112 bytes: 13 doubles and the padding that keeps the
// quaternion 16-byte aligned; 128 where AVX has Eigen align it to 32)
struct BodyState {
  Vec3 position;          // centre of mass, world (m)
  Vec3 linear_momentum;   // world (kg m/s)
  Quat orientation;       // body to world, unit
  Vec3 angular_momentum;  // about the centre of mass, world (kg m²/s)
};
static_assert(sizeof(BodyState) == (alignof(Quat) > 16 ? 128 : 112));

// the time derivative of a BodyState
struct BodyRate {
  Vec3 velocity;          // dx/dt (m/s)
  Vec3 force;             // dP/dt (N)
  Quat orientation_rate;  // dq/dt (1/s)
  Vec3 torque;            // dL/dt (N m)
};

// a body's constant mass properties
struct BodyMass {
  double inverse_mass = 0.0;                 // 1/kg; 0 for static bodies
  Vec3 inverse_inertia_body = Vec3::Zero();  // body frame diagonal (1/(kg m²))
};

using BodyId = std::uint32_t;
inline constexpr BodyId kWorldAnchor = ~BodyId{0};

// Hooke's law plus damping along the line between two attachment points
struct SpringDef {
  BodyId body_a = 0;
  Vec3 local_point_a = Vec3::Zero();  // body-a frame (m)
  BodyId body_b = kWorldAnchor;       // kWorldAnchor: point_b is a fixed world point
  Vec3 point_b = Vec3::Zero();        // body-b frame, or world when anchored (m)
  double stiffness = 0.0;             // N/m
  double damping = 0.0;               // N s/m, along the spring's line
  double rest_length = 0.0;           // m
};

// wall time of each stage of the last step (s)
struct StepProfile {
  double integrate = 0.0;
  double total = 0.0;
};

class World {
 public:
  explicit World(Vec3 gravity = Vec3(0.0, -9.81, 0.0),
                 Integrator integrator = Integrator::RungeKutta4);

  BodyId add_body(const BodyDef& def);
  void add_spring(const SpringDef& def);

  // advance by one fixed step of dt seconds
  void step(double dt);

  // apply an impulse (N s) at a world point: changes linear and angular momentum at once
  void apply_impulse(BodyId body, const Vec3& impulse, const Vec3& world_point);

  std::size_t body_count() const { return states_.size(); }
  const BodyState& state(BodyId body) const { return states_[body]; }
  Vec3 velocity(BodyId body) const;
  Vec3 angular_velocity(BodyId body) const;
  double mass(BodyId body) const;
  Mat3 inertia_world(BodyId body) const;
  const Vec3& gravity() const { return gravity_; }
  Integrator integrator() const { return integrator_; }
  void set_integrator(Integrator integrator) { integrator_ = integrator; }
  const StepProfile& profile() const { return profile_; }

  // total mechanical energy: kinetic + gravitational potential + spring potential (J)
  double mechanical_energy() const;

 private:
  // time derivative of every body's state, forces re-evaluated from that state
  void evaluate(const std::vector<BodyState>& states, std::vector<BodyRate>& rates) const;
  // the first half of both Euler-type integrators: momenta by the forces, positions by the new
  // velocities
  void kick_and_translate(double dt);
  void integrate_semi_implicit_euler(double dt);
  void integrate_midpoint(double dt);
  void integrate_runge_kutta4(double dt);
  void integrate_symplectic(double dt);
  // states = base + h * rates, quaternions left unnormalised until the step ends
  void advance(const std::vector<BodyState>& base, const std::vector<BodyRate>& rates, double h,
               std::vector<BodyState>& out) const;
  void normalise_orientations();

  Vec3 gravity_;
  Integrator integrator_;
  std::vector<BodyState> states_;
  std::vector<BodyMass> masses_;
  std::vector<SpringDef> springs_;
  StepProfile profile_;
  // integrator scratch, sized once per body count: no allocation inside a step
  std::vector<BodyState> stage_state_;
  std::vector<BodyRate> k1_, k2_, k3_, k4_;
};

}  // namespace rtp
