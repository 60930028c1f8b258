#include "physbench/runner.h"

#include <sys/utsname.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <chrono>
#include <cmath>
#include <ctime>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <sstream>

#include "physbench/metrics.h"
#include "physbench/mujoco_buffers.h"
#include "physbench/poses.h"
#include "physbench/process.h"
#include "physbench/results_schema.h"
#include "physbench/registry.h"
#include "physbench/scenarios.h"
#include "physbench/scene_json.h"
#include "physbench/worker.h"

#ifndef PHYSBENCH_BUILD_INFO
#define PHYSBENCH_BUILD_INFO "unknown"
#endif
#ifndef PHYSBENCH_SOURCE_DIR
#define PHYSBENCH_SOURCE_DIR "."
#endif

namespace physbench {

namespace fs = std::filesystem;
using nlohmann::json;

#ifndef PHYSBENCH_WORKER_CATALOG
#define PHYSBENCH_WORKER_CATALOG ""
#endif
#ifndef PHYSBENCH_WORKERS_DIR
#define PHYSBENCH_WORKERS_DIR ""
#endif

fs::path worker_catalog_file() {
  if (const char* file = std::getenv("PHYSBENCH_WORKER_CATALOG")) return file;
  return PHYSBENCH_WORKER_CATALOG;
}

fs::path default_workers_dir() {
  if (const char* dir = std::getenv("PHYSBENCH_WORKERS_DIR")) return dir;
  return PHYSBENCH_WORKERS_DIR;
}

std::vector<CatalogEntry> read_worker_catalog(const fs::path& file, const fs::path& workers_dir) {
  std::vector<CatalogEntry> entries;
  if (file.empty()) return entries;
  std::ifstream in(file);
  if (!in) return entries;
  auto split = [](const std::string& text, char by) {
    std::vector<std::string> parts;
    std::string part;
    std::istringstream stream(text);
    while (std::getline(stream, part, by))
      if (!part.empty()) parts.push_back(part);
    return parts;
  };
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    // engine <tab> variants, comma-separated <tab> command line, words separated by spaces
    const std::vector<std::string> fields = split(line, '\t');
    if (fields.size() != 3) continue;
    CatalogEntry entry;
    entry.engine = fields[0];
    entry.variants = split(fields[1], ',');
    entry.command = split(fields[2], ' ');
    if (entry.variants.empty() || entry.command.empty()) continue;
    fs::path program = entry.command[0];
    if (entry.command[0].find('/') == std::string::npos) program = workers_dir / program;
    entry.command[0] = program.string();
    if (access(program.c_str(), X_OK) != 0)
      entry.missing = program.string() + " is not built (cargo missing, or its build failed)";
    entries.push_back(std::move(entry));
  }
  return entries;
}

std::vector<EngineVariant> engine_catalog(const fs::path& self) {
  std::vector<EngineVariant> catalog;
  for (const EngineInfo& info : linked_engines())
    for (const std::string& v : info.variants)
      catalog.push_back({info.name, v, info.version, self, info.test_only});
#ifdef PHYSBENCH_HAVE_BULLET64
  // the double-precision Bullet build lives in its own executable beside this one
  for (std::size_t i = 0; i < catalog.size(); ++i)
    if (catalog[i].engine == "bullet") {
      catalog.insert(catalog.begin() + i + 1, {"bullet", "double", catalog[i].version,
                                               self.parent_path() / "physbench-bullet64"});
      break;
    }
#endif
#ifdef PHYSBENCH_MUJOCO4_VERSION
  // MuJoCo 4 lives in its own executable beside this one (Debian's 2.2.2 here is mujoco-2.2)
  for (std::size_t i = 0; i <= catalog.size(); ++i)
    if (i == catalog.size() || catalog[i].engine == "mujoco-2.2") {
      std::vector<EngineVariant> four;
      for (const std::string& v : mujoco_variants(4000000))
        four.push_back({"mujoco", v, PHYSBENCH_MUJOCO4_VERSION,
                        self.parent_path() / "physbench-mujoco4"});
      catalog.insert(catalog.begin() + long(i), four.begin(), four.end());
      break;
    }
#endif
  // the external workers that are built; their version comes back with each result
  const fs::path catalog_file = worker_catalog_file();
  for (const CatalogEntry& entry : read_worker_catalog(catalog_file, default_workers_dir()))
    if (entry.missing.empty())
      for (const std::string& v : entry.variants)
        catalog.push_back(
            {entry.engine, v, "external worker", entry.command[0], false, entry.command});
  return catalog;
}

namespace {

// a finished run whose energy in play grew by more than this fraction reads `diverged`
constexpr double kDivergedEnergyGrowth = 1.0;

// ---- small helpers --------------------------------------------------------------------------

std::string csv_field(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string quoted = "\"";
  for (char c : text)
    quoted += (c == '"') ? std::string("\"\"") : std::string(1, c == '\n' ? ' ' : c);
  return quoted + "\"";
}

std::string number(double value) {
  if (!std::isfinite(value)) return std::isnan(value) ? "" : (value > 0 ? "inf" : "-inf");
  std::ostringstream out;
  out << std::setprecision(9) << value;
  return out.str();
}

// 64-bit FNV-1a of a text, in hex: the plan's fingerprint (the same text gives the same value on
// every machine, which std::hash does not promise)
std::string fingerprint(const std::string& text) {
  std::uint64_t hash = 0xcbf29ce484222325ull;
  for (unsigned char c : text) hash = (hash ^ c) * 0x100000001b3ull;
  std::ostringstream out;
  out << std::hex << std::setw(16) << std::setfill('0') << hash;
  return out.str();
}

// every bit of a double, for values that are matched rather than read
std::string exact(double value) {
  std::ostringstream out;
  out << std::setprecision(17) << value;
  return out.str();
}

double median(std::vector<double> values) {
  if (values.empty()) return std::nan("");
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

std::string read_first_line(const std::string& command) {
  std::string line;
  if (FILE* pipe = popen(command.c_str(), "r")) {
    char buffer[512];
    if (fgets(buffer, sizeof buffer, pipe)) line = buffer;
    pclose(pipe);
  }
  while (!line.empty() && (line.back() == '\n' || line.back() == '\r')) line.pop_back();
  return line;
}

std::string cpu_model() {
  std::ifstream in("/proc/cpuinfo");
  for (std::string line; std::getline(in, line);)
    if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
  return "unknown";
}

std::string timestamp_utc() {
  const std::time_t now = std::time(nullptr);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&now));
  return text;
}

bool selected(const std::vector<std::string>& filter, const std::string& name) {
  return filter.empty() || std::find(filter.begin(), filter.end(), name) != filter.end();
}

std::string safe_name(std::string s) {
  for (char& c : s)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '.') c = '_';
  return s;
}

// ---- one job in its own process ----------------------------------------------------------------

struct JobPaths {
  fs::path scene, result, log;
};

}  // namespace

RunResult run_worker_job(const EngineVariant& ev, const fs::path& scene_file,
                         const fs::path& result_file, const fs::path& log_file, int every_steps,
                         double timing_budget, double timeout) {
  const struct {
    fs::path scene, result, log;
  } paths{scene_file, result_file, log_file};
  // the protocol's arguments follow the host's `worker` subcommand or the external command
  std::vector<std::string> argv = ev.command;
  if (argv.empty()) argv = {ev.host.string(), "worker"};
  for (const std::string& a : {std::string("--scene"), paths.scene.string(),
                               std::string("--engine"), ev.engine, std::string("--variant"),
                               ev.variant, std::string("--every"), std::to_string(every_steps),
                               std::string("--budget"), number(timing_budget),
                               std::string("--out"), paths.result.string()})
    argv.push_back(a);
  fs::remove(paths.result);
  const ChildOutcome outcome = run_child(argv, paths.log.string(), timeout);
  if (outcome.kind == ChildOutcome::Kind::Interrupted)
    throw RunInterrupted(outcome.signal, outcome.describe());
  RunResult result;
  result.engine_version = ev.version;
  if (outcome.kind == ChildOutcome::Kind::Exited && outcome.exit_code == 0 &&
      fs::exists(paths.result)) {
    std::ifstream in(paths.result);
    try {
      return result_from_json(json::parse(in));
    } catch (const std::exception& e) {
      result.status = Status::Error;
      result.message = std::string("unreadable worker result: ") + e.what();
      return result;
    }
  }
  switch (outcome.kind) {
    case ChildOutcome::Kind::TimedOut:
      result.status = Status::Timeout;
      break;
    case ChildOutcome::Kind::Signalled:
      result.status = Status::Crashed;
      break;
    default:
      result.status = Status::Error;
      break;
  }
  result.message = outcome.describe();
  const std::string tail = tail_of_file(paths.log.string(), 3);
  if (!tail.empty()) result.message += ": " + tail;
  return result;
}

namespace {

RunResult run_job(const EngineVariant& ev, const JobPaths& paths, int every_steps,
                  double timing_budget, double timeout) {
  return run_worker_job(ev, paths.scene, paths.result, paths.log, every_steps, timing_budget,
                        timeout);
}

// ---- the results folder -------------------------------------------------------------------------

// results.csv's columns, in order, from harness/results-schema.json (the generated header)
const std::vector<std::string> kColumns = [] {
  std::vector<std::string> names;
  for (const ResultColumn& c : kResultColumns) names.push_back(c.name);
  return names;
}();

// the probed particles a trajectory file keeps: the seed's particle modes probe a sample of 200
// for the replay viewer (poses/, docs/viewer.md), and no metric reads them, so the CSV keeps the
// first four as it did before (200 made a mode's file 5–9 MB a job, 158 MB for the three modes)
constexpr std::size_t kCsvParticles = 4;

// reference may be null; with one, each row also carries its own body's position error. Probed
// indices from first_particle on are particles, of which the first kCsvParticles are written
void write_trajectory_csv(const fs::path& path, const Trajectory& run, const ErrorSeries& series,
                          const Trajectory* reference, int first_particle) {
  std::ofstream out(path);
  out << "time,body,px,py,pz,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz,position_err,orientation_err,energy_"
         "drift,"
         "linear_momentum_drift,angular_momentum_drift,body_position_err,stack_drift,"
         "penetration\n";
  auto at = [](const std::vector<double>& v, std::size_t k) {
    return k < v.size() ? number(v[k]) : std::string();
  };
  auto at_abs = [](const std::vector<double>& v, std::size_t k) {
    return k < v.size() ? number(std::abs(v[k])) : std::string();
  };
  std::vector<bool> written(run.bodies.size());
  std::size_t particles = 0;
  for (std::size_t b = 0; b < run.bodies.size(); ++b)
    written[b] = run.bodies[b] < first_particle || particles++ < kCsvParticles;
  for (std::size_t k = 0; k < run.samples.size(); ++k) {
    const Sample& s = run.samples[k];
    for (std::size_t b = 0; b < s.bodies.size(); ++b) {
      if (!written[b]) continue;
      const SampledState& st = s.bodies[b];
      out << number(s.time) << ',' << run.bodies[b];
      for (int i = 0; i < 3; ++i) out << ',' << number(st.position[i]);
      out << ',' << number(st.orientation.w());
      for (int i = 0; i < 3; ++i) out << ',' << number(st.orientation.vec()[i]);
      for (int i = 0; i < 3; ++i) out << ',' << number(st.linear_velocity[i]);
      for (int i = 0; i < 3; ++i) out << ',' << number(st.angular_velocity[i]);
      // the error series are per sample (worst body), repeated on each body's row
      out << ',' << at(series.position_error, k) << ',' << at(series.orientation_error, k) << ','
          << at_abs(series.energy_change, k) << ',' << at(series.linear_momentum_drift, k) << ','
          << at(series.angular_momentum_drift, k) << ',';
      if (reference && k < reference->samples.size())
        out << number((st.position - reference->samples[k].bodies[b].position).norm());
      out << ',' << at(series.stack_drift, k) << ',' << at(series.penetration, k) << '\n';
    }
  }
}

struct ReferenceRun {
  bool available = false;
  // converged, not available: the failed run's status ("timeout", "error", …) and why
  std::string failed_status;
  std::string failure;
  Trajectory trajectory;             // converged: the dt/divisor run
  double self_error = std::nan("");  // converged: difference to the dt/(2·divisor) run
};

struct PreparedScene {
  Scene scene;
  std::string question;
  std::vector<double> dts;  // the scene's own step first when it is swept
  std::string family;       // scenarios that map one parameter, e.g. stiff-spring
  std::string parameter_name;
  double parameter = std::nan("");
};

// "120hz" for a step that is a whole rate, else the step in seconds
std::string step_tag(double dt) {
  const double rate = 1.0 / dt;
  if (std::abs(rate - std::round(rate)) < 1e-9 * rate)
    return std::to_string(std::lround(rate)) + "hz";
  return number(dt) + "s";
}

// the converged reference: rtp RK4 at dt/divisor, and again at dt/(2·divisor) to show it converged
ReferenceRun converged_reference(const Scene& scene, const std::string& tag, const fs::path& out,
                                 const fs::path& work, const fs::path& self, double timeout) {
  ReferenceRun reference;
  const EngineVariant rtp_rk4{"rtp", "rk4", rtp_engine_info().version, self};
  std::vector<Trajectory> runs;
  for (int factor : {1, 2}) {
    const int divisor = scene.reference.dt_divisor * factor;
    const fs::path file =
        out / "scenes" / (tag + ".reference-dt-over-" + std::to_string(divisor) + ".json");
    save_scene_file(refined(scene, divisor), file.string());
    std::cerr << "  reference for " << tag << ": rtp rk4 at dt/" << divisor << "\n";
    const RunResult r = run_job(rtp_rk4, {file, work / "reference.json", work / "reference.log"},
                                scene.probe_every_steps() * divisor, 0.0, timeout);
    if (r.status != Status::Ok) {
      reference.failed_status = to_string(r.status);
      reference.failure = "reference run (rtp rk4 at dt/" + std::to_string(divisor) + ") " +
                          to_string(r.status) + ": " + r.message;
      std::cerr << "  reference for " << tag << " failed: " << reference.failure << "\n";
      return reference;
    }
    runs.push_back(r.trajectory);
  }
  reference.available = true;
  reference.trajectory = runs[0];
  // converged when halving the step once more changes the answer by this little
  Scene check = scene;
  check.probe.metrics = {Metric::Position, Metric::Orientation};
  const ErrorSummary self_check = summarise(compare(check, runs[0], &runs[1]));
  reference.self_error = std::max(self_check.position->max, self_check.orientation->max);
  return reference;
}

}  // namespace

fs::path source_directory() { return PHYSBENCH_SOURCE_DIR; }

void check_row(const std::map<std::string, std::string>& row) {
  const std::string where = "row " + (row.count("scenario") ? row.at("scenario") : "?") + " " +
                            (row.count("engine") ? row.at("engine") : "?") + "/" +
                            (row.count("variant") ? row.at("variant") : "?");
  const auto bad = [&](const std::string& column, const std::string& why) {
    return RunError(where + ": column " + column + " " + why +
                    " (harness/results-schema.json; a defect of physbench, not of the scene)");
  };
  for (const auto& [key, value] : row)
    if (std::none_of(std::begin(kResultColumns), std::end(kResultColumns),
                     [&](const ResultColumn& c) { return key == c.name; }))
      throw bad(key, "is not in the schema");
  const auto is_number = [](const std::string& text) {
    if (text == "inf" || text == "-inf") return true;
    char* end = nullptr;
    const double value = std::strtod(text.c_str(), &end);
    return !text.empty() && end == text.c_str() + text.size() && std::isfinite(value);
  };
  for (const ResultColumn& c : kResultColumns) {
    const auto found = row.find(c.name);
    const std::string value = found == row.end() ? "" : found->second;
    if (value.empty()) {
      if (c.required) throw bad(c.name, "is empty on a row that must fill it");
      continue;
    }
    const std::string type = c.type;
    bool fits = true;
    if (type == "number") {
      fits = is_number(value);
    } else if (type == "integer") {
      fits = value.find_first_not_of("-0123456789") == std::string::npos && is_number(value);
    } else if (type == "numbers") {
      // an empty part is a value that could not be computed, as an empty cell is
      std::stringstream parts(value);
      for (std::string part; std::getline(parts, part, ';');)
        fits = fits && (part.empty() || is_number(part));
    } else if (type == "status") {
      fits = std::any_of(std::begin(kResultStatuses), std::end(kResultStatuses),
                         [&](const char* s) { return value == s; });
    }
    if (!fits) throw bad(c.name, "holds '" + value + "', not a " + type);
  }
}

std::pair<int, int> parse_shard(const std::string& text) {
  const auto bad = [&](const std::string& why) {
    return RunError("--shard " + text + ": " + why +
                    " (write K/N: the K-th of N slices, 1 ≤ K ≤ N, e.g. --shard 2/4)");
  };
  const std::size_t slash = text.find('/');
  if (slash == std::string::npos) throw bad("no '/'");
  auto whole = [&](const std::string& part, const char* what) {
    if (part.empty() || part.size() > 6 ||
        !std::all_of(part.begin(), part.end(), [](char c) { return c >= '0' && c <= '9'; }))
      throw bad(std::string(what) + " is not a whole number");
    return std::stoi(part);
  };
  const int k = whole(text.substr(0, slash), "K"), n = whole(text.substr(slash + 1), "N");
  if (n < 1) throw bad("N must be at least 1");
  if (k < 1 || k > n) throw bad("K must be between 1 and N");
  return {k, n};
}

int run_suite(const RunOptions& options, const fs::path& self) {
  if (options.shard_count < 1 || options.shard_index < 1 ||
      options.shard_index > options.shard_count)
    throw RunError("shard " + std::to_string(options.shard_index) + "/" +
                   std::to_string(options.shard_count) + " is not a slice of the plan");
  // ---- check every name before running anything
  const std::vector<EngineVariant> catalog = engine_catalog(self);
  auto known_engines = [&] {
    std::string names;
    for (const EngineVariant& ev : catalog)
      if (!ev.test_only && names.find(ev.engine) == std::string::npos)
        names += (names.empty() ? "" : ", ") + ev.engine;
    return names;
  };
  for (const std::string& e : options.engines)
    if (std::none_of(catalog.begin(), catalog.end(),
                     [&](const EngineVariant& ev) { return ev.engine == e; }))
      throw RunError("unknown engine '" + e + "' (this build has: " + known_engines() + ")");
  for (const std::string& v : options.variants)
    if (std::none_of(catalog.begin(), catalog.end(),
                     [&](const EngineVariant& ev) { return ev.variant == v; }))
      throw RunError("unknown variant '" + v + "' (see `physbench list`)");

  std::vector<PreparedScene> scenes;
  std::vector<std::string> wanted = options.scenarios;
  if (wanted.empty() && options.scene_files.empty())
    for (const Scenario& s : physbench::scenarios()) wanted.push_back(s.name);
  for (const std::string& name : wanted) {
    const Scenario* scenario = find_scenario(name);
    if (!scenario) {
      std::string names;
      for (const Scenario& s : physbench::scenarios())
        names += (names.empty() ? "" : ", ") + s.name;
      throw RunError("unknown scenario '" + name + "' (built in: " + names + ")");
    }
    PreparedScene p{scenario->build(), scenario->question,       scenario->sweep_dt,
                    scenario->family,  scenario->parameter_name, scenario->parameter};
    scenes.push_back(std::move(p));
  }
  for (const std::string& file : options.scene_files) {
    try {
      PreparedScene p;  // no dt sweep and no family: the file's own step only
      p.scene = load_scene_file(file);
      p.question = "scene file " + file;
      scenes.push_back(std::move(p));
    } catch (const SceneError& e) {
      throw RunError(e.what());
    }
  }
  for (PreparedScene& p : scenes) {
    if (options.dt) p.scene.dt = *options.dt;
    if (options.duration) p.scene.duration = *options.duration;
    if (!options.sweep_dt.empty()) p.dts = options.sweep_dt;
    if (options.dt || options.no_sweep) p.dts.clear();
    // the scene's own step first; the sweep's other steps after it
    std::erase_if(p.dts, [&](double dt) { return std::abs(dt - p.scene.dt) < 1e-12 * p.scene.dt; });
    p.dts.insert(p.dts.begin(), p.scene.dt);
    for (double dt : p.dts) {
      Scene instance = p.scene;
      instance.dt = dt;
      try {
        validate(instance);
      } catch (const SceneError& e) {
        throw RunError(p.scene.name + " at dt = " + number(dt) +
                       " with the overrides given: " + e.what());
      }
    }
  }

  std::vector<EngineVariant> jobs_engines;
  for (const EngineVariant& ev : catalog)
    // a test-only engine runs only when named: "every engine" never includes it
    if (selected(options.engines, ev.engine) && selected(options.variants, ev.variant) &&
        (!ev.test_only || !options.engines.empty()))
      jobs_engines.push_back(ev);
  if (jobs_engines.empty()) throw RunError("no engine variant matches the filters given");

  // ---- the plan: every scene step (a scene at one of its steps) in order, numbered from 0, each
  // with every engine variant; job s·E + e is step s on engine variant e. A shard runs the steps
  // whose number is K−1 modulo N, every engine of a step in one shard, so that the engines of a
  // scene are always timed on one machine, one after another. The plan's fingerprint covers each
  // scene as it will run, the engine variants and the timing budget, so `merge` can refuse shards
  // of different plans
  const std::size_t engines_per_step = jobs_engines.size();
  std::size_t steps_planned = 0;
  std::string plan_text = "budget " + exact(options.timing_budget) + "\n";
  for (const PreparedScene& p : scenes)
    for (double dt : p.dts) {
      Scene scene = p.scene;
      scene.dt = dt;
      plan_text += to_json(scene).dump() + "\n";
      for (const EngineVariant& ev : jobs_engines) plan_text += ev.engine + "/" + ev.variant + "\n";
      ++steps_planned;
    }
  const auto step_in_shard = [&](std::size_t step) {
    return step % std::size_t(options.shard_count) == std::size_t(options.shard_index - 1);
  };

  // ---- the results folder; results.csv appears only when complete
  const fs::path out = options.out;
  if (fs::exists(out) && (!fs::is_directory(out) || !fs::is_empty(out)))
    throw RunError("the results folder " + out.string() +
                   " already holds files (an earlier run?): physbench writes only into a new or "
                   "empty folder; choose another --out");
  // from here on SIGINT and SIGTERM stop the running job and leave the folder marked incomplete
  install_interrupt_handlers();
  fs::create_directories(out / "scenes");
  fs::create_directories(out / "trajectories");
  fs::create_directories(out / "poses");
  const fs::path work = out / ".work";
  fs::create_directories(work);
  std::ofstream csv(out / "results.csv.partial");
  for (std::size_t i = 0; i < kColumns.size(); ++i) csv << (i ? "," : "") << kColumns[i];
  csv << '\n';

  json metadata;
  metadata["created"] = timestamp_utc();
  metadata["command"] = options.command_line;
  metadata["git_commit"] = read_first_line(std::string("git -C '") + PHYSBENCH_SOURCE_DIR +
                                           "' rev-parse HEAD 2>/dev/null");
  utsname uts{};
  uname(&uts);
  metadata["machine"] = {{"cpu", cpu_model()},
                         {"logical_cores", sysconf(_SC_NPROCESSORS_ONLN)},
                         {"memory_gib", std::round(double(sysconf(_SC_PHYS_PAGES)) *
                                                   double(sysconf(_SC_PAGE_SIZE)) / (1 << 30))},
                         {"os", std::string(uts.sysname) + " " + uts.release},
                         {"hostname", uts.nodename}};
  metadata["build"] = PHYSBENCH_BUILD_INFO;
  metadata["compiler"] = std::string("g++ ") + __VERSION__;
  metadata["timing"] = {
      {"budget_s", options.timing_budget},
      {"note",
       "each job: one warm-up run that records the trajectory, then timed repeats on a "
       "fresh world until the budget is spent (at least 3); steps/s is the median"}};
  metadata["engines"] = json::object();
  metadata["scenarios"] = json::object();

  // the replay viewer's pose files (docs/viewer.md): each scene at its own step, within the caps
  json& poses_meta = metadata["poses"];
  poses_meta = {{"format",
                 "PBPOSES2: float32 px py pz qx qy qz qw |v| per body per frame; contact scenes "
                 "also each body's deepest penetration per frame and every contact point "
                 "(x y z depth), docs/viewer.md"},
                {"frame_rate", kPoseFrameRate},
                {"bytes_per_job_cap", kPoseBytesPerJob},
                {"bytes_per_run_cap", kPoseBytesPerRun},
                {"files", 0},
                {"bytes", 0},
                {"not_written", json::object()},
                {"contacts_not_written", json::object()}};
  std::uint64_t pose_bytes = 0;

  std::size_t total = 0, done = 0, rows_written = 0;
  for (std::size_t s = 0; s < steps_planned; ++s) total += step_in_shard(s) ? engines_per_step : 0;
  metadata["plan"] = {{"fingerprint", fingerprint(plan_text)},
                      {"jobs", steps_planned * engines_per_step},
                      {"shard", {{"index", options.shard_index}, {"count", options.shard_count}}},
                      {"jobs_in_shard", total},
                      {"row_jobs", json::array()}};  // each row's job number, in row order
  json& row_jobs = metadata["plan"]["row_jobs"];

  int failures = 0;
  std::size_t step_number = 0;  // in the whole plan
  try {
  for (const PreparedScene& p : scenes) {
    bool any_step = false;
    for (std::size_t i = 0; i < p.dts.size(); ++i) any_step |= step_in_shard(step_number + i);
    if (!any_step) {
      step_number += p.dts.size();
      continue;
    }
    json& scenario_meta = metadata["scenarios"][p.scene.name];
    scenario_meta = {{"description", p.scene.description},
                     {"question", p.question},
                     {"dt", p.scene.dt},
                     {"sweep_dt", p.dts},
                     {"duration", p.scene.duration},
                     {"planar", p.scene.planar},
                     {"reference", to_string(p.scene.reference.kind)},
                     {"reference_dt_divisor", p.scene.reference.dt_divisor},
                     {"reference_self_error", json::object()},
                     {"family", p.family},
                     {"parameter_name", p.parameter_name},
                     {"parameter", p.parameter},
                     {"scene_file", json::object()}};
    for (double dt : p.dts) {
      const std::size_t this_step = step_number++;
      if (!step_in_shard(this_step)) continue;
      Scene scene = p.scene;
      scene.dt = dt;
      // one file per step when the scene is swept, else the scene's own name
      const std::string tag =
          safe_name(p.dts.size() > 1 ? scene.name + ".dt-" + step_tag(dt) : scene.name);
      const fs::path scene_file = out / "scenes" / (tag + ".json");
      save_scene_file(scene, scene_file.string());
      const int every = scene.probe_every_steps();

      // ---- the reference this scene compares with
      ReferenceRun reference;
      if (scene.reference.kind == ReferenceKind::Converged)
        reference = converged_reference(scene, tag, out, work, self, options.timeout_seconds);
      scenario_meta["reference_self_error"][number(dt)] = reference.self_error;
      if (!reference.failure.empty())
        scenario_meta["reference_failure"][number(dt)] = reference.failure;
      scenario_meta["scene_file"][number(dt)] = fs::relative(scene_file, out).string();

      int dynamic_bodies = 0;
      for (const BodySpec& b : scene.bodies) dynamic_bodies += b.mass > 0.0;
      // particles count as bodies here: body_steps_per_s is particle-steps/s in a particle scene
      if (scene.particles) dynamic_bodies += static_cast<int>(scene.particles->count);

      for (std::size_t e = 0; e < engines_per_step; ++e) {
        const EngineVariant& ev = jobs_engines[e];
        const std::size_t this_job = this_step * engines_per_step + e;
        ++done;
        const std::string job = tag + "__" + safe_name(ev.engine + "__" + ev.variant);
        std::cerr << "[" << done << "/" << total << "] " << tag << "  " << ev.engine << "/"
                  << ev.variant << " ... " << std::flush;
        RunResult r = run_job(ev, {scene_file, work / (job + ".json"), work / (job + ".log")},
                              every, options.timing_budget, options.timeout_seconds);
        if (r.status == Status::NotApplicable) {
          std::cerr << "not applicable here\n";
          continue;
        }

        // an engine whose every row is unsupported has no entry (not a null one)
        if (r.status != Status::Unsupported && r.status != Status::Crashed &&
            r.status != Status::Timeout) {
          json& engine_meta = metadata["engines"][ev.engine];
          engine_meta["version"] = r.engine_version;
          json settings = json::array();
          for (const Setting& s : r.settings)
            settings.push_back({{"name", s.name}, {"value", s.value}, {"why", s.why}});
          engine_meta["variants"][ev.variant] = settings;
        }

        std::map<std::string, std::string> row;
        row["scenario"] = scene.name;
        row["engine"] = ev.engine;
        row["variant"] = ev.variant;
        row["engine_version"] = r.engine_version;
        row["family"] = p.family;
        row["parameter"] = number(p.parameter);
        row["dt"] = exact(scene.dt);  // full precision: rows are matched to their scenario's step
        row["duration"] = number(scene.duration);
        row["steps"] = std::to_string(scene.step_count());
        row["bodies"] = std::to_string(dynamic_bodies);
        row["reference"] = to_string(scene.reference.kind);
        // a converged reference is a job of its own: whether it ran is on every row that needs it
        if (scene.reference.kind == ReferenceKind::Converged)
          row["reference_status"] = reference.available ? "ok" : reference.failed_status;
        row["reference_self_error"] = number(reference.self_error);
        std::string message = r.message;

        if (r.status == Status::Ok || r.status == Status::Exploded) {
          if (!r.wall_seconds.empty()) {
            const double wall = median(r.wall_seconds);
            const double steps = static_cast<double>(r.steps);
            const auto [lo, hi] = std::minmax_element(r.wall_seconds.begin(), r.wall_seconds.end());
            row["repeats"] = std::to_string(r.wall_seconds.size());
            row["wall_s_median"] = number(wall);
            row["steps_per_s"] = number(steps / wall);
            row["steps_per_s_min"] = number(steps / *hi);
            row["steps_per_s_max"] = number(steps / *lo);
            // every repeat, for `physbench compare`'s rank test (docs/regression.md), to four
            // digits: a nightly history keeps them for years
            std::string repeats;
            char digits[32];
            for (double seconds : r.wall_seconds) {
              std::snprintf(digits, sizeof digits, "%.4g", steps / seconds);
              repeats += (repeats.empty() ? "" : ";") + std::string(digits);
            }
            row["steps_per_s_repeats"] = repeats;
            row["body_steps_per_s"] = number(steps * dynamic_bodies / wall);
            row["realtime_factor"] = number(scene.duration / wall);
            if (r.status == Status::Exploded) {
              // the run stopped early: its speed is not comparable
              for (const char* key : {"steps_per_s", "steps_per_s_min", "steps_per_s_max",
                                      "steps_per_s_repeats",
                                      "body_steps_per_s", "realtime_factor"})
                row[key] = "";
            }
          }
          try {
            Trajectory closed_form;
            const Trajectory* against = nullptr;
            if (has_analytic_reference(scene)) {
              closed_form = analytic_reference(scene, r.trajectory);
              against = &closed_form;
            } else if (scene.reference.kind == ReferenceKind::Converged) {
              if (reference.available)
                against = &reference.trajectory;
              else
                message += (message.empty() ? "" : "; ") +
                           std::string("no position or orientation error: ") + reference.failure;
            }
            Scene measured = scene;
            if (!against) {
              // without a reference only the invariants can be judged
              std::erase_if(measured.probe.metrics, [](Metric m) {
                return m == Metric::Position || m == Metric::Orientation;
              });
            }
            const ErrorSeries series = compare(measured, r.trajectory, against);
            const ErrorSummary summary = summarise(series);
            auto put = [&](const char* prefix, const std::optional<SeriesSummary>& s,
                           bool with_rms) {
              if (!s) return;
              if (with_rms) row[std::string(prefix) + "_rms"] = number(s->rms);
              row[std::string(prefix) + "_max"] = number(s->max);
              row[std::string(prefix) + "_final"] = number(s->final);
            };
            put("position_err", summary.position, true);
            put("orientation_err", summary.orientation, true);
            put("energy_drift", summary.energy, false);
            if (summary.energy_change_final)
              row["energy_change_final"] = number(*summary.energy_change_final);
            row["stability"] =
                r.status == Status::Exploded ? "exploded" : stability_of(scene, series);
            // a finished run whose energy more than doubled is not a success to skim past;
            // contact scenes are left out: their energy at rest is in joules, not relative
            if (r.status == Status::Ok && !scene.has_contacts() && !series.energy_change.empty()) {
              const double grew =
                  *std::max_element(series.energy_change.begin(), series.energy_change.end());
              if (!(grew <= kDivergedEnergyGrowth)) {
                r.status = Status::Diverged;
                std::ostringstream why;
                why << "energy grew to " << std::setprecision(3) << 1.0 + grew
                    << " times the energy in play (over +100 %)";
                message = why.str() + (message.empty() ? "" : "; " + message);
              }
            }
            put("linear_momentum_drift", summary.linear_momentum, false);
            put("angular_momentum_drift", summary.angular_momentum, false);
            put("stack_drift", summary.stack_drift, false);
            put("penetration", summary.penetration, false);
            // the contact scene's own question; an empty value could not be computed
            const ContactSummary contact = contact_summary(scene, r.trajectory, series);
            auto put_value = [&](const char* key, const std::optional<double>& v) {
              if (v) row[key] = number(*v);
            };
            put_value("top_height_change", contact.top_height_change);
            put_value("energy_added_max", contact.energy_added_max);
            put_value("speed_max", contact.speed_max);
            put_value("rest_speed_rms", contact.rest_speed_rms);
            std::string apexes;
            for (double e : contact.apex_relative_errors) {
              if (!apexes.empty()) apexes += ';';
              apexes += number(e);
            }
            row["apex_rel_err"] = apexes;
            put_value("apex_rel_err_max", contact.apex_relative_error_max);
            put_value("slide_distance", contact.slide_distance);
            put_value("slide_accel", contact.slide_acceleration);
            put_value("slide_accel_expected", contact.slide_acceleration_expected);
            put_value("slide_accel_rel_err", contact.slide_acceleration_error);
            put_value("exchange_err", contact.exchange_error);
            if (contact.tunnelled) row["tunnelled"] = *contact.tunnelled ? "1" : "0";
            if (contact.escaped) row["escaped"] = std::to_string(*contact.escaped);
            row["contact_verdict"] = contact.verdict;
            if (r.status == Status::Exploded && scene.has_contacts())
              row["contact_verdict"] = "exploded";
            else if (!contact.message.empty())
              message += (message.empty() ? "" : "; ") + contact.message;
            const fs::path trajectory = out / "trajectories" / (job + ".csv");
            write_trajectory_csv(trajectory, r.trajectory, series, against, int(scene.bodies.size()));
            row["trajectory"] = fs::relative(trajectory, out).string();
            if (std::abs(dt - p.scene.dt) <= 1e-9 * p.scene.dt) {
              // a contact scene's file also holds its contacts, counted against the same caps
              std::optional<OverlapGauge> contacts;
              if (scene.has_contacts()) contacts.emplace(scene, r.trajectory.bodies);
              const OverlapGauge* gauge = contacts ? &*contacts : nullptr;
              PoseLayout layout = pose_layout(r.trajectory, gauge);
              if (gauge && layout.frames > 0 && layout.contact_stride == 0)
                poses_meta["contacts_not_written"][job] =
                    "one frame's contacts exceed what the job cap leaves";
              // near the run's cap the poses go without their contacts rather than not at all
              if (layout.contact_stride > 0 && pose_bytes + layout.bytes > kPoseBytesPerRun) {
                layout = pose_layout(r.trajectory);
                gauge = nullptr;
                poses_meta["contacts_not_written"][job] = "the run's pose files neared their cap";
              }
              if (layout.frames == 0)
                poses_meta["not_written"][job] = "no samples, or two frames exceed the job cap";
              else if (pose_bytes + layout.bytes > kPoseBytesPerRun)
                poses_meta["not_written"][job] = "the run's pose files reached their cap";
              else {
                write_pose_file(out / "poses" / (job + ".bin"), r.trajectory, layout, gauge);
                pose_bytes += layout.bytes;
                poses_meta["files"] = poses_meta["files"].get<int>() + 1;
                poses_meta["bytes"] = pose_bytes;
              }
            }
          } catch (const std::exception& e) {
            message += (message.empty() ? "" : "; ") + std::string("metrics failed: ") + e.what();
          }
        }
        if (r.status == Status::Crashed || r.status == Status::Timeout || r.status == Status::Error)
          ++failures;
        row["status"] = to_string(r.status);
        row["message"] = message;
        check_row(row);  // a row that does not fit the schema stops the run, named
        for (std::size_t i = 0; i < kColumns.size(); ++i)
          csv << (i ? "," : "") << csv_field(row[kColumns[i]]);
        csv << '\n';
        csv.flush();  // an interrupted run keeps every finished row
        ++rows_written;
        row_jobs.push_back(this_job);

        std::cerr << row["status"];
        if (!row["steps_per_s"].empty()) std::cerr << "  " << row["steps_per_s"] << " steps/s";
        if (!row["position_err_max"].empty())
          std::cerr << "  pos err max " << row["position_err_max"] << " m";
        if (!row["orientation_err_max"].empty())
          std::cerr << "  orient err max " << row["orientation_err_max"] << " rad";
        if (!row["energy_drift_max"].empty())
          std::cerr << "  energy drift " << row["energy_drift_max"];
        if (!row["contact_verdict"].empty()) std::cerr << "  " << row["contact_verdict"];
        if (!row["stack_drift_max"].empty()) std::cerr << "  drift " << row["stack_drift_max"] << " m";
        if (!row["penetration_max"].empty())
          std::cerr << "  penetration max " << row["penetration_max"] << " m";
        if (r.status != Status::Ok || !message.empty()) std::cerr << "  (" << message << ")";
        std::cerr << '\n';
      }
    }
  }

  } catch (const RunInterrupted& e) {
    // the rows done so far stay in results.csv.partial; results.csv never appears
    csv.close();
    metadata["interrupted"] = {{"signal", e.signal},
                               {"rows_written", rows_written},
                               {"jobs_total", total}};
    {
      std::ofstream meta(out / "metadata.json.partial");
      meta << metadata.dump(2) << '\n';
    }
    {
      std::ofstream note(out / "INCOMPLETE");
      note << "This run was interrupted by signal " << e.signal << " (" << strsignal(e.signal)
           << ") during job " << done << " of " << total
           << "; that job's process group was killed.\n"
              "results.csv.partial holds the "
           << rows_written
           << " rows written before it, metadata.json.partial the metadata. No results.csv was "
              "written.\n";
    }
    fs::remove_all(work);
    throw;
  } catch (const RunError& e) {
    // a row that does not fit the schema: the rows before it stay, and the folder says why
    csv.close();
    std::ofstream(out / "INCOMPLETE") << "This run stopped at job " << done << " of " << total
                                      << ": " << e.what() << "\nresults.csv.partial holds the "
                                      << rows_written << " rows written before it.\n";
    fs::remove_all(work);
    throw;
  }

  csv.close();
  if (!csv) throw RunError("cannot write " + (out / "results.csv").string());
  {
    std::ofstream meta(out / "metadata.json.partial");
    meta << metadata.dump(2) << '\n';
  }
  fs::rename(out / "metadata.json.partial", out / "metadata.json");
  fs::rename(out / "results.csv.partial", out / "results.csv");
  fs::remove_all(work);
  return failures;
}

}  // namespace physbench
