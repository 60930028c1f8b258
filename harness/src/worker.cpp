#include "physbench/worker.h"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>

#include "physbench/registry.h"
#include "physbench/scene_json.h"

namespace physbench {

using nlohmann::json;

json result_to_json(const RunResult& r) {
  json doc;
  doc["status"] = to_string(r.status);
  doc["message"] = r.message;
  doc["engine_version"] = r.engine_version;
  doc["settings"] = json::array();
  for (const Setting& s : r.settings)
    doc["settings"].push_back({{"name", s.name}, {"value", s.value}, {"why", s.why}});
  doc["steps"] = r.steps;
  doc["wall_seconds"] = r.wall_seconds;
  // optional: the engine's own stage times, summed over the timed repeats
  if (!r.stages.names.empty())
    doc["stages"] = {{"names", r.stages.names},
                     {"seconds", r.stages.seconds},
                     {"steps", r.stages.steps}};
  // optional: the engine's contact points, summed over the first run's steps
  if (r.contacts.steps > 0)
    doc["contacts"] = {{"points", r.contacts.points}, {"steps", r.contacts.steps}};
  doc["bodies"] = r.trajectory.bodies;
  // one row per sample: time, then 13 numbers per body (position, quaternion wxyz, velocity,
  // angular velocity)
  json samples = json::array();
  for (const Sample& s : r.trajectory.samples) {
    json row = json::array({s.time});
    for (const SampledState& b : s.bodies) {
      for (int k = 0; k < 3; ++k) row.push_back(b.position[k]);
      row.push_back(b.orientation.w());
      for (int k = 0; k < 3; ++k) row.push_back(b.orientation.vec()[k]);
      for (int k = 0; k < 3; ++k) row.push_back(b.linear_velocity[k]);
      for (int k = 0; k < 3; ++k) row.push_back(b.angular_velocity[k]);
    }
    samples.push_back(std::move(row));
  }
  doc["samples"] = std::move(samples);
  return doc;
}

namespace {
// JSON has no NaN: nlohmann writes null for it, and null reads back as NaN here
double number_or_nan(const json& v) { return v.is_number() ? v.get<double>() : std::nan(""); }
}  // namespace

RunResult result_from_json(const json& doc) {
  RunResult r;
  r.status = status_from_string(doc.at("status").get<std::string>());
  r.message = doc.at("message").get<std::string>();
  r.engine_version = doc.at("engine_version").get<std::string>();
  for (const json& s : doc.at("settings"))
    r.settings.push_back({s.at("name").get<std::string>(), s.at("value").get<std::string>(),
                          s.at("why").get<std::string>()});
  r.steps = doc.at("steps").get<long>();
  r.wall_seconds = doc.at("wall_seconds").get<std::vector<double>>();
  if (doc.contains("stages")) {
    const json& stages = doc.at("stages");
    r.stages.names = stages.at("names").get<std::vector<std::string>>();
    r.stages.seconds = stages.at("seconds").get<std::vector<double>>();
    r.stages.steps = stages.at("steps").get<long>();
    if (r.stages.seconds.size() != r.stages.names.size() || r.stages.steps <= 0)
      throw std::runtime_error("stages: a time for each name, over a positive number of steps");
  }
  if (doc.contains("contacts")) {
    const json& contacts = doc.at("contacts");
    r.contacts.points = contacts.at("points").get<double>();
    r.contacts.steps = contacts.at("steps").get<long>();
    if (!(r.contacts.points >= 0.0) || r.contacts.steps <= 0)
      throw std::runtime_error("contacts: a count of points >= 0 over a positive number of steps");
  }
  r.trajectory.bodies = doc.at("bodies").get<std::vector<int>>();
  for (const json& row : doc.at("samples")) {
    Sample s;
    s.time = row.at(0).get<double>();
    for (std::size_t b = 0; b < r.trajectory.bodies.size(); ++b) {
      const std::size_t o = 1 + 13 * b;
      auto at = [&](std::size_t k) { return number_or_nan(row.at(o + k)); };
      SampledState state;
      state.position = Vec3(at(0), at(1), at(2));
      state.orientation = Quat(at(3), at(4), at(5), at(6));
      state.linear_velocity = Vec3(at(7), at(8), at(9));
      state.angular_velocity = Vec3(at(10), at(11), at(12));
      s.bodies.push_back(state);
    }
    r.trajectory.samples.push_back(std::move(s));
  }
  return r;
}

namespace {

// PHYSBENCH_TEST_SLOWDOWN=ENGINE[/VARIANT]:SHARE (e.g. rtp/rk4:0.3) stretches that engine's (or
// variant's) timed stepping by the share: the harness's tests inject a known slowdown to show that
// `physbench compare` flags it. Anything malformed is ignored (a test that sets it checks the result)
double test_slowdown(const std::string& engine, const std::string& variant) {
  const char* value = std::getenv("PHYSBENCH_TEST_SLOWDOWN");
  if (!value) return 0.0;
  const std::string text = value;
  const std::size_t colon = text.find(':');
  if (colon == std::string::npos) return 0.0;
  const std::string who = text.substr(0, colon);
  if (who != engine && who != engine + "/" + variant) return 0.0;
  char* end = nullptr;
  const double share = std::strtod(text.c_str() + colon + 1, &end);
  return end && *end == '\0' && share > 0.0 && share < 100.0 ? share : 0.0;
}

}  // namespace

int run_worker(const WorkerJob& job) {
  RunResult result;
  try {
    const Scene scene = load_scene_file(job.scene_path);
    const EngineInfo* engine = find_linked_engine(job.engine);
    if (!engine) {
      result.status = Status::Error;
      result.message = "engine '" + job.engine + "' is not linked into this executable";
    } else {
      SimulateOptions options;
      options.every_steps = job.every_steps;
      options.timing_budget = job.timing_budget;
      options.slowdown = test_slowdown(job.engine, job.variant);
      options.knobs = job.knobs;
      options.timing_only = job.timing_only;
      options.run_cap_seconds = job.run_cap_seconds;
      result = simulate(*engine, job.variant, scene, options);
    }
  } catch (const std::exception& e) {
    // an engine that throws is an error row; one that crashes is caught by the parent
    result.status = Status::Error;
    result.message = e.what();
  }
  const std::string partial = job.out_path + ".partial";
  {
    std::ofstream out(partial);
    out << result_to_json(result).dump();
    if (!out) {
      std::cerr << "worker: cannot write " << partial << '\n';
      return 3;
    }
  }
  std::filesystem::rename(partial, job.out_path);
  return 0;
}

}  // namespace physbench
