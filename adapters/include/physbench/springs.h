// External loads for engines that lack a native form: the scene's spring law, and the velocity
// change of an impulse.
//
// The scene's spring law, for engines that take springs as external forces: Hooke's law plus
// damping along the line between the two attachment points, the same law rtp evaluates inside
// its integrator (rtp/world.h). Peers apply it once per step, before stepping.
#pragma once

#include <functional>

#include "physbench/engine.h"

namespace physbench {

struct SpringForce {
  Vec3 force_on_a = Vec3::Zero();  // N; body b (if any) receives the opposite
  Vec3 point_a = Vec3::Zero();     // world attachment on body a (m)
  Vec3 point_b = Vec3::Zero();     // world attachment on body b or the anchor (m)
};

// b is null for a spring anchored to the world
SpringForce spring_force(const SpringSpec& spring, const SampledState& a, const SampledState* b);

using StateOf = std::function<SampledState(int body)>;
using ApplyForceAt = std::function<void(int body, const Vec3& force, const Vec3& world_point)>;

// evaluates every spring of the scene from the current states and applies the forces to the
// dynamic bodies at their world attachment points
void apply_spring_forces(const Scene& scene, const StateOf& state_of, const ApplyForceAt& apply);

// the change of linear and angular velocity (world) an impulse J at a world point p gives a body
// with the scene's mass properties in state `now`: Δv = J / m, Δω = I_world⁻¹ ((p − x) × J)
struct VelocityChange {
  Vec3 linear = Vec3::Zero();
  Vec3 angular = Vec3::Zero();
};
VelocityChange impulse_velocity_change(const BodySpec& body, const SampledState& now,
                                       const Vec3& impulse, const Vec3& world_point);

}  // namespace physbench
