#include "physbench/results_folder.h"

#include <sys/utsname.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <optional>

#include "physbench/overlaps.h"
#include "physbench/poses.h"
#include "physbench/results_schema.h"
#include "physbench/scene_json.h"
#include "text.h"

#ifndef PHYSBENCH_BUILD_INFO
#define PHYSBENCH_BUILD_INFO "unknown"
#endif
#ifndef PHYSBENCH_SOURCE_DIR
#define PHYSBENCH_SOURCE_DIR "."
#endif

namespace physbench {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// ---- the schema ---------------------------------------------------------------------------------

const ResultColumn* schema_column(std::string_view name) {
  for (const ResultColumn& c : kResultColumns)
    if (name == c.name) return &c;
  return nullptr;
}

bool is_number(const std::string& text) {
  if (text == "inf" || text == "-inf") return true;
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  return !text.empty() && end == text.c_str() + text.size() && std::isfinite(value);
}

// ---- machine and build --------------------------------------------------------------------------

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

std::string csv_field(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string quoted = "\"";
  for (char c : text)
    quoted += (c == '"') ? std::string("\"\"") : std::string(1, c == '\n' ? ' ' : c);
  return quoted + "\"";
}

// ---- trajectories -------------------------------------------------------------------------------

// the probed particles a trajectory file keeps: the seed's particle modes probe a sample of 200
// for the replay viewer (poses/, docs/viewer.md), and no metric reads them, so the CSV keeps the
// first four as it did before (200 made a mode's file 5–9 MB a job, 158 MB for the three modes)
constexpr std::size_t kCsvParticles = 4;

// the bodies whose states a trajectory keeps, unless the run keeps them all
// (--all-trajectories): at most kTrajectoryBodies (kContactTrajectoryBodies on a contact scene),
// spread evenly over the probed ones, the first and the last among them (a stack's bottom and top,
// a chain's ends). The per-sample columns (the error series, the stack's drift and penetration,
// the energy) come from every probed body, so no metric or chart loses anything; a free-motion
// scene keeps more because its chart draws each body's error. A pyramid's every box made one
// run's folder 1 GB (docs/usage.md, "The results folder")
constexpr std::size_t kTrajectoryBodies = 8, kContactTrajectoryBodies = 4;

std::vector<bool> kept_bodies(std::size_t probed, bool all, std::size_t most) {
  std::vector<bool> kept(probed, all || probed <= most);
  if (probed > most && !all)
    for (std::size_t k = 0; k < most; ++k)
      kept[(k * (probed - 1) + (most - 1) / 2) / (most - 1)] = true;
  return kept;
}

// reference may be null; with one, each row also carries its own body's position error. Probed
// indices from first_particle on are particles, of which the first kCsvParticles are written
void write_trajectory_csv(const fs::path& path, const Scene& scene, const Trajectory& run,
                          const ErrorSeries& series, const Trajectory* reference,
                          int first_particle, bool all_bodies) {
  std::ofstream out(path);
  out << "time,body,px,py,pz,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz,position_err,orientation_err,energy_"
         "drift,"
         "linear_momentum_drift,angular_momentum_drift,body_position_err,stack_drift,"
         "penetration,energy_change_j\n";
  auto at = [](const std::vector<double>& v, std::size_t k) {
    return k < v.size() ? number(v[k]) : std::string();
  };
  auto at_abs = [](const std::vector<double>& v, std::size_t k) {
    return k < v.size() ? number(std::abs(v[k])) : std::string();
  };
  std::vector<int> rigid;  // the probed bodies, particles left out
  for (int b : run.bodies)
    if (b < first_particle) rigid.push_back(b);
  const std::size_t most = scene.has_contacts() ? kContactTrajectoryBodies : kTrajectoryBodies;
  const std::vector<bool> kept = kept_bodies(rigid.size(), all_bodies, most);
  std::vector<bool> written(run.bodies.size());
  std::size_t particles = 0, bodies = 0;
  for (std::size_t b = 0; b < run.bodies.size(); ++b)
    written[b] = run.bodies[b] < first_particle ? bool(kept[bodies++]) : particles++ < kCsvParticles;
  const double energy_at_start =
      run.samples.empty() ? 0.0 : body_energy(scene, run.bodies, run.samples.front());
  for (std::size_t k = 0; k < run.samples.size(); ++k) {
    const Sample& s = run.samples[k];
    // E(t) − E(0) of every probed body (J): the energy chart's series, whichever bodies are kept
    const std::string energy_change =
        rigid.empty() ? std::string() : number(body_energy(scene, run.bodies, s) - energy_at_start);
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
      out << ',' << at(series.stack_drift, k) << ',' << at(series.penetration, k) << ','
          << energy_change << '\n';
    }
  }
}

}  // namespace

// ---- the typed row ------------------------------------------------------------------------------

void ResultRow::set(std::string_view column, std::string_view kinds, std::string value) {
  const ResultColumn* c = schema_column(column);
  if (!c)
    throw RunError("results row: column " + std::string(column) +
                   " is not in the schema (harness/results-schema.json; a defect of physbench)");
  // kinds: the column types this setter writes, separated by spaces
  const std::string type = c->type;
  std::string_view rest = kinds;
  bool fits = false;
  while (!rest.empty() && !fits) {
    const std::size_t space = rest.find(' ');
    fits = rest.substr(0, space) == type;
    rest = space == std::string_view::npos ? std::string_view() : rest.substr(space + 1);
  }
  if (!fits)
    throw RunError("results row: column " + std::string(column) + " is of type " + type +
                   ", written as " + std::string(kinds) +
                   " (harness/results-schema.json; a defect of physbench)");
  cells_[std::string(column)] = std::move(value);
}

void ResultRow::text(std::string_view column, std::string value) {
  set(column, "string status", std::move(value));
}
void ResultRow::number(std::string_view column, double value) {
  set(column, "number", physbench::number(value));
}
void ResultRow::exact(std::string_view column, double value) {
  set(column, "number", physbench::exact(value));
}
void ResultRow::integer(std::string_view column, long long value) {
  set(column, "integer", std::to_string(value));
}
void ResultRow::numbers(std::string_view column, const std::vector<double>& values, int digits) {
  std::string text;
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (i) text += ';';
    if (std::isnan(values[i])) continue;
    char part[40];
    std::snprintf(part, sizeof part, "%.*g", digits, values[i]);
    text += std::isfinite(values[i]) ? std::string(part) : physbench::number(values[i]);
  }
  set(column, "numbers", std::move(text));
}

const std::string& ResultRow::operator[](std::string_view column) const {
  static const std::string empty;
  const auto found = cells_.find(std::string(column));
  return found == cells_.end() ? empty : found->second;
}

void check_row(const std::map<std::string, std::string>& row) {
  const std::string where = "row " + (row.count("scenario") ? row.at("scenario") : "?") + " " +
                            (row.count("engine") ? row.at("engine") : "?") + "/" +
                            (row.count("variant") ? row.at("variant") : "?");
  const auto bad = [&](const std::string& column, const std::string& why) {
    return RunError(where + ": column " + column + " " + why +
                    " (harness/results-schema.json; a defect of physbench, not of the scene)");
  };
  for (const auto& [key, value] : row)
    if (!schema_column(key)) throw bad(key, "is not in the schema");
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

// ---- the folder ---------------------------------------------------------------------------------

void ResultsFolder::refuse_used(const fs::path& out) {
  if (fs::exists(out) && (!fs::is_directory(out) || !fs::is_empty(out)))
    throw RunError("the results folder " + out.string() +
                   " already holds files (an earlier run?): physbench writes only into a new or "
                   "empty folder; choose another --out");
}

ResultsFolder::ResultsFolder(const fs::path& out, const Plan& plan, const RunOptions& options,
                             std::size_t jobs_in_shard)
    : out_(out), work_(out / ".work") {
  refuse_used(out_);
  fs::create_directories(out_ / "scenes");
  fs::create_directories(out_ / "trajectories");
  fs::create_directories(out_ / "poses");
  fs::create_directories(work_);
  csv_.open(out_ / "results.csv.partial");
  for (std::size_t i = 0; i < std::size(kResultColumns); ++i)
    csv_ << (i ? "," : "") << kResultColumns[i].name;
  csv_ << '\n';
  all_trajectories_ = options.all_trajectories;
  rounds_.open(out_ / "timing_rounds.csv.partial");
  rounds_ << "scenario,dt,engine,variant,iterations,substeps,round,order,repeats,"
             "seconds_per_step\n";

  json& metadata = metadata_;
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
      {"rounds", options.rounds},
      {"round_cap_s", options.round_cap_seconds},
      {"note",
       "a scene step's jobs are timed in rounds: the first runs each job once in plan order "
       "(the sampled run, then timed repeats on a fresh world, at least 3, until budget/rounds "
       "is spent); every later round runs each job once more in its own process, in a fresh "
       "shuffled order, with timed repeats (at least 1) until budget/rounds; a job whose run "
       "takes over round_cap_s is timed in the first round only. steps/s is the median over "
       "every repeat; timing_rounds.csv has each round's median"}};
  metadata["engines"] = json::object();
  metadata["scenarios"] = json::object();

  // the replay viewer's pose files (docs/viewer.md): each scene at its own step, within the caps
  metadata["poses"] = {
      {"format",
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

  // what trajectories/ keeps (docs/usage.md, "The results folder")
  metadata["trajectories"] = {
      {"rows", options.all_trajectories ? "every row"
                                        : "the rows at their scene's own step and own knobs"},
      {"bodies", options.all_trajectories
                     ? std::string("every probed body")
                     : "at most " + std::to_string(kTrajectoryBodies) + " probed bodies' states (" +
                           std::to_string(kContactTrajectoryBodies) +
                           " on a contact scene), spread evenly, the first and last among them"},
      {"per_sample_columns_from", "every probed body"}};

  metadata["plan"] = {{"fingerprint", plan.fingerprint},
                      {"jobs", plan.jobs.size()},
                      {"shard", {{"index", options.shard_index}, {"count", options.shard_count}}},
                      {"jobs_in_shard", jobs_in_shard},
                      {"row_jobs", json::array()}};  // each row's job number, in row order
}

fs::path ResultsFolder::write_scene(const std::string& stem, const Scene& scene) {
  const fs::path file = out_ / "scenes" / (stem + ".json");
  save_scene_file(scene, file.string());
  return file;
}

void ResultsFolder::describe_scenario(const PlannedScene& p) {
  metadata_["scenarios"][p.scene.name] = {{"description", p.scene.description},
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
}

void ResultsFolder::record_step(const PlannedScene& p, double dt, const fs::path& scene_file,
                                const ReferenceRun& reference) {
  json& scenario_meta = metadata_["scenarios"][p.scene.name];
  scenario_meta["reference_self_error"][number(dt)] = reference.self_error;
  if (!reference.failure.empty()) scenario_meta["reference_failure"][number(dt)] = reference.failure;
  scenario_meta["scene_file"][number(dt)] = fs::relative(scene_file, out_).string();
}

void ResultsFolder::write_poses(const EvaluatedJob& job, const std::string& stem) {
  json& poses_meta = metadata_["poses"];
  const Trajectory& run = job.trajectory;
  // a contact scene's file also holds its contacts, counted against the same caps
  std::optional<OverlapGauge> contacts;
  if (job.scene->has_contacts()) contacts.emplace(*job.scene, run.bodies);
  const OverlapGauge* gauge = contacts ? &*contacts : nullptr;
  PoseLayout layout = pose_layout(run, gauge);
  if (gauge && layout.frames > 0 && layout.contact_stride == 0)
    poses_meta["contacts_not_written"][stem] = "one frame's contacts exceed what the job cap leaves";
  // near the run's cap the poses go without their contacts rather than not at all
  if (layout.contact_stride > 0 && pose_bytes_ + layout.bytes > kPoseBytesPerRun) {
    layout = pose_layout(run);
    gauge = nullptr;
    poses_meta["contacts_not_written"][stem] = "the run's pose files neared their cap";
  }
  if (layout.frames == 0)
    poses_meta["not_written"][stem] = "no samples, or two frames exceed the job cap";
  else if (pose_bytes_ + layout.bytes > kPoseBytesPerRun)
    poses_meta["not_written"][stem] = "the run's pose files reached their cap";
  else {
    write_pose_file(out_ / "poses" / (stem + ".bin"), run, layout, gauge);
    pose_bytes_ += layout.bytes;
    poses_meta["files"] = poses_meta["files"].get<int>() + 1;
    poses_meta["bytes"] = pose_bytes_;
  }
}

void ResultsFolder::add(EvaluatedJob& job, const std::string& stem, bool own_step,
                        std::size_t job_number) {
  // an engine whose every row is unsupported has no entry (not a null one)
  if (job.status != Status::Unsupported && job.status != Status::Crashed &&
      job.status != Status::Timeout) {
    json& engine_meta = metadata_["engines"][job.row["engine"]];
    engine_meta["version"] = job.engine_version;
    json settings = json::array();
    for (const Setting& s : job.settings)
      settings.push_back({{"name", s.name}, {"value", s.value}, {"why", s.why}});
    // a swept knob's table beside the variant's own: engines.<engine>.sweeps.<variant>.<knob>
    if (job.knobs.any())
      engine_meta["sweeps"][job.row["variant"]][knob_tag(job.knobs)] = settings;
    else
      engine_meta["variants"][job.row["variant"]] = settings;
    // the stages the engine times, naming stage_ms's parts
    if (!job.stage_names.empty()) engine_meta["stages"] = job.stage_names;
  }

  // the trajectory of a row the report draws over time: at the scene's own step and the engine's
  // own knobs; a sweep's other rows keep their metrics only, unless --all-trajectories
  const bool drawn = own_step && !job.knobs.any();
  if (job.measured && (drawn || all_trajectories_)) {
    try {
      const fs::path trajectory = out_ / "trajectories" / (stem + ".csv");
      write_trajectory_csv(trajectory, *job.scene, job.trajectory, job.series, job.against(),
                           int(job.scene->bodies.size()), all_trajectories_);
      job.row.text("trajectory", fs::relative(trajectory, out_).string());
      // the replay viewer shows each engine variant at its own settings
      if (own_step && !job.knobs.any()) write_poses(job, stem);
    } catch (const RunError&) {
      throw;
    } catch (const std::exception& e) {
      const std::string message = job.row["message"];
      job.row.text("message", message + (message.empty() ? "" : "; ") +
                                  std::string("metrics failed: ") + e.what());
    }
  }

  check_row(job.row.cells());  // a row that does not fit the schema stops the run, named
  for (std::size_t i = 0; i < std::size(kResultColumns); ++i)
    csv_ << (i ? "," : "") << csv_field(job.row[kResultColumns[i].name]);
  csv_ << '\n';
  csv_.flush();  // an interrupted run keeps every finished row
  ++rows_written_;
  metadata_["plan"]["row_jobs"].push_back(job_number);
}

void ResultsFolder::add_round(const Round& r) {
  rounds_ << csv_field(r.scenario) << ',' << number(r.dt) << ',' << csv_field(r.engine) << ','
          << csv_field(r.variant) << ','
          << (r.knobs.iterations > 0 ? std::to_string(r.knobs.iterations) : "") << ','
          << (r.knobs.substeps > 0 ? std::to_string(r.knobs.substeps) : "") << ',' << r.round
          << ',' << r.order << ',' << r.repeats << ',' << number(r.seconds_per_step) << '\n';
  rounds_.flush();
}

void ResultsFolder::finish(const nlohmann::json& wall_time) {
  if (!wall_time.is_null()) metadata_["wall_time"] = wall_time;
  csv_.close();
  if (!csv_) throw RunError("cannot write " + (out_ / "results.csv").string());
  rounds_.close();
  if (!rounds_) throw RunError("cannot write " + (out_ / "timing_rounds.csv").string());
  fs::rename(out_ / "timing_rounds.csv.partial", out_ / "timing_rounds.csv");
  {
    std::ofstream meta(out_ / "metadata.json.partial");
    meta << metadata_.dump(2) << '\n';
  }
  fs::rename(out_ / "metadata.json.partial", out_ / "metadata.json");
  fs::rename(out_ / "results.csv.partial", out_ / "results.csv");
  fs::remove_all(work_);
}

void ResultsFolder::mark_interrupted(int signal, std::size_t done, std::size_t total) {
  // the rows done so far stay in results.csv.partial; results.csv never appears
  csv_.close();
  rounds_.close();
  metadata_["interrupted"] = {
      {"signal", signal}, {"rows_written", rows_written_}, {"jobs_total", total}};
  {
    std::ofstream meta(out_ / "metadata.json.partial");
    meta << metadata_.dump(2) << '\n';
  }
  {
    std::ofstream note(out_ / "INCOMPLETE");
    note << "This run was interrupted by signal " << signal << " (" << strsignal(signal)
         << ") during job " << done << " of " << total
         << "; that job's process group was killed.\n"
            "results.csv.partial holds the "
         << rows_written_
         << " rows written before it, metadata.json.partial the metadata. No results.csv was "
            "written.\n";
  }
  fs::remove_all(work_);
}

void ResultsFolder::mark_stopped(const std::string& why, std::size_t done, std::size_t total) {
  // a row that does not fit the schema: the rows before it stay, and the folder says why
  csv_.close();
  rounds_.close();
  std::ofstream(out_ / "INCOMPLETE") << "This run stopped at job " << done << " of " << total
                                     << ": " << why << "\nresults.csv.partial holds the "
                                     << rows_written_ << " rows written before it.\n";
  fs::remove_all(work_);
}

}  // namespace physbench
