// Contact scenarios (issue 18): stacks, bounces, slopes, mass ratios, overlap recovery, tunnelling
// and a head-on collision, as data every engine builds the same way.
//
// Common to all: unit boxes (1 m cubes, 1 kg) unless a scene says otherwise, y up, dt = 1/60,
// a static ground that is a ShapeKind::Plane body (its local y = 0 surface, solid below: every
// engine has an infinite plane, and a plane has no edges for a sliding box to fall off), friction
// and restitution set on every body (the pair takes √(μa μb) and max(ea, eb)). Sleeping is off in
// every adapter. All motion is in the XY plane, so every scene here is marked planar and Box2D
// runs the same scene (no "-planar" twins: a twin would be the same data under a second name and
// double the rows).
#include <cmath>
#include <sstream>

#include "physbench/scenarios.h"

namespace physbench {

namespace {

constexpr double kHalf = 0.5;  // unit box half extent (m)

BodySpec ground(double friction, double restitution = 0.0) {
  BodySpec g;
  g.name = "ground";
  g.shape.kind = ShapeKind::Plane;
  g.mass = 0.0;
  g.friction = friction;
  g.restitution = restitution;
  return g;
}

BodySpec unit_box(const std::string& name, const Vec3& position, double friction,
                  double restitution = 0.0, double mass = 1.0) {
  BodySpec b;
  b.name = name;
  b.shape.kind = ShapeKind::Box;
  b.shape.half_extents = Vec3::Constant(kHalf);
  b.mass = mass;
  b.position = position;
  b.friction = friction;
  b.restitution = restitution;
  return b;
}

// a number as a name part: 0.5 → "0.5", 30 → "30"
std::string tag(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

Scene contact_scene(const std::string& name, const std::string& description, double duration) {
  Scene scene;
  scene.name = name;
  scene.description = description;
  scene.gravity = Vec3(0.0, -9.81, 0.0);
  scene.dt = 1.0 / 60.0;
  scene.duration = duration;
  scene.planar = true;
  scene.collisions = true;
  scene.reference.kind = ReferenceKind::None;
  return scene;
}

}  // namespace

Scene tower_scene(int boxes) {
  constexpr double kFriction = 0.6;
  Scene scene = contact_scene("tower-" + std::to_string(boxes),
                              std::to_string(boxes) +
                                  " unit boxes (1 m, 1 kg) stacked exactly touching on the ground, "
                                  "μ = 0.6, at rest: does the tower stand for 10 s?",
                              10.0);
  scene.bodies.push_back(ground(kFriction));
  for (int i = 0; i < boxes; ++i)
    scene.bodies.push_back(
        unit_box("box" + std::to_string(i), Vec3(0.0, kHalf + i * 2.0 * kHalf, 0.0), kFriction));
  scene.probe.metrics = {Metric::StackDrift, Metric::Penetration, Metric::Energy};
  return scene;
}

Scene pyramid_scene(int base) {
  constexpr double kFriction = 0.6;
  const int count = base * (base + 1) / 2;
  std::ostringstream description;
  description << "a pyramid of " << count << " unit boxes, " << base
              << " at the base, each row offset by half a box, all exactly touching, μ = 0.6: "
                 "does it stand, and what does a step cost?";
  Scene scene = contact_scene("pyramid-" + std::to_string(base), description.str(), 10.0);
  scene.bodies.push_back(ground(kFriction));
  for (int row = 0; row < base; ++row) {
    const int in_row = base - row;
    for (int i = 0; i < in_row; ++i) {
      // centred on x = 0; a row of n boxes spans n m, so rows above sit half a box in
      const double x = (i - 0.5 * (in_row - 1)) * 2.0 * kHalf;
      std::ostringstream name;
      name << 'r' << row << 'b' << i;
      scene.bodies.push_back(
          unit_box(name.str(), Vec3(x, kHalf + row * 2.0 * kHalf, 0.0), kFriction));
    }
  }
  // ten samples a second: 5,050 bodies sampled every step would be 3 million states
  scene.probe.interval = 0.1;
  scene.probe.metrics = {Metric::StackDrift, Metric::Penetration, Metric::Energy};
  return scene;
}

Scene bounce_scene(double restitution) {
  constexpr double kDrop = 1.0;  // bottom face above the ground (m)
  Scene scene =
      contact_scene("bounce-e" + tag(restitution),
                    "a unit box dropped flat from rest, its bottom face 1 m above the ground, "
                    "restitution " + tag(restitution) +
                        " on box and ground: apex n is e^(2n) · 1 m (closed form)",
                    4.0);
  scene.bodies.push_back(ground(0.5, restitution));
  scene.bodies.push_back(unit_box("box", Vec3(0.0, kHalf + kDrop, 0.0), 0.5, restitution));
  scene.probe.interval = scene.dt;  // every step: apexes are found between samples
  scene.probe.metrics = {Metric::BounceApex, Metric::Penetration, Metric::Energy};
  return scene;
}

Scene incline_scene(double degrees) {
  constexpr double kFriction = 0.5;
  const double theta = degrees * M_PI / 180.0;
  Scene scene = contact_scene(
      "incline-" + tag(degrees),
      "a unit box at rest on a plane sloped " + tag(degrees) +
          "°, μ = 0.5: it stays when tan θ ≤ μ, else slides with a = g (sin θ − μ cos θ) "
          "(closed form)",
      5.0);
  // the slope: the ground plane turned about z so that it falls towards +x
  BodySpec slope = ground(kFriction);
  slope.name = "slope";
  slope.orientation = Quat(Eigen::AngleAxisd(-theta, Vec3::UnitZ()));
  scene.bodies.push_back(slope);
  const Vec3 normal = slope.orientation * Vec3::UnitY();
  BodySpec box = unit_box("box", normal * kHalf, kFriction);
  box.orientation = slope.orientation;
  scene.bodies.push_back(box);
  scene.probe.metrics = {Metric::Incline, Metric::Penetration, Metric::Energy};
  return scene;
}

Scene mass_ratio_scene(double ratio) {
  constexpr double kFriction = 0.6;
  Scene scene = contact_scene(
      "mass-ratio-" + tag(ratio),
      "a " + tag(ratio) +
          " kg unit box resting on a 1 kg unit box on the ground, μ = 0.6: how far does the "
          "light box sink, or the heavy one slide?",
      10.0);
  scene.bodies.push_back(ground(kFriction));
  scene.bodies.push_back(unit_box("light", Vec3(0.0, kHalf, 0.0), kFriction, 0.0, 1.0));
  scene.bodies.push_back(unit_box("heavy", Vec3(0.0, 3.0 * kHalf, 0.0), kFriction, 0.0, ratio));
  scene.probe.metrics = {Metric::StackDrift, Metric::Penetration, Metric::Energy};
  return scene;
}

Scene overlap_recovery_scene() {
  constexpr double kFriction = 0.6, kOverlap = 0.05;
  constexpr int kBoxes = 4;
  Scene scene = contact_scene(
      "overlap-recovery",
      "a stack of 4 unit boxes started 5 cm into each other and into the ground, at rest, μ = 0.6: "
      "how much speed and energy does each engine's correction add?",
      5.0);
  scene.bodies.push_back(ground(kFriction));
  for (int i = 0; i < kBoxes; ++i)
    scene.bodies.push_back(unit_box("box" + std::to_string(i),
                                    Vec3(0.0, kHalf - kOverlap + i * (2.0 * kHalf - kOverlap), 0.0),
                                    kFriction));
  scene.probe.metrics = {Metric::StackDrift, Metric::Penetration, Metric::Energy};
  return scene;
}

Scene tunnelling_scene(double hz) {
  constexpr double kSpeed = 50.0, kHalfSize = 0.05, kWallHalfThickness = 0.025, kWallX = 2.0;
  Scene scene = contact_scene(
      "tunnelling-" + tag(hz),
      "a 0.1 m, 0.1 kg box at 50 m/s towards a 5 cm thick static wall 2 m ahead, no gravity, at "
      "dt = 1/" + tag(hz) + " s (" + tag(kSpeed / hz) +
          " m per step): does it go through?",
      0.2);
  scene.gravity = Vec3::Zero();
  scene.dt = 1.0 / hz;
  BodySpec bullet;
  bullet.name = "bullet";
  bullet.shape.half_extents = Vec3::Constant(kHalfSize);
  bullet.mass = 0.1;
  bullet.linear_velocity = Vec3(kSpeed, 0.0, 0.0);
  bullet.friction = 0.5;
  scene.bodies.push_back(bullet);
  BodySpec wall;
  wall.name = "wall";
  wall.shape.half_extents = Vec3(kWallHalfThickness, 1.0, 1.0);
  wall.mass = 0.0;
  wall.position = Vec3(kWallX, 0.0, 0.0);
  wall.friction = 0.5;
  scene.bodies.push_back(wall);
  scene.probe.interval = scene.dt;
  scene.probe.metrics = {Metric::Tunnelling, Metric::Penetration};
  return scene;
}

Scene head_on_scene() {
  Scene scene = contact_scene(
      "head-on",
      "two unit boxes, 1 m apart, at +2 and −1 m/s along x, e = 1, μ = 0, no gravity: equal "
      "masses exchange velocities",
      2.0);
  scene.gravity = Vec3::Zero();
  scene.bodies.push_back(unit_box("left", Vec3(-1.0, 0.0, 0.0), 0.0, 1.0));
  scene.bodies.back().linear_velocity = Vec3(2.0, 0.0, 0.0);
  scene.bodies.push_back(unit_box("right", Vec3(1.0, 0.0, 0.0), 0.0, 1.0));
  scene.bodies.back().linear_velocity = Vec3(-1.0, 0.0, 0.0);
  scene.probe.metrics = {Metric::Exchange, Metric::Penetration, Metric::Energy,
                         Metric::LinearMomentum};
  return scene;
}

std::vector<Scenario> contact_scenarios() {
  std::vector<Scenario> all;
  for (int boxes : {10, 20})
    all.push_back({"tower-" + std::to_string(boxes),
                   "does a tower of " + std::to_string(boxes) +
                       " unit boxes (μ = 0.6) stand for 10 s: drift, sink, cost?",
                   [boxes] { return tower_scene(boxes); }});
  for (int base : {10, 20, 50, 100}) {
    Scenario s;
    s.name = "pyramid-" + std::to_string(base);
    s.question = "does a pyramid of " + std::to_string(base * (base + 1) / 2) +
                 " boxes stand, and how does the cost of a step grow with the body count?";
    s.build = [base] {
      Scene scene = pyramid_scene(base);
      // 5,050 boxes for 10 s on every engine would be most of the suite: the suite runs 1 s
      // (60 steps); `physbench run -s pyramid-100 --duration 10` runs the whole scene
      if (base >= 100) {
        scene.duration = 1.0;
        scene.description += " (1 s in the default suite; --duration 10 for the whole run)";
      }
      return scene;
    };
    s.family = "pyramid";
    s.parameter_name = "base";
    s.parameter = base;
    all.push_back(s);
  }
  for (double e : {0.2, 0.5, 0.8})
    all.push_back({"bounce-e" + tag(e),
                   "do a dropped box's apexes fall as e^(2n) at e = " + tag(e) + "?",
                   [e] { return bounce_scene(e); }});
  for (double degrees : {25.0, 30.0})
    all.push_back({"incline-" + tag(degrees),
                   "does a block on a " + tag(degrees) +
                       "° slope (μ = 0.5) stay or slide as the closed form says?",
                   [degrees] { return incline_scene(degrees); }});
  for (double ratio : {10.0, 100.0, 1000.0})
    all.push_back({"mass-ratio-" + tag(ratio),
                   "heavy on light at " + tag(ratio) +
                       ":1: does the light box hold the heavy one, or sink, or let it slide?",
                   [ratio] { return mass_ratio_scene(ratio); }});
  all.push_back({"overlap-recovery",
                 "boxes started 5 cm into each other: how much speed and energy does the "
                 "correction add?",
                 overlap_recovery_scene});
  for (double hz : {30.0, 60.0, 120.0})
    all.push_back({"tunnelling-" + tag(hz),
                   "does a small box at 50 m/s pass through a 5 cm wall at " + tag(hz) + " Hz?",
                   [hz] { return tunnelling_scene(hz); }});
  all.push_back({"head-on", "do two equal boxes exchange velocities in an elastic collision?",
                 head_on_scene});
  return all;
}

}  // namespace physbench
