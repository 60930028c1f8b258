#include "physbench/scenarios.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

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

Scene spring_oscillator_scene(double damping) {
  Scene scene;
  scene.name = damping > 0.0 ? "spring-oscillator-damped" : "spring-oscillator";
  scene.description =
      "a 1 kg box on a k = 100 N/m spring (rest length 1 m) to a fixed anchor, released 0.1 m "
      "stretched, no gravity" +
      std::string(damping > 0.0 ? "; damping c = 2 N s/m (ζ = 0.1)" : "");
  scene.gravity = Vec3::Zero();
  scene.dt = 1.0 / 120.0;
  scene.duration = 10.0;
  scene.planar = true;  // motion along x: every engine, Box2D included, can run it
  scene.collisions = false;
  BodySpec box;
  box.name = "mass";
  box.shape.half_extents = Vec3(0.1, 0.1, 0.1);
  box.mass = 1.0;
  box.position = Vec3(1.1, 0.0, 0.0);
  scene.bodies.push_back(box);
  SpringSpec spring;
  spring.body_a = 0;
  spring.point_b = Vec3::Zero();
  spring.stiffness = 100.0;
  spring.damping = damping;
  spring.rest_length = 1.0;
  scene.springs.push_back(spring);
  // with damping the energy falls by design: only the undamped oscillator measures its drift
  scene.probe.metrics = damping > 0.0 ? std::vector<Metric>{Metric::Position}
                                      : std::vector<Metric>{Metric::Position, Metric::Energy};
  scene.reference.kind = ReferenceKind::Oscillator;
  return scene;
}

Scene spring_cube_scene() {
  Scene scene;
  scene.name = "spring-cube";
  scene.description =
      "the seed's cube: a 1 m, 1 kg cube hung by one corner from a spring (k = 50 N/m, c = 0.2 N "
      "s/m, rest 1 m) "
      "under gravity, released tilted so it swings and turns";
  scene.gravity = Vec3(0.0, -9.81, 0.0);
  scene.dt = 1.0 / 120.0;
  scene.duration = 5.0;
  scene.collisions = false;
  BodySpec cube;
  cube.name = "cube";
  cube.shape.half_extents = Vec3(0.5, 0.5, 0.5);
  cube.mass = 1.0;
  cube.position = Vec3(0.8, 0.2, 0.3);
  cube.orientation = Quat(Eigen::AngleAxisd(0.4, Vec3(1.0, 0.0, 1.0).normalized()));
  scene.bodies.push_back(cube);
  SpringSpec spring;
  spring.body_a = 0;
  spring.local_point_a = Vec3(0.5, 0.5, 0.5);  // a corner
  spring.point_b = Vec3(0.0, 2.0, 0.0);
  spring.stiffness = 50.0;
  spring.damping = 0.2;
  spring.rest_length = 1.0;
  scene.springs.push_back(spring);
  scene.probe.metrics = {Metric::Position, Metric::Orientation};
  scene.reference.kind = ReferenceKind::Converged;
  scene.reference.dt_divisor = 32;
  return scene;
}

Scene spring_chain_scene(int links) {
  constexpr double kMass = 0.5, kStiffness = 400.0, kRest = 0.3, kHalf = 0.1;
  Scene scene;
  scene.name = "spring-chain";
  scene.description =
      "a chain of " + std::to_string(links) +
      " 0.2 m, 0.5 kg cubes joined centre-top to centre-bottom by springs (k = 400 N/m, "
      "c = 0.5 N s/m, rest 0.3 m) hanging at rest from a fixed anchor; the bottom cube is kicked "
      "sideways at 1 m/s. Planar, and in the near-linear regime, so trajectories stay comparable";
  scene.gravity = Vec3(0.0, -9.81, 0.0);
  scene.dt = 1.0 / 120.0;
  scene.duration = 5.0;
  scene.planar = true;
  scene.collisions = false;
  double top = 0.0;  // the y of the attachment point above the next cube
  for (int i = 0; i < links; ++i) {
    // at equilibrium spring i carries the weight of every cube from i down
    const double stretch = (links - i) * kMass * -scene.gravity.y() / kStiffness;
    const double centre = top - kRest - stretch - kHalf;
    BodySpec cube;
    cube.name = "link" + std::to_string(i);
    cube.shape.half_extents = Vec3(kHalf, kHalf, kHalf);
    cube.mass = kMass;
    cube.position = Vec3(0.0, centre, 0.0);
    if (i == links - 1) cube.linear_velocity = Vec3(1.0, 0.0, 0.0);
    scene.bodies.push_back(cube);
    SpringSpec spring;
    spring.body_a = i;
    spring.local_point_a = Vec3(0.0, kHalf, 0.0);
    spring.body_b = i == 0 ? -1 : i - 1;
    spring.point_b = i == 0 ? Vec3::Zero() : Vec3(0.0, -kHalf, 0.0);
    spring.stiffness = kStiffness;
    spring.damping = 0.5;
    spring.rest_length = kRest;
    scene.springs.push_back(spring);
    top = centre - kHalf;
  }
  scene.probe.metrics = {Metric::Position, Metric::Orientation};
  scene.reference.kind = ReferenceKind::Converged;
  scene.reference.dt_divisor = 32;
  return scene;
}

Scene symmetric_top_scene() {
  Scene scene;
  scene.name = "symmetric-top";
  scene.description =
      "a flat 0.6 x 0.1 x 0.6 m, 1.5 kg box (a symmetric top about y) spinning at 12 rad/s about y "
      "with a "
      "3 rad/s wobble, in zero gravity: torque-free precession in closed form";
  scene.gravity = Vec3::Zero();
  scene.dt = 1.0 / 60.0;
  scene.duration = 5.0;
  scene.collisions = false;
  BodySpec top;
  top.name = "top";
  top.shape.half_extents = Vec3(0.3, 0.05, 0.3);
  top.mass = 1.5;
  top.orientation = Quat(Eigen::AngleAxisd(0.3, Vec3(1.0, 0.0, 0.5).normalized()));
  top.angular_velocity = top.orientation * Vec3(3.0, 12.0, 0.0);
  scene.bodies.push_back(top);
  scene.probe.metrics = {Metric::Orientation, Metric::Energy, Metric::AngularMomentum};
  scene.reference.kind = ReferenceKind::Ballistic;
  return scene;
}

Scene stiff_spring_scene(double stiffness) {
  // "1e4" for a power of ten, else the number as it prints
  std::ostringstream k;
  const long power = std::lround(std::log10(stiffness));
  if (std::abs(std::pow(10.0, power) - stiffness) < 1e-9 * stiffness)
    k << "1e" << power;
  else
    k << stiffness;
  Scene scene = spring_oscillator_scene(0.0);
  scene.name = "stiff-spring-k" + k.str();
  scene.description =
      "the oscillator of spring-oscillator at k = " + k.str() +
      " N/m: a hard case for explicit integrators (stable, unstable or over-damped)";
  scene.springs[0].stiffness = stiffness;
  scene.duration = 5.0;
  return scene;
}

Scene pushed_box_scene(bool planar) {
  Scene scene;
  scene.name = planar ? "pushed-box-planar" : "pushed-box";
  scene.description =
      "the seed's keyboard pushes, scheduled: a 1 x 0.5 x 0.25 m, 2 kg box at rest in zero gravity "
      "takes an "
      "impulse off its centre at 0.5 s and another at 1.5 s, so it drifts and turns";
  scene.gravity = Vec3::Zero();
  scene.dt = 1.0 / 60.0;
  scene.duration = 3.0;
  scene.planar = planar;
  scene.collisions = false;
  BodySpec box;
  box.name = "box";
  box.shape.half_extents = Vec3(0.5, 0.25, 0.125);
  box.mass = 2.0;
  scene.bodies.push_back(box);
  // a push up at the right end, then one back and sideways at the top left corner
  scene.impulses.push_back({0.5, 0, Vec3(0.0, 2.0, 0.0), Vec3(0.5, 0.0, planar ? 0.0 : 0.125)});
  scene.impulses.push_back({1.5, 0, Vec3(-1.0, 0.0, planar ? 0.0 : 1.0), Vec3(-0.3, 0.6, 0.0)});
  scene.probe.metrics = {Metric::Position, Metric::Orientation, Metric::LinearMomentum};
  scene.reference.kind = ReferenceKind::Converged;
  scene.reference.dt_divisor = 32;
  return scene;
}

Scene particles_bounce_scene() {
  Scene scene;
  scene.name = "particles-bounce";
  scene.description =
      "one particle dropped from 1 m onto a plane with restitution 0.8: apex n is 0.8^(2n) m";
  scene.dt = 1.0 / 120.0;
  scene.duration = 3.0;
  scene.planar = true;  // a vertical drop: Box2D can run it too
  ParticleSetSpec p;
  p.count = 1;
  p.spawn_min = p.spawn_max = Vec3(0.0, 1.0, 0.0);
  p.planes = {ParticlePlaneSpec{}};
  p.restitution = 0.8;
  scene.particles = p;
  scene.probe.metrics = {Metric::Position};
  scene.reference.kind = ReferenceKind::Bounce;
  return scene;
}

Scene particles_orbit_scene() {
  constexpr double kStrength = 10.0, kRadius = 2.0;
  Scene scene;
  scene.name = "particles-orbit";
  scene.description =
      "one particle on a circular orbit of 2 m about an attractor (s = 10 m³/s²), two periods";
  scene.gravity = Vec3::Zero();
  scene.dt = 1.0 / 60.0;
  scene.duration = 2.0 * 2.0 * M_PI * std::sqrt(kRadius * kRadius * kRadius / kStrength);
  scene.planar = true;  // the orbit lies in the XY plane: Box2D can run it too
  ParticleSetSpec p;
  p.count = 1;
  p.spawn_min = p.spawn_max = Vec3(kRadius, 0.0, 0.0);
  p.velocity_min = p.velocity_max = Vec3(0.0, std::sqrt(kStrength / kRadius), 0.0);
  p.attractors = {{Vec3::Zero(), kStrength}};
  p.softening = 1e-4;  // ε² / r² = 2.5e-9: far below any integrator's error here
  scene.particles = p;
  scene.probe.metrics = {Metric::Position, Metric::Energy};
  scene.reference.kind = ReferenceKind::Orbit;
  return scene;
}

namespace {

// the seed's three tilted planes, meeting under the middle of the scene like a shallow bowl
constexpr long kViewerParticles = 200;

std::vector<ParticlePlaneSpec> seed_planes() {
  return {{Vec3::Zero(), Vec3(0.25, 1.0, 0.0).normalized()},
          {Vec3::Zero(), Vec3(-0.25, 1.0, 0.1).normalized()},
          {Vec3::Zero(), Vec3(0.0, 1.0, -0.25).normalized()}};
}

// The seed modes' probed particles: an even sample of n across the set, so the replay viewer
// (docs/viewer.md) draws the mode's shape; the particle modes ask for throughput only, so no
// metric reads them, and sampling is outside the timed stepping
std::vector<long> particle_sample(long count, long n) {
  std::vector<long> sample;
  for (long i = 0; i < std::min(count, n); ++i) sample.push_back(i * count / std::min(count, n));
  return sample;
}

// the planar twins answer throughput only and have no replay: their first four particles
Scene planar_probe(Scene scene) {
  scene.particles->probe = {0, 1, 2, 3};
  return scene;
}

}  // namespace

Scene particles_attractors_scene(long count) {
  Scene scene;
  scene.name = "particles-attractors";
  scene.description =
      "the seed's first mode: particles orbit two attracting and one repelling force point above "
      "three tilted planes, bouncing off them, with air drag";
  scene.dt = 1.0 / 60.0;
  scene.duration = 3.0;
  ParticleSetSpec p;
  p.count = count;
  p.spawn_min = Vec3(-3.0, 2.0, -3.0);
  p.spawn_max = Vec3(3.0, 5.0, 3.0);
  p.velocity_min = Vec3(-1.0, -1.0, -1.0);
  p.velocity_max = Vec3(1.0, 1.0, 1.0);
  p.drag = 0.1;
  p.attractors = {
      {Vec3(-2.0, 3.0, 0.0), 20.0}, {Vec3(2.0, 3.0, 1.0), 15.0}, {Vec3(0.0, 4.0, -2.0), -10.0}};
  p.softening = 0.2;
  p.planes = seed_planes();
  p.restitution = 0.6;
  p.friction = 0.1;
  p.probe = particle_sample(count, kViewerParticles);
  scene.particles = p;
  scene.probe.metrics = {};
  return scene;
}

Scene particles_snow_scene(long count) {
  Scene scene;
  scene.name = "particles-snow";
  scene.description =
      "the seed's snow: no rebound (restitution 0, full friction) so flakes stick, wind drift with "
      "a per-flake offset, and flakes melt after 6 s and fall again from the sky";
  scene.dt = 1.0 / 60.0;
  scene.duration = 5.0;
  ParticleSetSpec p;
  p.count = count;
  p.spawn_min = Vec3(-5.0, 8.0, -5.0);
  p.spawn_max = Vec3(5.0, 10.0, 5.0);
  p.velocity_min = Vec3(0.0, -1.0, 0.0);
  p.velocity_max = Vec3(0.0, -0.5, 0.0);
  p.drag = 1.0;
  p.wind = Vec3(1.0, 0.0, 0.3);
  p.wind_jitter = 0.5;
  p.planes = {ParticlePlaneSpec{}};
  p.restitution = 0.0;
  p.friction = 1.0;
  p.lifetime = 6.0;
  p.probe = particle_sample(count, kViewerParticles);
  scene.particles = p;
  scene.probe.metrics = {};
  return scene;
}

Scene particles_plume_scene(long count) {
  Scene scene;
  scene.name = "particles-plume";
  scene.description =
      "the seed's plume: particles on high-friction ground are dragged toward a strong force point "
      "above it until it lifts them into a plume";
  scene.dt = 1.0 / 60.0;
  scene.duration = 4.0;
  ParticleSetSpec p;
  p.count = count;
  p.spawn_min = Vec3(-4.0, 0.0, -4.0);
  p.spawn_max = Vec3(4.0, 0.05, 4.0);
  p.drag = 0.05;
  p.attractors = {{Vec3(0.0, 3.0, 0.0), 60.0}};
  p.softening = 0.3;
  p.planes = {ParticlePlaneSpec{}};
  p.restitution = 0.2;
  p.friction = 0.9;
  p.probe = particle_sample(count, kViewerParticles);
  scene.particles = p;
  scene.probe.metrics = {};
  return scene;
}

Scene planar_particles(Scene scene) {
  if (!scene.particles) throw std::invalid_argument(scene.name + ": no particles to make planar");
  // every position, velocity and direction seen in the XY plane: z dropped, normals renormalised
  // (a plane facing along z has no line in XY: its normal stays zero and validation names it)
  auto flat = [](Vec3 v) {
    v.z() = 0.0;
    return v;
  };
  scene.name += "-planar";
  scene.description += "; in the XY plane, so Box2D can run it too";
  scene.planar = true;
  scene.gravity = flat(scene.gravity);
  ParticleSetSpec& p = *scene.particles;
  p.spawn_min = flat(p.spawn_min);
  p.spawn_max = flat(p.spawn_max);
  p.velocity_min = flat(p.velocity_min);
  p.velocity_max = flat(p.velocity_max);
  p.wind = flat(p.wind);
  for (ParticleAttractor& a : p.attractors) a.position = flat(a.position);
  for (ParticlePlaneSpec& plane : p.planes) {
    plane.point = flat(plane.point);
    const Vec3 normal = flat(plane.normal);
    plane.normal = normal.norm() > 0.0 ? Vec3(normal.normalized()) : normal;
  }
  return scene;
}

std::vector<double> standard_dt_sweep() {
  return {1.0 / 30.0, 1.0 / 60.0, 1.0 / 120.0, 1.0 / 240.0, 1.0 / 480.0, 1.0 / 960.0};
}

const std::vector<Scenario>& scenarios() {
  static const std::vector<Scenario> list = [] {
    std::vector<Scenario> all = {
        {"projectile",
         "how far does each integrator put a thrown box from the closed-form parabola?",
         projectile_scene},
        {"projectile-planar", "the same question in the plane, so Box2D can answer it",
         projectile_planar_scene},
        {"tumbling-box",
         "does each engine keep a free body's energy and angular momentum, and follow the "
         "converged "
         "tumble?",
         tumbling_box_scene, standard_dt_sweep()},
        {"symmetric-top", "does each engine precess a spinning top at the closed-form rate?",
         symmetric_top_scene, standard_dt_sweep()},
        {"spring-oscillator",
         "how far from the closed-form oscillation does each integrator drift, and at what cost?",
         [] { return spring_oscillator_scene(0.0); }, standard_dt_sweep()},
        {"spring-oscillator-damped", "the same with damping (ζ = 0.1): is the decay rate right?",
         [] { return spring_oscillator_scene(2.0); }, standard_dt_sweep()},
        {"spring-cube",
         "a spring at a body point: does the torque r × F turn the cube as the converged run does?",
         spring_cube_scene, standard_dt_sweep()},
        {"spring-chain", "coupled springs: how does error grow along a chain?",
         [] { return spring_chain_scene(8); }, standard_dt_sweep()},
    };
    all.push_back({"pushed-box",
                   "do impulses at a point change linear and angular momentum by J and r x J?",
                   [] { return pushed_box_scene(false); }});
    all.push_back({"pushed-box-planar", "the same in the plane, so Box2D can answer it",
                   [] { return pushed_box_scene(true); }});
    all.push_back({"particles-bounce", "do bounce apexes fall as e^(2n), as the closed form says?",
                   particles_bounce_scene, standard_dt_sweep()});
    all.push_back({"particles-orbit",
                   "how far off a circular orbit does each integrator drift, and at what cost?",
                   particles_orbit_scene, standard_dt_sweep()});
    all.push_back({"particles-attractors",
                   "how many particle-steps per second, in the seed's attractor mode?",
                   [] { return particles_attractors_scene(10000); }});
    all.push_back({"particles-snow",
                   "how many particle-steps per second with ageing and recycling (snow)?",
                   [] { return particles_snow_scene(10000); }});
    all.push_back({"particles-plume",
                   "how many particle-steps per second in the seed's plume mode?",
                   [] { return particles_plume_scene(10000); }});
    all.push_back({"particles-attractors-planar",
                   "the attractor mode in the XY plane: particle-steps per second with Box2D too",
                   [] { return planar_probe(planar_particles(particles_attractors_scene(2000))); }});
    all.push_back({"particles-plume-planar",
                   "the plume mode in the XY plane: particle-steps per second with Box2D too",
                   [] { return planar_probe(planar_particles(particles_plume_scene(2000))); }});
    // particle throughput against count: the seed's attractor mode at 10^4 … 4·10^6 particles
    for (long count : {10000L, 100000L, 1000000L, 4000000L}) {
      Scenario s;
      s.name = "particles-scaling-" + std::to_string(count);
      s.question =
          "how many particle-steps per second at this count, against the memory-bandwidth "
          "roofline?";
      s.build = [count] {
        Scene scene = particles_attractors_scene(count);
        scene.name = "particles-scaling-" + std::to_string(count);
        scene.duration = 0.1;  // six steps: enough to time, short enough for Bullet at 10^5
        scene.particles->probe = {0, 1, 2, 3};  // a throughput question: no replay sample
        return scene;
      };
      s.family = "particles-scaling";
      s.parameter_name = "particles";
      s.parameter = static_cast<double>(count);
      all.push_back(s);
    }
    // the stiff-spring stability map: k × dt, every engine and variant
    for (double k : {1e2, 1e3, 1e4, 1e5, 1e6}) {
      Scenario s;
      s.name = stiff_spring_scene(k).name;
      s.question =
          "which engines and integrators hold a stiff spring at this k, over dt = 1/30 … 1/240?";
      s.build = [k] { return stiff_spring_scene(k); };
      s.sweep_dt = {1.0 / 30.0, 1.0 / 60.0, 1.0 / 120.0, 1.0 / 240.0};
      s.family = "stiff-spring";
      s.parameter_name = "stiffness k (N/m)";
      s.parameter = k;
      all.push_back(s);
    }
    for (Scenario& s : contact_scenarios()) all.push_back(std::move(s));
    return all;
  }();
  return list;
}

const Scenario* find_scenario(const std::string& name) {
  for (const Scenario& s : scenarios())
    if (s.name == name) return &s;
  return nullptr;
}

}  // namespace physbench
