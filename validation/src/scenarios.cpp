#include "physbench/scenarios.h"

namespace physbench {

Scene projectile_scene() {
  Scene scene;
  scene.name = "projectile";
  scene.description =
      "a spinning 1 x 0.5 x 0.25 m box thrown under gravity; closed-form centre of mass";
  scene.gravity = Vec3(0.0, -9.81, 0.0);
  scene.dt = 1.0 / 60.0;
  scene.duration = 2.5;
  scene.collisions = false;  // nothing to hit: no collision detection in any engine
  BodySpec box;
  box.name = "box";
  box.shape.kind = ShapeKind::Box;
  box.shape.half_extents = Vec3(0.5, 0.25, 0.125);
  box.mass = 2.0;
  box.position = Vec3(0.0, 1.0, 0.0);
  box.linear_velocity = Vec3(3.0, 12.0, -2.0);
  box.angular_velocity = Vec3(0.5, 2.0, 1.5);
  scene.bodies.push_back(box);
  scene.probe.metrics = {Metric::Position, Metric::Energy};
  scene.reference.kind = ReferenceKind::Ballistic;
  return scene;
}

Scene projectile_planar_scene() {
  Scene scene = projectile_scene();
  scene.name = "projectile-planar";
  scene.description =
      "the projectile confined to the XY plane, spinning about z, so 2D engines have a row";
  scene.planar = true;
  scene.bodies[0].linear_velocity = Vec3(3.0, 12.0, 0.0);
  scene.bodies[0].angular_velocity = Vec3(0.0, 0.0, 3.0);
  return scene;
}

Scene tumbling_box_scene() {
  Scene scene;
  scene.name = "tumbling-box";
  scene.description =
      "a 1 x 4 x 9 m box in zero gravity spinning about its intermediate axis with a small "
      "perturbation "
      "(the Dzhanibekov effect): energy and angular momentum must stay constant";
  scene.gravity = Vec3::Zero();
  scene.dt = 1.0 / 60.0;
  scene.duration = 10.0;
  scene.collisions = false;
  BodySpec box;
  box.name = "box";
  box.shape.kind = ShapeKind::Box;
  box.shape.half_extents = Vec3(0.5, 2.0, 4.5);  // y is the intermediate principal axis
  box.mass = 1.0;
  box.angular_velocity = Vec3(0.01, 2.0, 0.0);  // rad/s: about y, perturbed about x
  scene.bodies.push_back(box);
  scene.probe.metrics = {Metric::Orientation, Metric::Energy, Metric::AngularMomentum};
  scene.reference.kind = ReferenceKind::Converged;
  scene.reference.dt_divisor = 64;
  return scene;
}

const std::vector<Scenario>& scenarios() {
  static const std::vector<Scenario> list = {
      {"projectile", "how far does each integrator put a thrown box from the closed-form parabola?",
       projectile_scene},
      {"projectile-planar", "the same question in the plane, so Box2D can answer it",
       projectile_planar_scene},
      {"tumbling-box",
       "does each engine keep a free body's energy and angular momentum, and follow the converged "
       "tumble?",
       tumbling_box_scene},
  };
  return list;
}

const Scenario* find_scenario(const std::string& name) {
  for (const Scenario& s : scenarios())
    if (s.name == name) return &s;
  return nullptr;
}

}  // namespace physbench
