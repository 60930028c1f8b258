#include "physbench/scene_json.h"

#include <cstdint>
#include <cstdio>
#include <limits>
#include <type_traits>
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
  // an integer that fits T: a wider one, or a number with a fraction or exponent, is named
  template <typename T = int>
  T integer() const {
    constexpr auto lo = std::numeric_limits<T>::min();
    constexpr auto hi = std::numeric_limits<T>::max();
    const auto range = [&] {
      return "expected an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) +
             "], got ";
    };
    if (value_.is_number_unsigned()) {
      const auto v = value_.get<std::uint64_t>();
      if (v > static_cast<std::uint64_t>(hi)) fail(range() + value_.dump());
      return static_cast<T>(v);
    }
    if (value_.is_number_integer()) {
      const auto v = value_.get<std::int64_t>();
      if ((std::is_signed_v<T> && v < static_cast<std::int64_t>(lo)) ||
          (!std::is_signed_v<T> && v < 0) ||
          (v > 0 && static_cast<std::uint64_t>(v) > static_cast<std::uint64_t>(hi)))
        fail(range() + value_.dump());
      return static_cast<T>(v);
    }
    fail(range() + (value_.is_number() ? value_.dump() : type_of()));
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
  p.count = f.member("count").integer<long>();
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
  if (f.has("seed")) p.seed = f.member("seed").integer<std::uint64_t>();
  if (f.has("probe")) {
    p.probe.clear();
    const Field list = f.member("probe");
    for (std::size_t i = 0; i < list.array().size(); ++i)
      p.probe.push_back(list.at(i).integer<long>());
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
  doc["version"] = kSceneFormatVersion;
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
    root.object({"version", "name", "description", "gravity", "dt", "duration", "planar",
                 "collisions", "bodies", "springs", "impulses", "particles", "probe",
                 "reference"});
    // a file without a version is read as version 1, the format before it carried one
    if (root.has("version")) {
      const Field version = root.member("version");
      const long v = version.integer<long>();
      if (v != kSceneFormatVersion)
        version.fail("this build reads scene format version " +
                     std::to_string(kSceneFormatVersion) + ", got " + std::to_string(v));
    }
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

namespace {

// Builds the document as nlohmann's own DOM parser does, but knows where it is, so that what the
// DOM cannot hold is named by its field: a duplicate key (the DOM keeps one of the two silently),
// a number past the range of a double, one that underflows to zero, nesting past the cap.
class SceneSax : public nlohmann::json_sax<json> {
 public:
  explicit SceneSax(json& root) : root_(root) {}

  const std::string& error() const { return error_; }

  bool null() override { return add(json(nullptr)); }
  bool boolean(bool v) override { return add(json(v)); }
  bool number_integer(number_integer_t v) override { return add(json(v)); }
  bool number_unsigned(number_unsigned_t v) override { return add(json(v)); }
  bool number_float(number_float_t v, const string_t& text) override {
    // strtod gives 0 for 1e-400; a mantissa with a non-zero digit did not mean 0
    const std::string mantissa = text.substr(0, text.find_first_of("eE"));
    if (v == 0.0 && mantissa.find_first_of("123456789") != std::string::npos)
      return fail_here("the number " + text + " is too small for a double (it would read as 0)");
    return add(json(v));
  }
  bool string(string_t& v) override { return add(json(std::move(v))); }
  bool binary(binary_t&) override { return fail_here("binary values are not JSON text"); }
  bool start_object(std::size_t) override { return open(json::object()); }
  bool key(string_t& k) override {
    Frame& top = stack_.back();
    if (top.value->contains(k)) {
      top.key = k;
      return fail_here("duplicate key (an object may name each field once)");
    }
    top.key = std::move(k);
    return true;
  }
  bool end_object() override { return close(); }
  bool start_array(std::size_t) override { return open(json::array()); }
  bool end_array() override { return close(); }
  bool parse_error(std::size_t, const std::string& token,
                   const nlohmann::detail::exception& e) override {
    if (!error_.empty()) return false;  // ours came first
    const std::string at = path();
    if (e.id == 406) {  // nlohmann's number overflow: finite in the text, infinite as a double
      const std::string shown =
          token.size() <= 40 ? token
                             : token.substr(0, 20) + "... (" + std::to_string(token.size()) +
                                   " characters)";
      error_ = (at.empty() ? "(top level)" : at) + ": the number " + shown +
               " is past the range of a double (about ±1.8e308)";
    }
    else {
      error_ = (at.empty() ? "" : at + ": ") + "not valid JSON: " + e.what();
    }
    return false;
  }

 private:
  struct Frame {
    json* value;
    std::string key;  // objects: the key being read
  };

  // the path of the value being read, in the loader's notation: bodies[2].shape.radius
  std::string path() const {
    std::string p;
    for (std::size_t i = 0; i < stack_.size(); ++i) {
      const Frame& f = stack_[i];
      if (f.value->is_array()) {
        // an open child is already in its array; the value being read is not yet
        const std::size_t n = f.value->size();
        p += '[';
        p += std::to_string(i + 1 < stack_.size() && n > 0 ? n - 1 : n);
        p += ']';
      } else if (!f.key.empty()) {
        if (!p.empty()) p += '.';
        p += f.key;
      }
    }
    return p;
  }
  bool fail_here(const std::string& what) {
    const std::string at = path();
    error_ = (at.empty() ? "(top level)" : at) + ": " + what;
    return false;
  }
  json* place(json&& v) {
    if (stack_.empty()) {
      root_ = std::move(v);
      return &root_;
    }
    json& parent = *stack_.back().value;
    if (parent.is_array()) {
      parent.push_back(std::move(v));
      return &parent.back();
    }
    json& slot = parent[stack_.back().key];
    slot = std::move(v);
    return &slot;
  }
  bool add(json&& v) {
    place(std::move(v));
    return true;
  }
  bool open(json&& container) {
    if (static_cast<int>(stack_.size()) >= limits::kNestingDepth)
      return fail_here("nested deeper than " + std::to_string(limits::kNestingDepth) +
                       " levels (no scene field needs more than four)");
    json* at = place(std::move(container));
    stack_.push_back({at, {}});
    return true;
  }
  bool close() {
    stack_.pop_back();
    return true;
  }

  json& root_;
  std::vector<Frame> stack_;
  std::string error_;
};

}  // namespace

Scene load_scene_text(std::string_view text, const std::string& source) {
  if (text.size() > limits::kFileBytes)
    throw SceneError(source + ": the scene is " + std::to_string(text.size()) +
                     " bytes, over the cap of " + std::to_string(limits::kFileBytes) +
                     " (the largest built-in scene is under 8 MB)");
  json document;
  SceneSax sax(document);
  bool ok = false;
  try {
    ok = json::sax_parse(text.begin(), text.end(), &sax);
  } catch (const json::exception& e) {
    throw SceneError(source + ": not valid JSON: " + e.what());
  }
  if (!ok)
    throw SceneError(source + ": " + (sax.error().empty() ? "not valid JSON" : sax.error()));
  return scene_from_json(document, source);
}

Scene load_scene_file(const std::string& path) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) throw SceneError(path + ": cannot open the scene file (" + ec.message() + ")");
  if (size > limits::kFileBytes)
    throw SceneError(path + ": the file is " + std::to_string(size) + " bytes, over the cap of " +
                     std::to_string(limits::kFileBytes) +
                     " (the largest built-in scene is under 8 MB)");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw SceneError(path + ": cannot open the scene file");
  std::string text(static_cast<std::size_t>(size), '\0');
  in.read(text.data(), static_cast<std::streamsize>(size));
  text.resize(static_cast<std::size_t>(in.gcount()));
  return load_scene_text(text, path);
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
