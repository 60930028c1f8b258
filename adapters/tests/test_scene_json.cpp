// Scene files: the JSON means what the C++ structure means, and bad input is named precisely.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <typeinfo>
#include <unistd.h>

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
  const auto path = std::filesystem::temp_directory_path() /
                    ("physbench_scene_roundtrip_" + std::to_string(getpid()) + ".json");
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
  EXPECT_NE(error_for(doc).find("bodies[0].mass: must lie in [1e-09, 1e+09] kg (or 0: static)"),
            std::string::npos)
      << error_for(doc);
  doc = to_json(sample_scene());
  doc["springs"][0]["body_b"] = 7;
  EXPECT_NE(error_for(doc).find("springs[0].body_b: no body 7"), std::string::npos)
      << error_for(doc);
  doc = to_json(sample_scene());
  doc["bodies"][0]["orientation"] = json::array({1.0, 1.0, 0.0, 0.0});
  EXPECT_NE(error_for(doc).find("bodies[0].orientation: must be a unit quaternion"),
            std::string::npos);
  // a static body with a velocity: engines differ on what it means (moved, or ignored), so none
  doc = to_json(sample_scene());
  doc["bodies"][0]["mass"] = 0.0;
  doc["bodies"][0]["linear_velocity"] = json::array({1.0, 0.0, 0.0});
  EXPECT_NE(error_for(doc).find("bodies[0].linear_velocity: a static body (mass 0) cannot move"),
            std::string::npos)
      << error_for(doc);
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
  const auto path = std::filesystem::temp_directory_path() /
                    ("physbench_scene_nan_" + std::to_string(getpid()) + ".json");
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
  scene.name = "planar-particles";
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


// ---- bad scene files, one test per class: each message names the file and the field ----------

// writes text to a file of this test's own and returns the loader's message ("" if it loads)
struct FileCase {
  std::string path, message;
};
FileCase file_error(const std::string& text) {
  const std::string name = ::testing::UnitTest::GetInstance()->current_test_info()->name();
  const auto path = std::filesystem::temp_directory_path() /
                    ("physbench_bad_" + name + "_" + std::to_string(getpid()) + ".json");
  {
    std::ofstream out(path, std::ios::binary);
    out << text;
  }
  FileCase c{path.string(), ""};
  try {
    load_scene_file(c.path);
  } catch (const SceneError& e) {
    c.message = e.what();
  }
  std::filesystem::remove(path);
  return c;
}

// the sample scene as text with one field's JSON text replaced: "bodies":...,"mass":2.0 -> ...
std::string sample_text_with(const std::string& from, const std::string& to) {
  std::string text = to_json(sample_scene()).dump();
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

#define EXPECT_NAMES(c, field_and_what)                                                     \
  do {                                                                                      \
    const FileCase& fc = (c);                                                               \
    EXPECT_EQ(fc.message.rfind(fc.path + ": ", 0), 0u) << fc.message;                       \
    EXPECT_NE(fc.message.find(std::string(": ") + (field_and_what)), std::string::npos)     \
        << fc.message;                                                                      \
  } while (0)

TEST(SceneFile, NumberPastDoubleRangeIsNamedNotAnAbort) {
  // nlohmann throws out_of_range (not parse_error) for these: it used to escape uncaught
  EXPECT_NAMES(file_error(sample_text_with("\"mass\":2.0", "\"mass\":1e400")),
               "bodies[0].mass: the number 1e400 is past the range of a double");
  EXPECT_NAMES(file_error(sample_text_with("\"mass\":2.0", "\"mass\":-1e400")),
               "bodies[0].mass: the number -1e400 is past the range of a double");
  EXPECT_NAMES(file_error(sample_text_with("\"dt\":", "\"dt\":" + std::string(400, '9') + ",\"x\":")),
               "dt: the number 9999");
  EXPECT_NAMES(file_error(sample_text_with("\"position\":[1.0,2.0,3.0]", "\"position\":[1.0,1e999,3.0]")),
               "bodies[0].position[1]: the number 1e999 is past the range");
  EXPECT_NAMES(file_error(sample_text_with("\"stiffness\":100.0", "\"stiffness\":1e-400")),
               "springs[0].stiffness: the number 1e-400 is too small for a double");
}

TEST(SceneFile, IntegerPastItsTypeIsNamed) {
  EXPECT_NAMES(file_error(sample_text_with("\"body_b\":1", "\"body_b\":4294967297")),
               "springs[0].body_b: expected an integer in [-2147483648, 2147483647], got 4294967297");
  EXPECT_NAMES(file_error(sample_text_with("\"body_a\":0", "\"body_a\":-9223372036854775808")),
               "springs[0].body_a: expected an integer in [-2147483648, 2147483647]");
  // 25 digits: past 64 bits, so nlohmann reads it as a double
  EXPECT_NAMES(file_error(sample_text_with("\"body_a\":0", "\"body_a\":1000000000000000000000000")),
               "springs[0].body_a: expected an integer in [-2147483648, 2147483647], got 1e+24");
  EXPECT_NAMES(file_error(sample_text_with("\"dt_divisor\":64", "\"dt_divisor\":2.5")),
               "reference.dt_divisor: expected an integer");
  json doc = to_json(sample_scene());
  doc["particles"] = {{"count", 10}, {"spawn_min", {0, 0, 0}}, {"seed", -1}};
  EXPECT_NE(error_for(doc).find("test.json: particles.seed: expected an integer in [0, "
                                "18446744073709551615], got -1"),
            std::string::npos)
      << error_for(doc);
}

TEST(SceneFile, CountsDurationsStepsAndProbeSizesOverTheirCaps) {
  EXPECT_NAMES(file_error(sample_text_with("\"duration\":1.5", "\"duration\":7200")),
               "duration: must lie in [1e-07, 3600] s, got 7200");
  json doc = to_json(sample_scene());
  doc["dt"] = 1e-6;
  doc["duration"] = 200.0;
  EXPECT_NE(error_for(doc).find("test.json: duration: is 2e+08 steps of dt, over the cap of 100000000"),
            std::string::npos)
      << error_for(doc);
  doc = to_json(sample_scene());
  doc["dt"] = 1e-5;
  doc["duration"] = 100.0;
  doc["probe"]["interval"] = 1e-5;  // 10^7 + 1 samples of two bodies
  EXPECT_NE(error_for(doc).find("test.json: probe: asks for 2e+07 body-samples, over the cap"),
            std::string::npos)
      << error_for(doc);
  doc = to_json(sample_scene());
  doc["particles"] = {{"count", 100000000}, {"spawn_min", {0, 0, 0}}};
  doc["reference"]["kind"] = "none";
  doc["probe"]["metrics"] = json::array();
  EXPECT_NE(error_for(doc).find("test.json: particles.count: is 100000000, over the cap of 10000000"),
            std::string::npos)
      << error_for(doc);
  doc = to_json(sample_scene());
  doc["reference"]["dt_divisor"] = 4096;
  EXPECT_NE(error_for(doc).find("test.json: reference.dt_divisor: must lie in [2, 1024], got 4096"),
            std::string::npos)
      << error_for(doc);
  doc = to_json(sample_scene());
  const json body = doc["bodies"][1];
  for (int i = 0; i < 50'000; ++i) doc["bodies"].push_back(body);
  EXPECT_NE(error_for(doc).find("test.json: bodies: has 50002 entries, over the cap of 50000"),
            std::string::npos)
      << error_for(doc);
}

TEST(SceneFile, ValuesOutsideTheirStatedRangeAreNamed) {
  json doc = to_json(sample_scene());
  doc["bodies"][0]["mass"] = 1e12;
  EXPECT_NE(error_for(doc).find("test.json: bodies[0].mass: must lie in [1e-09, 1e+09] kg"),
            std::string::npos)
      << error_for(doc);
  doc = to_json(sample_scene());
  doc["bodies"][0]["position"][2] = 5e6;
  EXPECT_NE(error_for(doc).find("bodies[0].position[2]: must lie in [-1e+06, 1e+06] m, got 5e+06"),
            std::string::npos)
      << error_for(doc);
  doc = to_json(sample_scene());
  doc["bodies"][1]["shape"]["radius"] = 1e-9;
  EXPECT_NE(error_for(doc).find("bodies[1].shape.radius: must lie in [0.0001, 10000] m"),
            std::string::npos)
      << error_for(doc);
  doc = to_json(sample_scene());
  doc["springs"][0]["stiffness"] = 1e300;
  EXPECT_NE(error_for(doc).find("springs[0].stiffness: must lie in [0, 1e+12] N/m"),
            std::string::npos)
      << error_for(doc);
  doc = to_json(sample_scene());
  doc["probe"]["bodies"] = json::array({1, 0, 1});
  EXPECT_NE(error_for(doc).find("probe.bodies[2]: body 1 is listed twice (also at [0])"),
            std::string::npos)
      << error_for(doc);
}

TEST(SceneFile, NamesThatCannotBecomeFileNamesAreRejected) {
  for (const std::string bad : {"../evil", "a/b", ".hidden", "with space", "tab\there", ""}) {
    json doc = to_json(sample_scene());
    doc["name"] = bad;
    EXPECT_NE(error_for(doc).find("test.json: name: "), std::string::npos) << bad;
  }
  json doc = to_json(sample_scene());
  doc["name"] = std::string(101, 'a');
  EXPECT_NE(error_for(doc).find("test.json: name: is 101 bytes, over the cap of 100"),
            std::string::npos)
      << error_for(doc);
  doc = to_json(sample_scene());
  doc["name"] = "../../etc/passwd";
  EXPECT_NE(error_for(doc).find("name: must start with a letter or digit"), std::string::npos);
  doc = to_json(sample_scene());
  doc["bodies"][0]["name"] = "line\nbreak";
  EXPECT_NE(error_for(doc).find("test.json: bodies[0].name: must not contain control characters"),
            std::string::npos)
      << error_for(doc);
}

TEST(SceneFile, DuplicateKeysAreNamed) {
  // a DOM keeps one of the two silently: which value ran would depend on the parser
  EXPECT_NAMES(file_error(sample_text_with("\"dt\":", "\"dt\":0.5,\"dt\":")),
               "dt: duplicate key");
  EXPECT_NAMES(file_error(sample_text_with("\"mass\":2.0", "\"mass\":2.0,\"mass\":3.0")),
               "bodies[0].mass: duplicate key");
  EXPECT_NAMES(file_error(sample_text_with("\"type\":\"sphere\"",
                                           "\"type\":\"sphere\",\"type\":\"box\"")),
               "bodies[1].shape.type: duplicate key");
}

TEST(SceneFile, FileOverTheSizeCapIsRefusedUnread) {
  const auto path = std::filesystem::temp_directory_path() /
                    ("physbench_bad_huge_" + std::to_string(getpid()) + ".json");
  { std::ofstream out(path); }
  std::filesystem::resize_file(path, limits::kFileBytes + 1);  // sparse: no 64 MiB written
  try {
    load_scene_file(path.string());
    ADD_FAILURE() << "an oversized file was read";
  } catch (const SceneError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(path.string() + ": the file is 67108865 bytes, over the cap of 67108864", 0), 0u)
        << e.what();
  }
  std::filesystem::remove(path);
}

TEST(SceneFile, VersionIsWrittenAndAnUnknownOneIsRefused) {
  EXPECT_EQ(to_json(sample_scene())["version"], kSceneFormatVersion);
  EXPECT_NAMES(file_error(sample_text_with("\"version\":1", "\"version\":2")),
               "version: this build reads scene format version 1, got 2");
  // a file from before the version field reads as version 1
  json doc = to_json(sample_scene());
  doc.erase("version");
  EXPECT_EQ(error_for(doc), "");
}

TEST(SceneFile, NestingPastTheCapIsNamed) {
  const std::string deep = std::string(40, '[') + std::string(40, ']');
  EXPECT_NAMES(file_error(sample_text_with("\"description\":\"two boxes and a spring\"",
                                           "\"description\":" + deep)),
               "description[0][0][0][0][0][0][0][0][0][0][0][0][0][0][0]: nested deeper than 16");
}

TEST(SceneFile, SyntaxErrorsNameTheFieldTheyInterrupt) {
  EXPECT_NAMES(file_error(sample_text_with("\"mass\":2.0", "\"mass\":2.0.0")),
               "bodies[0].mass: not valid JSON");
}

// every input the fuzzer found (adapters/fuzz/regressions) is loaded or refused by name, in the
// normal build, so ./test.sh checks them with and without the sanitizers
TEST(SceneFile, FuzzRegressionInputsAreLoadedOrRefusedByName) {
  int inputs = 0;
  for (const auto& entry : std::filesystem::directory_iterator(PHYSBENCH_FUZZ_REGRESSIONS)) {
    if (!entry.is_regular_file() || entry.path().filename() == "README.md") continue;
    ++inputs;
    const std::string path = entry.path().string();
    try {
      const Scene scene = load_scene_file(path);
      EXPECT_EQ(to_json(scene_from_json(to_json(scene))), to_json(scene)) << path;
    } catch (const SceneError& e) {
      EXPECT_EQ(std::string(e.what()).rfind(path + ": ", 0), 0u) << e.what();
    } catch (const std::exception& e) {
      ADD_FAILURE() << path << ": escaped as " << typeid(e).name() << ": " << e.what();
    }
  }
  EXPECT_GT(inputs, 0) << "no regression inputs in " << PHYSBENCH_FUZZ_REGRESSIONS;
}

}  // namespace
