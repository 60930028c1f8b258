#include "physbench/rtp_world.h"

namespace physbench {

namespace {

// the scene's shapes in rtp's terms (a plane is the body's local y = 0 surface in both)
rtp::ShapeDef shape_def(const Shape& shape) {
  rtp::ShapeDef def;
  switch (shape.kind) {
    case ShapeKind::Box:
      def.kind = rtp::BodyShape::Box;
      def.half_extents = shape.half_extents;
      break;
    case ShapeKind::Sphere:
      def.kind = rtp::BodyShape::Sphere;
      def.radius = shape.radius;
      break;
    case ShapeKind::Plane:
      def.kind = rtp::BodyShape::Plane;
      break;
  }
  return def;
}

}  // namespace

rtp::World make_rtp_world(const Scene& scene, rtp::Integrator integrator,
                          const rtp::ContactSettings& contacts) {
  rtp::World world(scene.gravity, integrator, contacts);
  // shapes only where bodies can touch: a scene without contacts keeps its integrator
  const bool shaped = scene.has_contacts();
  for (const BodySpec& b : scene.bodies) {
    rtp::BodyDef def;
    def.position = b.position;
    def.orientation = b.orientation;
    def.linear_velocity = b.linear_velocity;
    def.angular_velocity = b.angular_velocity;
    def.mass = b.mass;
    if (b.mass > 0.0) def.principal_inertia = principal_inertia(b.shape, b.mass);
    if (shaped) def.shape = shape_def(b.shape);
    def.friction = b.friction;
    def.restitution = b.restitution;
    world.add_body(def);
  }
  for (const SpringSpec& s : scene.springs) {
    rtp::SpringDef def;
    def.body_a = static_cast<rtp::BodyId>(s.body_a);
    def.local_point_a = s.local_point_a;
    def.body_b = s.body_b < 0 ? rtp::kWorldAnchor : static_cast<rtp::BodyId>(s.body_b);
    def.point_b = s.point_b;
    def.stiffness = s.stiffness;
    def.damping = s.damping;
    def.rest_length = s.rest_length;
    world.add_spring(def);
  }
  return world;
}

}  // namespace physbench
