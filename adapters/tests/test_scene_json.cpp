// Scene files: the JSON means what the C++ structure means, and bad input is named precisely.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "physbench/scene_json.h"

namespace {

using namespace physbench;
using nlohmann::json;

Scene sample_scene() {
  Scene scene;
  scene.name = "sample";
  scene.description = "two boxes and a spring";
  scene.gravity = Vec3(0.0, -9.81, 0.0);
  scene.dt = 1.0 / 120.0;
  scene.duration = 1.5;
  scene.collisions = false;
  BodySpec a;
  a.name = "a";
  a.shape.half_extents = Vec3(0.5, 0.25, 0.125);
  a.mass = 2.0;
  a.position = Vec3(1.0, 2.0, 3.0);
  a.orientation = Quat(Eigen::AngleAxisd(0.7, Vec3(1, 1, 0).normalized()));
  a.linear_velocity = Vec3(0.1, 0.2, 0.3);
  a.angular_velocity = Vec3(-1.0, 0.5, 2.0);
  a.friction = 0.3;
  a.restitution = 0.4;
  BodySpec b;
  b.shape.kind = ShapeKind::Sphere;
  b.shape.radius = 0.2;
  b.mass = 1.0 / 3.0;  // not exactly representable in decimal: the round trip must keep every bit
  scene.bodies = {a, b};
  SpringSpec s;
  s.body_a = 0;
  s.local_point_a = Vec3(0.5, 0.25, 0.125);
  s.body_b = 1;
  s.stiffness = 100.0;
  s.damping = 0.5;
  s.rest_length = 1.0;
  scene.springs = {s};
  scene.probe.metrics = {Metric::Position, Metric::Energy};
  scene.reference.kind = ReferenceKind::Converged;
  return scene;
}

// the error message scene_from_json gives for a document, or "" when it accepts it
std::string error_for(const json& document) {
  try {
    scene_from_json(document, "test.json");
    return "";
  } catch (const SceneError& e) {
    return e.what();
  }
}

TEST(SceneJson, RoundTripKeepsEveryValue) {
  const Scene original = sample_scene();
  const Scene back = scene_from_json(to_json(original));
  EXPECT_EQ(to_json(back), to_json(original));
  EXPECT_EQ(back.bodies[1].mass, 1.0 / 3.0);
  EXPECT_EQ(back.dt, 1.0 / 120.0);
  EXPECT_TRUE(back.bodies[0].orientation.isApprox(original.bodies[0].orientation, 0.0));
  EXPECT_EQ(back.springs[0].body_b, 1);
  EXPECT_EQ(back.reference.kind, ReferenceKind::Converged);
}

TEST(SceneJson, FileRoundTrip) {
  const auto path = std::filesystem::temp_directory_path() / "physbench_scene_roundtrip.json";
  save_scene_file(sample_scene(), path.string());
  EXPECT_EQ(to_json(load_scene_file(path.string())), to_json(sample_scene()));
  std::filesystem::remove(path);
}

TEST(SceneJson, WrongTypeNamesTheField) {
  json doc = to_json(sample_scene());
  doc["bodies"][1]["mass"] = "heavy";
  EXPECT_EQ(error_for(doc), "test.json: bodies[1].mass: expected a number, got \"heavy\"");
}

TEST(SceneJson, MissingRequiredFieldIsNamed) {
  json doc = to_json(sample_scene());
  doc.erase("dt");
  EXPECT_EQ(error_for(doc), "test.json: dt: missing (required)");
}

TEST(SceneJson, UnknownFieldIsRejectedNotIgnored) {
  json doc = to_json(sample_scene());
  doc["bodies"][0]["colour"] = "red";
  EXPECT_NE(error_for(doc).find("bodies[0].colour: unknown field"), std::string::npos)
      << error_for(doc);
}

TEST(SceneJson, OutOfRangeValuesAreNamed) {
  json doc = to_json(sample_scene());
  doc["bodies"][0]["mass"] = -2.0;
  EXPECT_NE(error_for(doc).find("bodies[0].mass: must be >= 0"), std::string::npos)
      << error_for(doc);
  doc = to_json(sample_scene());
  doc["springs"][0]["body_b"] = 7;
  EXPECT_NE(error_for(doc).find("springs[0].body_b: no body 7"), std::string::npos)
      << error_for(doc);
  doc = to_json(sample_scene());
  doc["bodies"][0]["orientation"] = json::array({1.0, 1.0, 0.0, 0.0});
  EXPECT_NE(error_for(doc).find("bodies[0].orientation: must be a unit quaternion"),
            std::string::npos);
  doc = to_json(sample_scene());
  doc["bodies"][0]["shape"]["type"] = "torus";
  EXPECT_NE(error_for(doc).find("bodies[0].shape.type: unknown shape \"torus\""),
            std::string::npos);
  doc = to_json(sample_scene());
  doc["bodies"][0]["position"] = json::array({1.0, 2.0});
  EXPECT_NE(error_for(doc).find("bodies[0].position: expected 3 numbers, got 2"),
            std::string::npos);
}

TEST(SceneJson, InfiniteNumberIsRejected) {
  json doc = to_json(sample_scene());
  doc["gravity"][1] = std::numeric_limits<double>::infinity();
  EXPECT_NE(error_for(doc).find("gravity[1]: must be a finite number"), std::string::npos)
      << error_for(doc);
}

TEST(SceneJson, NanInAFileIsAParseErrorWithItsPlace) {
  const auto path = std::filesystem::temp_directory_path() / "physbench_scene_nan.json";
  {
    std::ofstream out(path);
    out << "{\n  \"name\": \"x\",\n  \"dt\": NaN,\n  \"duration\": 1, \"bodies\": []\n}\n";
  }
  try {
    load_scene_file(path.string());
    FAIL() << "a NaN was accepted";
  } catch (const SceneError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("not valid JSON"), std::string::npos) << what;
    EXPECT_NE(what.find("line 3"), std::string::npos) << what;
  }
  std::filesystem::remove(path);
}

TEST(SceneJson, PlanarSceneMustStayInThePlane) {
  Scene scene = sample_scene();
  scene.planar = true;
  scene.springs.clear();
  scene.bodies[0].orientation = Quat::Identity();
  scene.bodies[0].position.z() = 0.0;
  scene.bodies[1].position.z() = 0.0;
  scene.bodies[0].linear_velocity.z() = 0.0;
  EXPECT_NE(error_for(to_json(scene)).find("bodies[0].angular_velocity: must be about z only"),
            std::string::npos);
}

TEST(SceneJson, MissingFileIsNamed) {
  EXPECT_THROW(
      {
        try {
          load_scene_file("/nonexistent/scene.json");
        } catch (const SceneError& e) {
          EXPECT_NE(std::string(e.what()).find("/nonexistent/scene.json"), std::string::npos);
          throw;
        }
      },
      SceneError);
}

TEST(SceneJson, ParticlesRoundTripAndBadFieldsAreNamed) {
  Scene scene;
  scene.name = "particles";
  scene.dt = 0.01;
  scene.duration = 1.0;
  ParticleSetSpec p;
  p.count = 100;
  p.spawn_min = Vec3(-1, 0, -1);
  p.spawn_max = Vec3(1, 2, 1);
  p.attractors = {{Vec3(0, 1, 0), 5.0}};
  p.planes = {{Vec3::Zero(), Vec3::UnitY()}};
  p.lifetime = 2.0;
  p.seed = 42;
  p.probe = {0, 99};
  scene.particles = p;
  scene.probe.metrics = {};
  const json doc = to_json(scene);
  EXPECT_EQ(to_json(scene_from_json(doc)), doc);
  EXPECT_EQ(scene.probed_bodies(), (std::vector<int>{0, 99}));  // particles follow the (no) bodies

  json bad = doc;
  bad["particles"]["planes"][0]["normal"] = json::array({0.0, 2.0, 0.0});
  EXPECT_NE(error_for(bad).find("particles.planes[0].normal: must be a unit vector"),
            std::string::npos)
      << error_for(bad);
  bad = doc;
  bad["particles"]["probe"] = json::array({100});
  EXPECT_NE(error_for(bad).find("particles.probe[0]: no particle 100"), std::string::npos)
      << error_for(bad);
  bad = doc;
  bad["particles"]["friction"] = 1.5;
  EXPECT_NE(error_for(bad).find("particles.friction: must be <= 1"), std::string::npos)
      << error_for(bad);
}

TEST(SceneJson, PlanarParticlesMustStayInThePlane) {
  Scene scene;
  scene.name = "planar particles";
  scene.dt = 0.01;
  scene.duration = 1.0;
  scene.planar = true;
  ParticleSetSpec p;
  p.count = 10;
  p.spawn_max = Vec3(1, 2, 0);
  p.attractors = {{Vec3(0, 1, 0), 5.0}};
  p.planes = {{Vec3::Zero(), Vec3(0.6, 0.8, 0.0)}};
  scene.particles = p;
  scene.probe.metrics = {};
  const json doc = to_json(scene);
  EXPECT_EQ(error_for(doc), "");

  json bad = doc;
  bad["particles"]["attractors"][0]["position"] = json::array({0.0, 1.0, 0.5});
  EXPECT_NE(error_for(bad).find("particles.attractors[0].position[2]: must be 0 in a planar scene"),
            std::string::npos)
      << error_for(bad);
  bad = doc;
  bad["particles"]["planes"][0]["normal"] = json::array({0.0, 0.8, 0.6});
  EXPECT_NE(error_for(bad).find("particles.planes[0].normal[2]: must be 0 in a planar scene"),
            std::string::npos)
      << error_for(bad);
  bad = doc;
  bad["particles"]["wind_jitter"] = 0.5;
  EXPECT_NE(error_for(bad).find("particles.wind_jitter: must be 0 in a planar scene"),
            std::string::npos)
      << error_for(bad);
}

TEST(Scene, BoxInertiaMatchesTheClosedForm) {
  Shape box;
  box.half_extents = Vec3(0.5, 2.0, 4.5);  // a 1 x 4 x 9 box
  // I_x = m (b² + c²) / 12 with full sides b = 4, c = 9
  EXPECT_TRUE(principal_inertia(box, 12.0).isApprox(Vec3(16 + 81, 1 + 81, 1 + 16)));
}

}  // namespace
