#include "physbench/scene_json.h"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

namespace physbench {

using nlohmann::json;

namespace {

// A cursor into the document that knows its path, so every error names the field.
class Field {
 public:
  Field(const json& value, std::string path) : value_(value), path_(std::move(path)) {}

  [[noreturn]] void fail(const std::string& what) const {
    throw SceneError((path_.empty() ? std::string("(top level)") : path_) + ": " + what);
  }

  const std::string& path() const { return path_; }
  const json& raw() const { return value_; }

  double number() const {
    if (!value_.is_number()) fail("expected a number, got " + type_of());
    return value_.get<double>();
  }
  int integer() const {
    if (!value_.is_number_integer()) fail("expected an integer, got " + type_of());
    return value_.get<int>();
  }
  bool boolean() const {
    if (!value_.is_boolean()) fail("expected true or false, got " + type_of());
    return value_.get<bool>();
  }
  std::string string() const {
    if (!value_.is_string()) fail("expected a string, got " + type_of());
    return value_.get<std::string>();
  }
  Vec3 vec3() const {
    const json& a = array(3);
    return Vec3(Field(a[0], path_ + "[0]").number(), Field(a[1], path_ + "[1]").number(),
                Field(a[2], path_ + "[2]").number());
  }
  Quat quaternion() const {
    const json& a = array(4);
    // [w, x, y, z]
    return Quat(Field(a[0], path_ + "[0]").number(), Field(a[1], path_ + "[1]").number(),
                Field(a[2], path_ + "[2]").number(), Field(a[3], path_ + "[3]").number());
  }
  const json& array(std::size_t size = 0) const {
    if (!value_.is_array()) fail("expected an array, got " + type_of());
    if (size != 0 && value_.size() != size)
      fail("expected " + std::to_string(size) + " numbers, got " + std::to_string(value_.size()));
    return value_;
  }
  Field at(std::size_t index) const {
    return Field(value_[index], path_ + "[" + std::to_string(index) + "]");
  }

  // an object whose keys are all known; optional members read through has()/member()
  const Field& object(std::initializer_list<const char*> known) const {
    if (!value_.is_object()) fail("expected an object, got " + type_of());
    std::set<std::string> allowed(known.begin(), known.end());
    for (const auto& item : value_.items())
      if (!allowed.count(item.key())) {
        std::string list;
        for (const char* k : known) list += std::string(list.empty() ? "" : ", ") + k;
        throw SceneError(child_path(item.key()) + ": unknown field (known: " + list + ")");
      }
    return *this;
  }
  bool has(const char* key) const { return value_.contains(key); }
  Field member(const char* key) const {
    if (!value_.contains(key)) throw SceneError(child_path(key) + ": missing (required)");
    return Field(value_.at(key), child_path(key));
  }

 private:
  std::string child_path(const std::string& key) const {
    return path_.empty() ? key : path_ + "." + key;
  }
  std::string type_of() const {
    // the JSON text of a string is the string quoted (and it avoids GCC 12's false -Wrestrict)
    if (value_.is_string()) return value_.dump();
    return value_.type_name();
  }
  const json& value_;
  std::string path_;
};

json vec(const Vec3& v) { return json::array({v.x(), v.y(), v.z()}); }
json quat(const Quat& q) { return json::array({q.w(), q.x(), q.y(), q.z()}); }

Shape read_shape(const Field& f) {
  f.object({"type", "half_extents", "radius"});
  Shape shape;
  const std::string type = f.member("type").string();
  if (type == "box") {
    shape.kind = ShapeKind::Box;
    shape.half_extents = f.member("half_extents").vec3();
  } else if (type == "sphere") {
    shape.kind = ShapeKind::Sphere;
    shape.radius = f.member("radius").number();
  } else if (type == "plane") {
    shape.kind = ShapeKind::Plane;
  } else {
    f.member("type").fail("unknown shape \"" + type + "\" (known: box, sphere, plane)");
  }
  return shape;
}

BodySpec read_body(const Field& f) {
  f.object({"name", "shape", "mass", "position", "orientation", "linear_velocity",
            "angular_velocity", "friction", "restitution"});
  BodySpec b;
  if (f.has("name")) b.name = f.member("name").string();
  b.shape = read_shape(f.member("shape"));
  b.mass = f.member("mass").number();
  if (f.has("position")) b.position = f.member("position").vec3();
  if (f.has("orientation")) b.orientation = f.member("orientation").quaternion();
  if (f.has("linear_velocity")) b.linear_velocity = f.member("linear_velocity").vec3();
  if (f.has("angular_velocity")) b.angular_velocity = f.member("angular_velocity").vec3();
  if (f.has("friction")) b.friction = f.member("friction").number();
  if (f.has("restitution")) b.restitution = f.member("restitution").number();
  return b;
}

ParticleSetSpec read_particles(const Field& f) {
  f.object({"count", "spawn_min", "spawn_max", "velocity_min", "velocity_max", "mass", "radius",
            "drag", "wind", "wind_jitter", "attractors", "softening", "planes", "restitution",
            "friction", "lifetime", "seed", "probe"});
  ParticleSetSpec p;
  p.count = f.member("count").integer();
  p.spawn_min = f.member("spawn_min").vec3();
  p.spawn_max = f.has("spawn_max") ? f.member("spawn_max").vec3() : p.spawn_min;
  if (f.has("velocity_min")) p.velocity_min = f.member("velocity_min").vec3();
  p.velocity_max = f.has("velocity_max") ? f.member("velocity_max").vec3() : p.velocity_min;
  if (f.has("mass")) p.mass = f.member("mass").number();
  if (f.has("radius")) p.radius = f.member("radius").number();
  if (f.has("drag")) p.drag = f.member("drag").number();
  if (f.has("wind")) p.wind = f.member("wind").vec3();
  if (f.has("wind_jitter")) p.wind_jitter = f.member("wind_jitter").number();
  if (f.has("attractors")) {
    const Field list = f.member("attractors");
    for (std::size_t i = 0; i < list.array().size(); ++i) {
      const Field a = list.at(i);
      a.object({"position", "strength"});
      p.attractors.push_back({a.member("position").vec3(), a.member("strength").number()});
    }
  }
  if (f.has("softening")) p.softening = f.member("softening").number();
  if (f.has("planes")) {
    const Field list = f.member("planes");
    for (std::size_t i = 0; i < list.array().size(); ++i) {
      const Field plane = list.at(i);
      plane.object({"point", "normal"});
      p.planes.push_back({plane.member("point").vec3(), plane.member("normal").vec3()});
    }
  }
  if (f.has("restitution")) p.restitution = f.member("restitution").number();
  if (f.has("friction")) p.friction = f.member("friction").number();
  if (f.has("lifetime")) p.lifetime = f.member("lifetime").number();
  if (f.has("seed")) p.seed = static_cast<std::uint64_t>(f.member("seed").integer());
  if (f.has("probe")) {
    p.probe.clear();
    const Field list = f.member("probe");
    for (std::size_t i = 0; i < list.array().size(); ++i) p.probe.push_back(list.at(i).integer());
  }
  return p;
}

ImpulseSpec read_impulse(const Field& f) {
  f.object({"time", "body", "impulse", "point"});
  ImpulseSpec p;
  p.time = f.member("time").number();
  p.body = f.member("body").integer();
  p.impulse = f.member("impulse").vec3();
  p.point = f.member("point").vec3();
  return p;
}

SpringSpec read_spring(const Field& f) {
  f.object({"body_a", "local_point_a", "body_b", "point_b", "stiffness", "damping", "rest_length"});
  SpringSpec s;
  s.body_a = f.member("body_a").integer();
  if (f.has("local_point_a")) s.local_point_a = f.member("local_point_a").vec3();
  if (f.has("body_b")) s.body_b = f.member("body_b").integer();
  if (f.has("point_b")) s.point_b = f.member("point_b").vec3();
  s.stiffness = f.member("stiffness").number();
  if (f.has("damping")) s.damping = f.member("damping").number();
  if (f.has("rest_length")) s.rest_length = f.member("rest_length").number();
  return s;
}

}  // namespace

json to_json(const Scene& scene) {
  json doc;
  doc["name"] = scene.name;
  if (!scene.description.empty()) doc["description"] = scene.description;
  doc["gravity"] = vec(scene.gravity);
  doc["dt"] = scene.dt;
  doc["duration"] = scene.duration;
  doc["planar"] = scene.planar;
  doc["collisions"] = scene.collisions;
  doc["bodies"] = json::array();
  for (const BodySpec& b : scene.bodies) {
    json body;
    if (!b.name.empty()) body["name"] = b.name;
    json shape{{"type", to_string(b.shape.kind)}};
    if (b.shape.kind == ShapeKind::Box) shape["half_extents"] = vec(b.shape.half_extents);
    if (b.shape.kind == ShapeKind::Sphere) shape["radius"] = b.shape.radius;
    body["shape"] = shape;
    body["mass"] = b.mass;
    body["position"] = vec(b.position);
    body["orientation"] = quat(b.orientation);
    body["linear_velocity"] = vec(b.linear_velocity);
    body["angular_velocity"] = vec(b.angular_velocity);
    body["friction"] = b.friction;
    body["restitution"] = b.restitution;
    doc["bodies"].push_back(body);
  }
  if (!scene.springs.empty()) {
    doc["springs"] = json::array();
    for (const SpringSpec& s : scene.springs)
      doc["springs"].push_back({{"body_a", s.body_a},
                                {"local_point_a", vec(s.local_point_a)},
                                {"body_b", s.body_b},
                                {"point_b", vec(s.point_b)},
                                {"stiffness", s.stiffness},
                                {"damping", s.damping},
                                {"rest_length", s.rest_length}});
  }
  if (!scene.impulses.empty()) {
    doc["impulses"] = json::array();
    for (const ImpulseSpec& p : scene.impulses)
      doc["impulses"].push_back({{"time", p.time},
                                 {"body", p.body},
                                 {"impulse", vec(p.impulse)},
                                 {"point", vec(p.point)}});
  }
  if (scene.particles) {
    const ParticleSetSpec& p = *scene.particles;
    json attractors = json::array(), planes = json::array();
    for (const ParticleAttractor& a : p.attractors)
      attractors.push_back({{"position", vec(a.position)}, {"strength", a.strength}});
    for (const ParticlePlaneSpec& plane : p.planes)
      planes.push_back({{"point", vec(plane.point)}, {"normal", vec(plane.normal)}});
    doc["particles"] = {{"count", p.count},
                        {"spawn_min", vec(p.spawn_min)},
                        {"spawn_max", vec(p.spawn_max)},
                        {"velocity_min", vec(p.velocity_min)},
                        {"velocity_max", vec(p.velocity_max)},
                        {"mass", p.mass},
                        {"radius", p.radius},
                        {"drag", p.drag},
                        {"wind", vec(p.wind)},
                        {"wind_jitter", p.wind_jitter},
                        {"attractors", attractors},
                        {"softening", p.softening},
                        {"planes", planes},
                        {"restitution", p.restitution},
                        {"friction", p.friction},
                        {"lifetime", p.lifetime},
                        {"seed", p.seed},
                        {"probe", p.probe}};
  }
  json metrics = json::array();
  for (Metric m : scene.probe.metrics) metrics.push_back(to_string(m));
  doc["probe"] = {
      {"bodies", scene.probe.bodies}, {"interval", scene.probe.interval}, {"metrics", metrics}};
  doc["reference"] = {{"kind", to_string(scene.reference.kind)},
                      {"dt_divisor", scene.reference.dt_divisor}};
  return doc;
}

Scene scene_from_json(const json& document, const std::string& source) {
  try {
    const Field root(document, "");
    root.object({"name", "description", "gravity", "dt", "duration", "planar", "collisions",
                 "bodies", "springs", "impulses", "particles", "probe", "reference"});
    Scene scene;
    scene.name = root.member("name").string();
    if (root.has("description")) scene.description = root.member("description").string();
    if (root.has("gravity")) scene.gravity = root.member("gravity").vec3();
    scene.dt = root.member("dt").number();
    scene.duration = root.member("duration").number();
    if (root.has("planar")) scene.planar = root.member("planar").boolean();
    if (root.has("collisions")) scene.collisions = root.member("collisions").boolean();
    const Field bodies = root.member("bodies");
    for (std::size_t i = 0; i < bodies.array().size(); ++i)
      scene.bodies.push_back(read_body(bodies.at(i)));
    if (root.has("springs")) {
      const Field springs = root.member("springs");
      for (std::size_t i = 0; i < springs.array().size(); ++i)
        scene.springs.push_back(read_spring(springs.at(i)));
    }
    if (root.has("particles")) scene.particles = read_particles(root.member("particles"));
    if (root.has("impulses")) {
      const Field impulses = root.member("impulses");
      for (std::size_t i = 0; i < impulses.array().size(); ++i)
        scene.impulses.push_back(read_impulse(impulses.at(i)));
    }
    if (root.has("probe")) {
      const Field probe = root.member("probe");
      probe.object({"bodies", "interval", "metrics"});
      if (probe.has("bodies")) {
        const Field list = probe.member("bodies");
        for (std::size_t i = 0; i < list.array().size(); ++i)
          scene.probe.bodies.push_back(list.at(i).integer());
      }
      if (probe.has("interval")) scene.probe.interval = probe.member("interval").number();
      if (probe.has("metrics")) {
        scene.probe.metrics.clear();
        const Field list = probe.member("metrics");
        for (std::size_t i = 0; i < list.array().size(); ++i) {
          const std::string name = list.at(i).string();
          const auto metric = metric_from_string(name);
          if (!metric) {
            std::string known;
            for (Metric m : all_metrics()) known += (known.empty() ? "" : ", ") + std::string(to_string(m));
            list.at(i).fail("unknown metric \"" + name + "\" (known: " + known + ")");
          }
          scene.probe.metrics.push_back(*metric);
        }
      }
    }
    if (root.has("reference")) {
      const Field reference = root.member("reference");
      reference.object({"kind", "dt_divisor"});
      const std::string kind = reference.member("kind").string();
      if (kind == "none")
        scene.reference.kind = ReferenceKind::None;
      else if (kind == "ballistic")
        scene.reference.kind = ReferenceKind::Ballistic;
      else if (kind == "bounce")
        scene.reference.kind = ReferenceKind::Bounce;
      else if (kind == "orbit")
        scene.reference.kind = ReferenceKind::Orbit;
      else if (kind == "oscillator")
        scene.reference.kind = ReferenceKind::Oscillator;
      else if (kind == "converged")
        scene.reference.kind = ReferenceKind::Converged;
      else
        reference.member("kind").fail(
            "unknown reference \"" + kind +
            "\" (known: none, ballistic, oscillator, orbit, bounce, converged)");
      if (reference.has("dt_divisor"))
        scene.reference.dt_divisor = reference.member("dt_divisor").integer();
    }
    validate(scene);
    return scene;
  } catch (const SceneError& e) {
    throw SceneError(source + ": " + e.what());
  } catch (const json::exception& e) {
    throw SceneError(source + ": " + e.what());
  }
}

Scene load_scene_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw SceneError(path + ": cannot open the scene file");
  json document;
  try {
    document = json::parse(in);
  } catch (const json::parse_error& e) {
    // nlohmann names the byte; NaN and Infinity are not JSON and land here too
    throw SceneError(path + ": not valid JSON: " + e.what());
  }
  return scene_from_json(document, path);
}

void save_scene_file(const Scene& scene, const std::string& path) {
  // write beside the target and rename: never a half-written scene file
  const std::string partial = path + ".partial";
  {
    std::ofstream out(partial);
    if (!out) throw SceneError(path + ": cannot write the scene file");
    out << to_json(scene).dump(2) << '\n';
    if (!out) throw SceneError(path + ": write failed");
  }
  std::filesystem::rename(partial, path);
}

}  // namespace physbench
