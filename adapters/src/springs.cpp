#include "physbench/springs.h"

namespace physbench {

SpringForce spring_force(const SpringSpec& spring, const SampledState& a, const SampledState* b) {
  SpringForce f;
  f.point_a = a.position + a.orientation * spring.local_point_a;
  Vec3 velocity_b = Vec3::Zero();
  f.point_b = spring.point_b;
  if (b) {
    f.point_b = b->position + b->orientation * spring.point_b;
    velocity_b = b->linear_velocity + b->angular_velocity.cross(f.point_b - b->position);
  }
  const Vec3 velocity_a = a.linear_velocity + a.angular_velocity.cross(f.point_a - a.position);
  const Vec3 delta = f.point_a - f.point_b;
  const double length = delta.norm();
  // a spring of zero length has no direction: it pulls along nothing
  if (length <= 1e-12) return f;
  const Vec3 direction = delta / length;
  const double extension_rate = direction.dot(velocity_a - velocity_b);
  f.force_on_a =
      -(spring.stiffness * (length - spring.rest_length) + spring.damping * extension_rate) *
      direction;
  return f;
}

void apply_spring_forces(const Scene& scene, const StateOf& state_of, const ApplyForceAt& apply) {
  for (const SpringSpec& spring : scene.springs) {
    const SampledState a = state_of(spring.body_a);
    SampledState b_state;
    const SampledState* b = nullptr;
    if (spring.body_b >= 0) {
      b_state = state_of(spring.body_b);
      b = &b_state;
    }
    const SpringForce f = spring_force(spring, a, b);
    if (scene.bodies[spring.body_a].mass > 0.0) apply(spring.body_a, f.force_on_a, f.point_a);
    if (b && scene.bodies[spring.body_b].mass > 0.0) apply(spring.body_b, -f.force_on_a, f.point_b);
  }
}

VelocityChange impulse_velocity_change(const BodySpec& body, const SampledState& now,
                                       const Vec3& impulse, const Vec3& world_point) {
  VelocityChange change;
  if (body.mass == 0.0) return change;
  const Mat3 rotation = now.orientation.normalized().toRotationMatrix();
  const Mat3 inverse_inertia_world =
      rotation * principal_inertia(body.shape, body.mass).cwiseInverse().asDiagonal() *
      rotation.transpose();
  change.linear = impulse / body.mass;
  change.angular = inverse_inertia_world * (world_point - now.position).cross(impulse);
  return change;
}

}  // namespace physbench
