// Small contact worlds for the engine's contact tests (test_contacts.cpp,
// test_overlap_recovery.cpp, test_held_contacts.cpp): a ground plane and boxes of a given mass, at the tests' step and
// gravity.
#pragma once

#include <vector>

#include "rtp/world.h"

namespace rtp::contact_worlds {

inline constexpr double kDt = 1.0 / 60.0;
inline const Vec3 kGravity(0.0, -9.81, 0.0);

inline BodyId add_ground(World& world, double friction, double restitution = 0.0,
                         const Quat& orientation = Quat::Identity()) {
  BodyDef ground;
  ground.mass = 0.0;
  ground.orientation = orientation;
  ground.shape.kind = BodyShape::Plane;
  ground.friction = friction;
  ground.restitution = restitution;
  return world.add_body(ground);
}

inline BodyId add_box(World& world, const Vec3& position, double mass, double friction,
                      double restitution = 0.0, const Quat& orientation = Quat::Identity(),
                      const Vec3& half = Vec3::Constant(0.5)) {
  BodyDef box;
  box.position = position;
  box.orientation = orientation;
  box.mass = mass;
  box.principal_inertia = mass / 3.0 *
                          Vec3(half.y() * half.y() + half.z() * half.z(),
                               half.x() * half.x() + half.z() * half.z(),
                               half.x() * half.x() + half.y() * half.y());
  box.shape.kind = BodyShape::Box;
  box.shape.half_extents = half;
  box.friction = friction;
  box.restitution = restitution;
  return world.add_body(box);
}

// every body's pose and momenta, number by number (to compare two runs' bits)
inline std::vector<double> state_numbers(const World& world) {
  std::vector<double> state;
  for (BodyId b = 0; b < world.body_count(); ++b) {
    const BodyState& s = world.state(b);
    state.insert(state.end(), s.position.data(), s.position.data() + 3);
    state.insert(state.end(), s.orientation.coeffs().data(), s.orientation.coeffs().data() + 4);
    state.insert(state.end(), s.linear_momentum.data(), s.linear_momentum.data() + 3);
    state.insert(state.end(), s.angular_momentum.data(), s.angular_momentum.data() + 3);
  }
  return state;
}

}  // namespace rtp::contact_worlds
