#include "physbench/scene.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>

namespace physbench {

long Scene::step_count() const { return std::lround(duration / dt); }

bool Scene::has_contacts() const { return collisions && bodies.size() > 1; }

int Scene::probe_every_steps() const {
  return std::max(1, static_cast<int>(std::lround(probe.interval / dt)));
}

std::vector<int> Scene::probed_bodies() const {
  std::vector<int> probed = probe.bodies;
  if (probed.empty())
    for (int i = 0; i < static_cast<int>(bodies.size()); ++i)
      if (bodies[i].mass > 0.0) probed.push_back(i);
  // probed particles follow the bodies
  if (particles)
    for (long p : particles->probe) probed.push_back(static_cast<int>(bodies.size() + p));
  return probed;
}

Vec3 principal_inertia(const Shape& shape, double mass) {
  switch (shape.kind) {
    case ShapeKind::Box: {
      // solid cuboid: I_x = m (b² + c²) / 3 with half extents a, b, c
      const Vec3 e2 = shape.half_extents.cwiseProduct(shape.half_extents);
      return mass / 3.0 * Vec3(e2.y() + e2.z(), e2.x() + e2.z(), e2.x() + e2.y());
    }
    case ShapeKind::Sphere:
      return Vec3::Constant(0.4 * mass * shape.radius * shape.radius);
    case ShapeKind::Plane:
      return Vec3::Zero();
  }
  return Vec3::Zero();
}

std::optional<int> symmetry_axis(const Vec3& inertia) {
  auto equal = [](double a, double b) {
    return std::abs(a - b) <= 1e-12 * std::max(std::abs(a), std::abs(b));
  };
  if (equal(inertia.x(), inertia.y())) return 2;
  if (equal(inertia.x(), inertia.z())) return 1;
  if (equal(inertia.y(), inertia.z())) return 0;
  return std::nullopt;
}

const char* to_string(ShapeKind kind) {
  switch (kind) {
    case ShapeKind::Box:
      return "box";
    case ShapeKind::Sphere:
      return "sphere";
    case ShapeKind::Plane:
      return "plane";
  }
  return "?";
}

const char* to_string(ReferenceKind kind) {
  switch (kind) {
    case ReferenceKind::None:
      return "none";
    case ReferenceKind::Ballistic:
      return "ballistic";
    case ReferenceKind::Oscillator:
      return "oscillator";
    case ReferenceKind::Orbit:
      return "orbit";
    case ReferenceKind::Bounce:
      return "bounce";
    case ReferenceKind::Converged:
      return "converged";
  }
  return "?";
}

double pair_friction(const BodySpec& a, const BodySpec& b) {
  return std::sqrt(a.friction * b.friction);
}

double pair_restitution(const BodySpec& a, const BodySpec& b) {
  return std::max(a.restitution, b.restitution);
}

const std::vector<Metric>& all_metrics() {
  static const std::vector<Metric> all = {
      Metric::Position,   Metric::Orientation, Metric::Energy,     Metric::LinearMomentum,
      Metric::AngularMomentum, Metric::StackDrift, Metric::Penetration, Metric::BounceApex,
      Metric::Incline,    Metric::Exchange,    Metric::Tunnelling, Metric::Confined,
      Metric::Rolling,    Metric::Elastic};
  return all;
}

const char* to_string(Metric metric) {
  switch (metric) {
    case Metric::Position:
      return "position";
    case Metric::Orientation:
      return "orientation";
    case Metric::Energy:
      return "energy";
    case Metric::LinearMomentum:
      return "linear_momentum";
    case Metric::AngularMomentum:
      return "angular_momentum";
    case Metric::StackDrift:
      return "stack_drift";
    case Metric::Penetration:
      return "penetration";
    case Metric::BounceApex:
      return "bounce_apex";
    case Metric::Incline:
      return "incline";
    case Metric::Exchange:
      return "exchange";
    case Metric::Tunnelling:
      return "tunnelling";
    case Metric::Confined:
      return "confined";
    case Metric::Rolling:
      return "rolling";
    case Metric::Elastic:
      return "elastic";
  }
  return "?";
}

std::optional<Metric> metric_from_string(const std::string& name) {
  for (Metric m : all_metrics())
    if (name == to_string(m)) return m;
  return std::nullopt;
}

namespace {

[[noreturn]] void fail(const std::string& field, const std::string& what) {
  throw SceneError(field + ": " + what);
}

template <typename T>
std::string show(const T& value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

void require_finite(const std::string& field, double value) {
  if (!std::isfinite(value)) fail(field, "must be a finite number, got " + show(value));
}

void require_finite(const std::string& field, const Vec3& v) {
  for (int i = 0; i < 3; ++i) require_finite(field + "[" + std::to_string(i) + "]", v[i]);
}


void require_nonnegative(const std::string& field, double value) {
  require_finite(field, value);
  if (!(value >= 0.0)) fail(field, "must be >= 0, got " + show(value));
}

// a stated range, inclusive at both ends
void require_range(const std::string& field, double value, double lo, double hi,
                   const char* unit = "") {
  require_finite(field, value);
  if (!(value >= lo && value <= hi))
    fail(field, "must lie in [" + show(lo) + ", " + show(hi) + "]" + unit + ", got " + show(value));
}

// every component within ±bound
void require_bounded(const std::string& field, const Vec3& v, double bound, const char* unit) {
  for (int i = 0; i < 3; ++i)
    require_range(field + "[" + std::to_string(i) + "]", v[i], -bound, bound, unit);
}

void require_count(const std::string& field, std::size_t count, std::size_t cap,
                   const char* why) {
  if (count > cap)
    fail(field, "has " + std::to_string(count) + " entries, over the cap of " +
                    std::to_string(cap) + " (" + why + ")");
}

// names become parts of file names: letters, digits, '-', '_', '.', starting with a letter or digit
void require_file_name(const std::string& field, const std::string& name) {
  if (name.empty()) fail(field, "must not be empty");
  if (name.size() > limits::kNameLength)
    fail(field, "is " + std::to_string(name.size()) + " bytes, over the cap of " +
                    std::to_string(limits::kNameLength) + " (it becomes part of file names)");
  const auto plain = [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9');
  };
  if (!plain(name[0]))
    fail(field, "must start with a letter or digit (it becomes part of file names), got \"" +
                    name + "\"");
  for (char c : name)
    if (!plain(c) && c != '-' && c != '_' && c != '.')
      fail(field, "may hold only letters, digits, '-', '_' and '.' (it becomes part of file "
                  "names), got \"" + name + "\"");
}

// free text: no control characters (it lands in CSV cells, logs and the report)
void require_text(const std::string& field, const std::string& text, std::size_t cap) {
  if (text.size() > cap)
    fail(field, "is " + std::to_string(text.size()) + " bytes, over the cap of " +
                    std::to_string(cap));
  for (unsigned char c : text)
    if (c < 0x20 || c == 0x7f) fail(field, "must not contain control characters");
}


// the contact metrics' closed forms hold only for the scenes they describe
void validate_contact_metrics(const Scene& scene) {
  auto wants = [&](Metric metric) {
    return std::find(scene.probe.metrics.begin(), scene.probe.metrics.end(), metric) !=
           scene.probe.metrics.end();
  };
  std::vector<int> dynamic, planes, static_boxes;
  for (int i = 0; i < static_cast<int>(scene.bodies.size()); ++i) {
    const BodySpec& b = scene.bodies[i];
    if (b.mass > 0.0)
      dynamic.push_back(i);
    else if (b.shape.kind == ShapeKind::Plane)
      planes.push_back(i);
    else if (b.shape.kind == ShapeKind::Box)
      static_boxes.push_back(i);
  }
  const bool contact_metric = wants(Metric::StackDrift) || wants(Metric::Penetration) ||
                              wants(Metric::BounceApex) || wants(Metric::Incline) ||
                              wants(Metric::Exchange) || wants(Metric::Tunnelling) ||
                              wants(Metric::Confined) || wants(Metric::Rolling) ||
                              wants(Metric::Elastic);
  if (!contact_metric) return;
  if (scene.particles) fail("probe.metrics", "the contact metrics are for bodies, not particles");
  if (dynamic.empty()) fail("probe.metrics", "the contact metrics need a dynamic body");
  if (wants(Metric::BounceApex)) {
    if (dynamic.size() != 1 || planes.size() != 1)
      fail("probe.metrics", "bounce_apex needs one dynamic body and one static plane");
    const BodySpec& b = scene.bodies[dynamic[0]];
    const Vec3 normal = scene.bodies[planes[0]].orientation * Vec3::UnitY();
    if (b.linear_velocity.norm() != 0.0 || b.angular_velocity.norm() != 0.0)
      fail("bodies[" + std::to_string(dynamic[0]) + "]", "bounce_apex needs a drop from rest");
    if (scene.gravity.norm() == 0.0 || normal.cross(scene.gravity).norm() > 1e-9 * scene.gravity.norm() ||
        normal.dot(scene.gravity) >= 0.0)
      fail("gravity", "bounce_apex needs gravity straight into the plane");
  }
  if (wants(Metric::Incline)) {
    if (dynamic.size() != 1 || planes.size() != 1)
      fail("probe.metrics", "incline needs one dynamic body and one static plane");
    if (scene.gravity.norm() == 0.0) fail("gravity", "incline needs gravity");
  }
  if (wants(Metric::Exchange)) {
    if (dynamic.size() != 2) fail("probe.metrics", "exchange needs exactly two dynamic bodies");
    if (scene.gravity.norm() != 0.0) fail("gravity", "exchange holds without gravity");
  }
  if (wants(Metric::Tunnelling)) {
    if (dynamic.size() != 1 || static_boxes.empty())
      fail("probe.metrics", "tunnelling needs one dynamic body and a static box (the wall)");
    if (scene.bodies[dynamic[0]].linear_velocity.norm() == 0.0)
      fail("bodies[" + std::to_string(dynamic[0]) + "].linear_velocity",
           "tunnelling needs a moving body");
  }
  if (wants(Metric::Rolling)) {
    if (dynamic.size() != 1 || planes.size() != 1 ||
        scene.bodies[dynamic[0]].shape.kind != ShapeKind::Sphere)
      fail("probe.metrics", "rolling needs one dynamic sphere and one static plane");
    const Vec3 normal = scene.bodies[planes[0]].orientation * Vec3::UnitY();
    if (scene.gravity.norm() == 0.0 || normal.cross(scene.gravity).norm() > 1e-9 * scene.gravity.norm() ||
        normal.dot(scene.gravity) >= 0.0)
      fail("gravity", "rolling needs gravity straight into the plane");
  }
  if (wants(Metric::Elastic)) {
    if (dynamic.size() < 2) fail("probe.metrics", "elastic needs two dynamic bodies or more");
    if (scene.gravity.norm() != 0.0) fail("gravity", "elastic holds without gravity");
    if (!scene.springs.empty() || !scene.impulses.empty())
      fail("probe.metrics", "elastic needs a scene without springs or impulses");
    for (int i : dynamic)
      if (scene.bodies[i].restitution != 1.0 || scene.bodies[i].friction != 0.0)
        fail("bodies[" + std::to_string(i) + "]", "elastic needs restitution 1 and friction 0");
  }
  if (wants(Metric::Confined)) {
    if (planes.size() != 1 || static_boxes.empty())
      fail("probe.metrics",
           "confined needs one static plane (the floor) and static boxes (the walls)");
    const Vec3 g = scene.gravity;
    if (g.norm() == 0.0 || (g.cwiseAbs().maxCoeff() < g.norm() * (1.0 - 1e-12)))
      fail("gravity", "confined needs gravity along a world axis (the container's up)");
    for (int w : static_boxes)
      if (scene.bodies[w].orientation.angularDistance(Quat::Identity()) > 1e-9)
        fail("bodies[" + std::to_string(w) + "].orientation",
             "confined needs its walls aligned with the world axes");
  }
}

}  // namespace

void validate(const Scene& scene) {
  using namespace limits;
  require_file_name("name", scene.name);
  require_text("description", scene.description, kDescriptionLength);
  require_bounded("gravity", scene.gravity, kMaxGravity, " m/s²");
  require_range("dt", scene.dt, kMinDt, kMaxDt, " s");
  require_range("duration", scene.duration, kMinDt, kMaxDuration, " s");
  if (scene.duration < scene.dt)
    fail("duration", "is shorter than one step (dt = " + show(scene.dt) + ")");
  if (scene.duration / scene.dt > static_cast<double>(kMaxSteps))
    fail("duration", "is " + show(scene.duration / scene.dt) + " steps of dt, over the cap of " +
                         std::to_string(kMaxSteps) +
                         " (at a million steps a second that is minutes for one engine)");
  require_count("bodies", scene.bodies.size(), kMaxBodies,
                "ten times the largest built-in scene, pyramid-100's 5,050");
  require_count("springs", scene.springs.size(), kMaxSprings, "as many as bodies");
  require_count("impulses", scene.impulses.size(), kMaxImpulses, "one a step for 10^5 steps");
  if (scene.planar && scene.gravity.z() != 0.0) fail("gravity[2]", "must be 0 in a planar scene");

  const int body_count = static_cast<int>(scene.bodies.size());
  for (int i = 0; i < body_count; ++i) {
    const BodySpec& b = scene.bodies[i];
    const std::string at = "bodies[" + std::to_string(i) + "]";
    require_text(at + ".name", b.name, kNameLength);
    require_finite(at + ".mass", b.mass);
    if (b.mass != 0.0) require_range(at + ".mass", b.mass, kMinMass, kMaxMass, " kg (or 0: static)");
    require_bounded(at + ".position", b.position, kMaxCoordinate, " m");
    require_bounded(at + ".linear_velocity", b.linear_velocity, kMaxSpeed, " m/s");
    require_bounded(at + ".angular_velocity", b.angular_velocity, kMaxAngularSpeed, " rad/s");
    // a static body does not move: a velocity on it would be kept by some engines (a kinematic
    // body) and dropped by others, so it has one meaning, none, and is refused
    if (b.mass == 0.0 && b.linear_velocity.squaredNorm() != 0.0)
      fail(at + ".linear_velocity", "a static body (mass 0) cannot move: must be 0");
    if (b.mass == 0.0 && b.angular_velocity.squaredNorm() != 0.0)
      fail(at + ".angular_velocity", "a static body (mass 0) cannot turn: must be 0");
    require_finite(at + ".orientation", b.orientation.vec());
    require_finite(at + ".orientation", b.orientation.w());
    if (std::abs(b.orientation.norm() - 1.0) > 1e-6)
      fail(at + ".orientation",
           "must be a unit quaternion [w, x, y, z], norm is " + show(b.orientation.norm()));
    require_range(at + ".friction", b.friction, 0.0, kMaxFriction);
    require_range(at + ".restitution", b.restitution, 0.0, 1.0);
    switch (b.shape.kind) {
      case ShapeKind::Box:
        for (int k = 0; k < 3; ++k)
          require_range(at + ".shape.half_extents[" + std::to_string(k) + "]",
                        b.shape.half_extents[k], kMinSize, kMaxSize, " m");
        break;
      case ShapeKind::Sphere:
        require_range(at + ".shape.radius", b.shape.radius, kMinSize, kMaxSize, " m");
        break;
      case ShapeKind::Plane:
        if (b.mass != 0.0) fail(at + ".mass", "a plane must be static (mass 0)");
        break;
    }
    if (scene.planar) {
      // planar: the body lies in z = 0 and turns about z only
      if (b.position.z() != 0.0) fail(at + ".position[2]", "must be 0 in a planar scene");
      if (b.linear_velocity.z() != 0.0)
        fail(at + ".linear_velocity[2]", "must be 0 in a planar scene");
      if (b.angular_velocity.x() != 0.0 || b.angular_velocity.y() != 0.0)
        fail(at + ".angular_velocity", "must be about z only in a planar scene");
      if (std::abs(b.orientation.x()) > 1e-12 || std::abs(b.orientation.y()) > 1e-12)
        fail(at + ".orientation", "must be a rotation about z in a planar scene");
    }
  }

  for (int i = 0; i < static_cast<int>(scene.springs.size()); ++i) {
    const SpringSpec& s = scene.springs[i];
    const std::string at = "springs[" + std::to_string(i) + "]";
    if (s.body_a < 0 || s.body_a >= body_count)
      fail(at + ".body_a", "no body " + std::to_string(s.body_a) + " (the scene has " +
                               std::to_string(body_count) + ")");
    if (s.body_b < -1 || s.body_b >= body_count)
      fail(at + ".body_b", "no body " + std::to_string(s.body_b) + " (-1 anchors to the world)");
    if (s.body_b == s.body_a) fail(at + ".body_b", "a spring needs two different ends");
    require_bounded(at + ".local_point_a", s.local_point_a, kMaxCoordinate, " m");
    require_bounded(at + ".point_b", s.point_b, kMaxCoordinate, " m");
    require_range(at + ".stiffness", s.stiffness, 0.0, kMaxStiffness, " N/m");
    require_range(at + ".damping", s.damping, 0.0, kMaxDamping, " N s/m");
    require_range(at + ".rest_length", s.rest_length, 0.0, kMaxCoordinate, " m");
  }

  for (int i = 0; i < static_cast<int>(scene.impulses.size()); ++i) {
    const ImpulseSpec& p = scene.impulses[i];
    const std::string at = "impulses[" + std::to_string(i) + "]";
    require_finite(at + ".time", p.time);
    if (p.time < 0.0 || p.time >= scene.duration)
      fail(at + ".time", "must lie in [0, duration), got " + show(p.time));
    if (p.body < 0 || p.body >= body_count || scene.bodies[p.body].mass == 0.0)
      fail(at + ".body", "no dynamic body " + std::to_string(p.body));
    require_bounded(at + ".impulse", p.impulse, kMaxImpulse, " N s");
    require_bounded(at + ".point", p.point, kMaxCoordinate, " m");
    if (scene.planar && (p.impulse.z() != 0.0 || p.point.z() != 0.0))
      fail(at, "must lie in the XY plane in a planar scene");
  }
  if (!scene.impulses.empty() && (scene.reference.kind == ReferenceKind::Ballistic ||
                                  scene.reference.kind == ReferenceKind::Oscillator))
    fail("reference.kind", "the closed forms do not include impulses: use converged");

  if (scene.particles) {
    const ParticleSetSpec& p = *scene.particles;
    const std::string at = "particles";
    if (p.count < 1) fail(at + ".count", "must be >= 1");
    if (p.count > kMaxParticles)
      fail(at + ".count", "is " + std::to_string(p.count) + ", over the cap of " +
                              std::to_string(kMaxParticles) +
                              " (the largest built-in, 4·10^6, took 4.7 GB in one engine)");
    require_count(at + ".attractors", p.attractors.size(), kMaxAttractors,
                  "each particle sums every attractor each step");
    require_count(at + ".planes", p.planes.size(), kMaxParticlePlanes,
                  "each particle tests every plane each step");
    require_count(at + ".probe", p.probe.size(), static_cast<std::size_t>(p.count),
                  "one entry per particle");
    for (auto [name, v] : {std::pair{".spawn_min", p.spawn_min}, {".spawn_max", p.spawn_max}})
      require_bounded(at + name, v, kMaxCoordinate, " m");
    for (auto [name, v] : {std::pair{".velocity_min", p.velocity_min},
                           {".velocity_max", p.velocity_max},
                           {".wind", p.wind}})
      require_bounded(at + name, v, kMaxSpeed, " m/s");
    for (int k = 0; k < 3; ++k) {
      if (p.spawn_min[k] > p.spawn_max[k]) fail(at + ".spawn_min", "must not exceed spawn_max");
      if (p.velocity_min[k] > p.velocity_max[k])
        fail(at + ".velocity_min", "must not exceed velocity_max");
    }
    require_range(at + ".mass", p.mass, kMinMass, kMaxMass, " kg");
    require_range(at + ".radius", p.radius, kMinSize, kMaxSize, " m");
    require_range(at + ".drag", p.drag, 0.0, kMaxDrag, " 1/s");
    require_range(at + ".wind_jitter", p.wind_jitter, 0.0, kMaxSpeed, " m/s");
    require_range(at + ".softening", p.softening, kMinSize, kMaxSize, " m");
    require_nonnegative(at + ".restitution", p.restitution);
    if (p.restitution > 1.0) fail(at + ".restitution", "must be <= 1");
    require_nonnegative(at + ".friction", p.friction);
    if (p.friction > 1.0)
      fail(at + ".friction", "must be <= 1 (the fraction of tangential velocity lost)");
    require_range(at + ".lifetime", p.lifetime, 0.0, kMaxDuration, " s");
    for (std::size_t i = 0; i < p.attractors.size(); ++i) {
      require_bounded(at + ".attractors[" + std::to_string(i) + "].position",
                      p.attractors[i].position, kMaxCoordinate, " m");
      require_range(at + ".attractors[" + std::to_string(i) + "].strength",
                    p.attractors[i].strength, -kMaxAttractorStrength, kMaxAttractorStrength,
                    " m³/s²");
      if (scene.planar && p.attractors[i].position.z() != 0.0)
        fail(at + ".attractors[" + std::to_string(i) + "].position[2]",
             "must be 0 in a planar scene");
    }
    for (std::size_t i = 0; i < p.planes.size(); ++i) {
      const std::string plane = at + ".planes[" + std::to_string(i) + "]";
      require_bounded(plane + ".point", p.planes[i].point, kMaxCoordinate, " m");
      require_bounded(plane + ".normal", p.planes[i].normal, 2.0, "");
      if (std::abs(p.planes[i].normal.norm() - 1.0) > 1e-6)
        fail(plane + ".normal", "must be a unit vector");
      if (scene.planar && p.planes[i].normal.z() != 0.0)
        fail(plane + ".normal[2]", "must be 0 in a planar scene (the plane is a line in XY)");
    }
    for (std::size_t i = 0; i < p.probe.size(); ++i)
      if (p.probe[i] < 0 || p.probe[i] >= p.count)
        fail(at + ".probe[" + std::to_string(i) + "]", "no particle " + std::to_string(p.probe[i]));
    if (scene.planar &&
        (p.spawn_min.z() != 0.0 || p.spawn_max.z() != 0.0 || p.velocity_min.z() != 0.0 ||
         p.velocity_max.z() != 0.0 || p.wind.z() != 0.0))
      fail(at, "must stay in the XY plane in a planar scene (spawn, velocity and wind z = 0)");
    if (scene.planar && p.wind_jitter != 0.0)
      fail(at + ".wind_jitter",
           "must be 0 in a planar scene (each particle's offset is drawn in three dimensions)");
    if (scene.reference.kind == ReferenceKind::Ballistic ||
        scene.reference.kind == ReferenceKind::Oscillator)
      fail("reference.kind",
           "the ballistic and oscillator closed forms are for bodies, not particles");
  }
  if (scene.reference.kind == ReferenceKind::Orbit) {
    if (!scene.particles || scene.particles->count != 1 ||
        scene.particles->attractors.size() != 1 || !scene.bodies.empty())
      fail("reference.kind", "orbit needs exactly one particle, one attractor and no bodies");
    const ParticleSetSpec& p = *scene.particles;
    if (p.spawn_min != p.spawn_max || p.velocity_min != p.velocity_max)
      fail("particles",
           "orbit needs one exact start: spawn_min = spawn_max, velocity_min = velocity_max");
    if (p.drag != 0.0 || !p.planes.empty() || scene.gravity.norm() != 0.0)
      fail("reference.kind", "orbit holds without drag, planes or gravity");
  }
  if (scene.reference.kind == ReferenceKind::Bounce) {
    if (!scene.particles || scene.particles->count != 1 || scene.particles->planes.size() != 1 ||
        !scene.bodies.empty())
      fail("reference.kind", "bounce needs exactly one particle, one plane and no bodies");
    const ParticleSetSpec& p = *scene.particles;
    if (p.spawn_min != p.spawn_max || p.velocity_min.norm() != 0.0 || p.velocity_max.norm() != 0.0)
      fail("particles",
           "bounce needs one exact start at rest: spawn_min = spawn_max, velocities 0");
    if (p.drag != 0.0 || !p.attractors.empty() ||
        p.planes[0].normal.cross(scene.gravity).norm() > 1e-12 ||
        p.planes[0].normal.dot(scene.gravity) >= 0.0)
      fail("reference.kind",
           "bounce holds without drag or attractors, with gravity into the plane");
  }

  require_range("probe.interval", scene.probe.interval, kMinDt, scene.duration,
                " s (at most the duration)");
  {
    std::map<long, std::size_t> seen;  // entry -> where it first appeared
    for (std::size_t i = 0; i < scene.probe.bodies.size(); ++i) {
      const int b = scene.probe.bodies[i];
      const std::string at = "probe.bodies[" + std::to_string(i) + "]";
      if (b < 0 || b >= body_count) fail(at, "no body " + std::to_string(b));
      const auto [first, fresh] = seen.emplace(b, i);
      if (!fresh)
        fail(at, "body " + std::to_string(b) + " is listed twice (also at [" +
                     std::to_string(first->second) + "])");
    }
    seen.clear();
    for (std::size_t i = 0; scene.particles && i < scene.particles->probe.size(); ++i) {
      const long q = scene.particles->probe[i];
      const auto [first, fresh] = seen.emplace(q, i);
      if (!fresh)
        fail("particles.probe[" + std::to_string(i) + "]",
             "particle " + std::to_string(q) + " is listed twice (also at [" +
                 std::to_string(first->second) + "])");
    }
  }
  {
    // every sample holds 13 numbers per probed body and particle, kept in memory and written out
    const double samples = std::floor(scene.duration / scene.dt / scene.probe_every_steps()) + 1.0;
    const double size = samples * static_cast<double>(scene.probed_bodies().size());
    if (size > static_cast<double>(kMaxProbeSamples))
      fail("probe", "asks for " + show(size) + " body-samples, over the cap of " +
                        std::to_string(kMaxProbeSamples) +
                        " (13 numbers each, held in memory and written as JSON by the worker)");
  }
  if (scene.reference.dt_divisor < 2 || scene.reference.dt_divisor > kMaxDtDivisor)
    fail("reference.dt_divisor", "must lie in [2, " + std::to_string(kMaxDtDivisor) + "], got " +
                                     std::to_string(scene.reference.dt_divisor));
  const bool needs_reference =
      std::any_of(scene.probe.metrics.begin(), scene.probe.metrics.end(),
                  [](Metric m) { return m == Metric::Position || m == Metric::Orientation; });
  if (needs_reference && scene.reference.kind == ReferenceKind::None)
    fail("reference.kind",
         "metrics position/orientation need a reference (ballistic or converged)");
  if (scene.reference.kind == ReferenceKind::Oscillator) {
    // the closed form holds while the motion stays on the spring's line
    const auto dynamic = scene.probed_bodies();
    if (dynamic.size() != 1 || scene.springs.size() != 1)
      fail("reference.kind", "oscillator needs one dynamic body and one spring");
    const SpringSpec& s = scene.springs[0];
    const BodySpec& b = scene.bodies[dynamic[0]];
    const std::string at = "bodies[" + std::to_string(dynamic[0]) + "]";
    if (s.body_a != dynamic[0] || s.body_b != -1 || s.local_point_a.norm() != 0.0)
      fail("springs[0]",
           "oscillator needs a spring from the body's centre (local_point_a 0) to a world anchor");
    const Vec3 line = b.position - s.point_b;
    if (line.norm() == 0.0) fail(at + ".position", "must not sit on the anchor");
    const Vec3 u = line.normalized();
    if (b.linear_velocity.cross(u).norm() > 1e-12 * std::max(1.0, b.linear_velocity.norm()))
      fail(at + ".linear_velocity", "must lie along the spring for the oscillator reference");
    if (scene.gravity.cross(u).norm() > 1e-12 * std::max(1.0, scene.gravity.norm()))
      fail("gravity", "must lie along the spring (or be zero) for the oscillator reference");
    for (Metric m : scene.probe.metrics)
      if (m == Metric::Orientation)
        fail("probe.metrics", "the oscillator reference has no orientation");
  }
  validate_contact_metrics(scene);
  if (scene.reference.kind == ReferenceKind::Ballistic) {
    if (!scene.springs.empty()) fail("reference.kind", "ballistic holds only without springs");
    const bool orientation = std::find(scene.probe.metrics.begin(), scene.probe.metrics.end(),
                                       Metric::Orientation) != scene.probe.metrics.end();
    for (int i = 0; orientation && i < body_count; ++i) {
      const BodySpec& b = scene.bodies[i];
      if (b.mass > 0.0 && !symmetry_axis(principal_inertia(b.shape, b.mass)))
        fail("probe.metrics",
             "the ballistic orientation is closed-form only for symmetric tops; bodies[" +
                 std::to_string(i) + "] has three different principal moments");
    }
  }
}

}  // namespace physbench
