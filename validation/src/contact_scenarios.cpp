// Contact scenarios (issue 18): stacks, bounces, slopes, mass ratios, overlap recovery, tunnelling,
// a head-on collision and boxes raining into a container, as data every engine builds the same
// way.
//
// Common to all: unit boxes (1 m cubes, 1 kg) unless a scene says otherwise, y up, dt = 1/60,
// a static ground that is a ShapeKind::Plane body (its local y = 0 surface, solid below: every
// engine has an infinite plane, and a plane has no edges for a sliding box to fall off), friction
// and restitution set on every body (the pair takes √(μa μb) and max(ea, eb)). Sleeping is off in
// every adapter. All motion is in the XY plane, so every scene here is marked planar and Box2D
// runs the same scene (no "-planar" twins: a twin would be the same data under a second name and
// double the rows) — except `rain`, a 3D pile in a box of four walls, whose planar twin
// `rain-planar` (two walls) is a different scene.
#include <cmath>
#include <cstdint>
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

// a rotation drawn from a counter (SplitMix64): the same scene on every run and every engine
Quat tilt(std::uint64_t counter, double max_angle, bool about_z_only) {
  auto next = [&counter] {
    std::uint64_t z = (counter += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return double((z ^ (z >> 31)) >> 11) * 0x1.0p-53;  // [0, 1)
  };
  const double angle = (2.0 * next() - 1.0) * max_angle;
  Vec3 axis = Vec3::UnitZ();
  if (!about_z_only) {
    const double u = 2.0 * next() - 1.0, phi = 2.0 * M_PI * next();
    axis = Vec3(std::sqrt(1.0 - u * u) * std::cos(phi), std::sqrt(1.0 - u * u) * std::sin(phi), u);
  }
  return Quat(Eigen::AngleAxisd(angle, axis));
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

// Box3D's `many_pyramids` benchmark (its shared/benchmarks.c, at the commit the box3d worker
// runs): 14 × 14 walls of base 10, one box deep, standing apart on one ground — many islands, the
// case where threads and the broad phase matter. Pyramid (i, j) is centred at x = −71.5 + 11 j,
// z = −76 + 152 i / 13, its boxes placed as pyramid_scene's. Box3D's ground is a 154 m square box
// whose top is y = 0, here a plane; its gravity is 10 m/s², its boxes 100 kg (every box alike, so
// the motion is the same), and it runs 100 steps at 60 Hz and 4 substeps, as here
Scene many_pyramids_scene(int per_side, int base) {
  constexpr double kFriction = 0.6;
  const int count = per_side * per_side * base * (base + 1) / 2;
  std::ostringstream description;
  description << per_side << " x " << per_side << " pyramids of " << base * (base + 1) / 2
              << " unit boxes (" << count << " in all; base " << base
              << ", one box deep, 11 m apart), μ = 0.6, Box3D's many_pyramids layout: do they "
                 "stand, and what does a step of many islands cost?";
  Scene scene = contact_scene("many-pyramids", description.str(), 100.0 / 60.0);
  scene.planar = false;
  scene.bodies.push_back(ground(kFriction));
  for (int i = 0; i < per_side; ++i)
    for (int j = 0; j < per_side; ++j) {
      const double centre_x = -71.5 + 11.0 * j;
      const double z = -76.0 + 152.0 * i / (per_side - 1);
      for (int row = 0; row < base; ++row) {
        const int in_row = base - row;
        for (int k = 0; k < in_row; ++k) {
          std::ostringstream name;
          name << 'p' << i << '.' << j << 'r' << row << 'b' << k;
          const double x = centre_x + (k - 0.5 * (in_row - 1)) * 2.0 * kHalf;
          scene.bodies.push_back(
              unit_box(name.str(), Vec3(x, kHalf + row * 2.0 * kHalf, z), kFriction));
        }
      }
    }
  scene.probe.interval = 10.0 / 60.0;  // every 10 steps: 10,780 bodies
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

Scene elastic_bounce_scene(ShapeKind shape) {
  // bounce_scene's drop at e = 1, for 20 bounces: a flight from 1 m and back is 2 √(2 h / g)
  // = 0.903 s, the twentieth apex 18.1 s after release
  const bool sphere = shape == ShapeKind::Sphere;
  const std::string what = sphere ? "sphere" : "box";
  Scene scene = bounce_scene(1.0);
  scene.name = "bounce-e1-" + what;
  scene.description =
      std::string(sphere ? "a sphere of radius 0.5 m (1 kg)" : "a unit box dropped flat") +
      " dropped from rest, its lowest point 1 m above the ground, restitution 1 on body and "
      "ground: every one of 20 bounces reaches 1 m again (closed form)";
  scene.duration = 18.5;
  if (sphere) {
    BodySpec& ball = scene.bodies.back();
    ball.name = "ball";
    ball.shape.kind = ShapeKind::Sphere;
    ball.shape.radius = kHalf;
  }
  return scene;
}

Scene rolling_scene(bool sliding) {
  // a solid sphere (radius 0.5 m, 1 kg) on the ground, μ = 0.3: launched sliding at v0 = 5 m/s
  // without spin it rolls at 5/7 v0 from t = 2 v0 / (7 μ g) = 0.485 s; launched rolling at
  // 3 m/s it rolls on at 3 m/s
  constexpr double kFriction = 0.3, kRadius = 0.5;
  const double v0 = sliding ? 5.0 : 3.0;
  Scene scene = contact_scene(
      sliding ? "roll-slide" : "roll-keep",
      sliding ? "a solid sphere (r = 0.5 m, 1 kg) launched sliding at 5 m/s without spin on the "
                "ground, μ = 0.3: it rolls at 5/7 of 5 m/s from 2 v0 / (7 μ g) = 0.485 s on "
                "(closed form)"
              : "a solid sphere (r = 0.5 m, 1 kg) rolling on the ground at 3 m/s (ω = v / r), "
                "μ = 0.3: it rolls on at 3 m/s, losing no speed and gaining no spin (closed form)",
      sliding ? 2.0 : 5.0);
  scene.bodies.push_back(ground(kFriction));
  BodySpec ball = unit_box("ball", Vec3(0.0, kRadius, 0.0), kFriction);
  ball.shape.kind = ShapeKind::Sphere;
  ball.shape.radius = kRadius;
  ball.linear_velocity = Vec3(v0, 0.0, 0.0);
  // rolling towards +x turns about −z
  if (!sliding) ball.angular_velocity = Vec3(0.0, 0.0, -v0 / kRadius);
  scene.bodies.push_back(ball);
  scene.probe.interval = scene.dt;  // the time rolling starts is found between samples
  scene.probe.metrics = {Metric::Rolling, Metric::Penetration, Metric::Energy};
  return scene;
}

Scene cradle_scene(int balls) {
  // balls of radius 0.5 m (1 kg) in a row along x, each touching the next, the first 1 m behind
  // the row moving at 2 m/s; e = 1, μ = 0, no gravity
  constexpr double kRadius = 0.5, kSpeed = 2.0;
  Scene scene = contact_scene(
      "cradle-" + std::to_string(balls),
      "a row of " + std::to_string(balls - 1) +
          " touching spheres (r = 0.5 m, 1 kg) struck along its line by one more at 2 m/s, "
          "e = 1, μ = 0, no gravity: are momentum and energy kept, and which classical answer "
          "is given (the last ball leaves, or the row leaves as one)?",
      2.0);
  scene.gravity = Vec3::Zero();
  for (int i = 0; i < balls; ++i) {
    // the striker at x = −2 (its surface 1 m from the row's first), the row from x = 0
    const double x = i == 0 ? -2.0 : (i - 1) * 2.0 * kRadius;
    BodySpec ball = unit_box(i == 0 ? "striker" : "ball" + std::to_string(i), Vec3(x, 0.0, 0.0),
                             0.0, 1.0);
    ball.shape.kind = ShapeKind::Sphere;
    ball.shape.radius = kRadius;
    if (i == 0) ball.linear_velocity = Vec3(kSpeed, 0.0, 0.0);
    scene.bodies.push_back(ball);
  }
  scene.probe.interval = scene.dt;
  scene.probe.metrics = {Metric::Elastic, Metric::Penetration, Metric::Energy,
                         Metric::LinearMomentum};
  return scene;
}

Scene offcentre_impact_scene() {
  // box a turned 45° about z, so that an edge leads along +x at the height of its centre, at
  // 2 m/s towards box b at rest, 0.2 m above a's line: the edge meets b's face at one line, off
  // b's centre. Closed form (one impulse J along x at r = (−0.5, −0.2) from b's centre, none on
  // a's turn): J = 2 v / (2 + 0.2² · 6) = 1.786 N s; a leaves at 0.214 m/s, b at 1.786 m/s
  // turning at 2.14 rad/s about +z, and the energy, 2 J, is kept. b's corners then move at most
  // 1.51 m/s about its centre, slower than it draws away: they do not meet again
  Scene scene = contact_scene(
      "impact-offcentre",
      "a unit box turned 45° about z, an edge leading, at 2 m/s into a unit box at rest 0.2 m off "
      "its line, e = 1, μ = 0, no gravity: are linear and angular momentum and energy kept?",
      1.5);
  scene.gravity = Vec3::Zero();
  BodySpec a = unit_box("striker", Vec3(-2.0, 0.0, 0.0), 0.0, 1.0);
  a.orientation = Quat(Eigen::AngleAxisd(M_PI / 4.0, Vec3::UnitZ()));
  a.linear_velocity = Vec3(2.0, 0.0, 0.0);
  scene.bodies.push_back(a);
  scene.bodies.push_back(unit_box("struck", Vec3(0.0, 0.2, 0.0), 0.0, 1.0));
  scene.probe.interval = scene.dt;
  scene.probe.metrics = {Metric::Elastic, Metric::Penetration, Metric::Energy,
                         Metric::LinearMomentum, Metric::AngularMomentum};
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

// Boxes spawned into one another, as a spawner does by accident: a 4 × 4 × 4 block of 64 unit
// boxes 0.6 m apart centre to centre, so each is 0.4 m into each neighbour along every axis,
// tilted a little, the bottom layer 0.2 m into the ground, μ = 0.6. Every engine must push them
// apart: what does a step cost while it does, and how much speed and energy does it add?
Scene overlap_heap_scene() {
  constexpr double kFriction = 0.6, kSpacing = 0.6, kSunk = 0.2, kTilt = 0.1;
  constexpr int kSide = 4;
  Scene scene = contact_scene(
      "overlap-heap",
      "64 unit boxes spawned 0.6 m apart (0.4 m into each neighbour), the bottom layer 0.2 m into "
      "the ground, μ = 0.6: what does a step cost while each engine pushes them apart, and how much "
      "speed and energy does that add?",
      3.0);
  scene.planar = false;
  scene.bodies.push_back(ground(kFriction));
  std::uint64_t counter = 64;
  for (int layer = 0; layer < kSide; ++layer)
    for (int i = 0; i < kSide; ++i)
      for (int k = 0; k < kSide; ++k) {
        const Vec3 at((i - 0.5 * (kSide - 1)) * kSpacing, kHalf - kSunk + layer * kSpacing,
                      (k - 0.5 * (kSide - 1)) * kSpacing);
        BodySpec b = unit_box("h" + std::to_string(layer) + "." + std::to_string(i) + "." +
                                  std::to_string(k),
                              at, kFriction);
        b.orientation = tilt(counter++ * 0x100, kTilt, false);
        scene.bodies.push_back(b);
      }
  scene.probe.metrics = {Metric::Penetration, Metric::Energy};
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

Scene rain_scene(bool planar) {
  // 0.5 m boxes, 1 kg, μ = 0.6, in a lattice 0.9 m apart (each tilted up to 20°, so its bounds
  // reach at most 0.42 m: no two start touching), from 1 m above the floor upwards, each layer
  // shifted half a spacing from the one below (±0.225 m) so that boxes land on the gaps and
  // tumble rather than stand in columns; the walls 0.5 m thick, their tops at the rim
  constexpr double kHalfBox = 0.25, kSpacing = 0.9, kLowest = 1.0, kWallHalf = 0.25,
                   kFriction = 0.6, kTilt = 20.0 * M_PI / 180.0;
  const int columns = planar ? 8 : 5, layers = planar ? 12 : 8;
  const double inner_half = planar ? 4.0 : 2.5, rim = planar ? 6.0 : 4.0, stagger = 0.25 * kSpacing;
  const int count = (planar ? columns : columns * columns) * layers;
  std::ostringstream description;
  description << count << " boxes of 0.5 m (1 kg, μ = 0.6), tilted up to 20°, falling from rest in "
              << "a lattice 0.9 m apart, each layer shifted half a spacing (1 m to "
              << kLowest + (layers - 1) * kSpacing << " m up) into a "
              << (planar ? "trough " : "box ") << 2.0 * inner_half << " m "
              << (planar ? "wide" : "square") << " with " << (planar ? "two" : "four")
              << " static walls " << rim << " m high, for 8 s"
              << (planar ? " (the planar twin of rain: all motion in XY, walls at ±x only)" : "")
              << ": does every box end inside, at rest, and at what cost per step?";
  Scene scene = contact_scene(planar ? "rain-planar" : "rain", description.str(), 8.0);
  scene.planar = planar;
  scene.bodies.push_back(ground(kFriction));
  // the walls: at ±x, and in 3D at ±z too, each long enough to close the corners; the planar
  // twin's walls reach 50 m either side of z = 0, so that a box a 3D engine lets wander out of
  // the plane stays between them (with 1 m, boxes walked round the walls' ends on three engines)
  auto wall = [&](const std::string& name, const Vec3& centre, const Vec3& half) {
    BodySpec w;
    w.name = name;
    w.shape.kind = ShapeKind::Box;
    w.shape.half_extents = half;
    w.mass = 0.0;
    w.position = centre;
    w.friction = kFriction;
    scene.bodies.push_back(w);
  };
  const double across = inner_half + 2.0 * kWallHalf, side = inner_half + kWallHalf;
  const double depth = planar ? 50.0 : across;
  wall("wall-x-", Vec3(-side, 0.5 * rim, 0.0), Vec3(kWallHalf, 0.5 * rim, depth));
  wall("wall-x+", Vec3(side, 0.5 * rim, 0.0), Vec3(kWallHalf, 0.5 * rim, depth));
  if (!planar) {
    wall("wall-z-", Vec3(0.0, 0.5 * rim, -side), Vec3(across, 0.5 * rim, kWallHalf));
    wall("wall-z+", Vec3(0.0, 0.5 * rim, side), Vec3(across, 0.5 * rim, kWallHalf));
  }
  std::uint64_t counter = 18;
  for (int layer = 0; layer < layers; ++layer)
    for (int i = 0; i < columns; ++i)
      for (int k = 0; k < (planar ? 1 : columns); ++k) {
        const double shift = layer % 2 ? stagger : -stagger;
        const double x = (i - 0.5 * (columns - 1)) * kSpacing + shift;
        const double z = planar ? 0.0 : (k - 0.5 * (columns - 1)) * kSpacing + shift;
        std::ostringstream name;
        name << 'l' << layer << 'c' << i << '.' << k;
        BodySpec b = unit_box(name.str(), Vec3(x, kLowest + layer * kSpacing, z), kFriction);
        b.shape.half_extents = Vec3::Constant(kHalfBox);
        b.orientation = tilt(counter++ * 0x100, kTilt, planar);
        scene.bodies.push_back(b);
      }
  scene.probe.interval = 2.0 * scene.dt;  // impacts last a few steps: sampled every other step
  scene.probe.metrics = {Metric::Confined, Metric::Penetration, Metric::Energy};
  return scene;
}

std::vector<Scenario> contact_scenarios() {
  std::vector<Scenario> all;
  for (int boxes : {10, 20}) {
    Scenario s{"tower-" + std::to_string(boxes),
               "does a tower of " + std::to_string(boxes) +
                   " unit boxes (μ = 0.6) stand for 10 s: drift, sink, cost?",
               [boxes] { return tower_scene(boxes); }};
    // the 20-box tower also at 1, 2, 4 and 8 substeps, and at 20 iterations (twice Bullet's,
    // Jolt's, Rapier's and Box2D's 10; PhysX's position iterations, five times its 4; an engine
    // without the knob says unsupported), on every engine:
    // what each engine needs to hold it, read at its best knobs (the pyramids' grid costs a peer
    // minutes a job: run it with --sweep-substeps, as docs/runs/ does)
    if (boxes == 20) {
      s.sweep_substeps = {1, 2, 4, 8};
      s.sweep_iterations = {20};
    }
    all.push_back(s);
  }
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
  all.push_back({"many-pyramids",
                 "do 196 pyramids of 55 boxes (Box3D's many_pyramids) stand, and what does a step "
                 "of many islands cost?",
                 [] { return many_pyramids_scene(14, 10); }});
  for (double e : {0.2, 0.5, 0.8})
    all.push_back({"bounce-e" + tag(e),
                   "do a dropped box's apexes fall as e^(2n) at e = " + tag(e) + "?",
                   [e] { return bounce_scene(e); }});
  for (ShapeKind shape : {ShapeKind::Box, ShapeKind::Sphere}) {
    const std::string what = shape == ShapeKind::Sphere ? "sphere" : "box";
    all.push_back({"bounce-e1-" + what,
                   "does a " + what + " dropped with e = 1 reach its release height on each of 20 "
                   "bounces?",
                   [shape] { return elastic_bounce_scene(shape); }});
  }
  all.push_back({"roll-slide",
                 "does a sphere launched sliding roll at 5/7 of its speed, from the closed form's "
                 "time?",
                 [] { return rolling_scene(true); }});
  all.push_back({"roll-keep", "does a rolling sphere roll on without losing speed?",
                 [] { return rolling_scene(false); }});
  all.push_back({"cradle-5",
                 "does a struck row of elastic spheres keep momentum and energy, and which "
                 "classical answer does it give?",
                 [] { return cradle_scene(5); }});
  all.push_back({"impact-offcentre",
                 "does an off-centre elastic impact of two boxes keep linear and angular "
                 "momentum and energy?",
                 offcentre_impact_scene});
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
  all.push_back({"overlap-heap",
                 "64 boxes spawned deep into one another: what does pushing them apart cost a "
                 "step, and how much speed and energy does it add?",
                 overlap_heap_scene});
  for (double hz : {30.0, 60.0, 120.0})
    all.push_back({"tunnelling-" + tag(hz),
                   "does a small box at 50 m/s pass through a 5 cm wall at " + tag(hz) + " Hz?",
                   [hz] { return tunnelling_scene(hz); }});
  all.push_back({"head-on", "do two equal boxes exchange velocities in an elastic collision?",
                 head_on_scene});
  all.push_back({"rain",
                 "do 200 boxes rained into a four-walled box all end inside it, at rest, and what "
                 "does a step cost while the contact set changes?",
                 [] { return rain_scene(false); }});
  all.push_back({"rain-planar",
                 "the same in the XY plane (96 boxes, two walls), so Box2D runs it too",
                 [] { return rain_scene(true); }});
  return all;
}

}  // namespace physbench
