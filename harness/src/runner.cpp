#include "physbench/runner.h"

// The runner as four stages: plan the jobs (plan.cpp), run each in its own process (here),
// evaluate it into a row (evaluate.cpp), and write the results folder (results_folder.cpp);
// run_suite at the end of this file drives them in order.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <fstream>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <map>
#include <optional>
#include <random>
#include <sstream>
#include <utility>

#include "physbench/evaluate.h"
#include "physbench/metrics.h"
#include "physbench/mujoco_buffers.h"
#include "physbench/plan.h"
#include "physbench/process.h"
#include "physbench/registry.h"
#include "physbench/results_folder.h"
#include "physbench/scene_json.h"
#include "physbench/worker.h"
#include "text.h"

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
#ifdef PHYSBENCH_HAVE_RTP_BASELINE
  // rtp's default variants, and soft-step-4 (Box2D v3's settings), at the baseline instruction set
  // live in their own executable beside this one (the same engine compiled without -march), after
  // rtp's own variants
  for (std::size_t i = catalog.size(); i-- > 0;)
    if (catalog[i].engine == "rtp") {
      const fs::path host = self.parent_path() / "physbench-rtp-baseline";
      const std::string version = catalog[i].version;
      catalog.insert(catalog.begin() + long(i) + 1,
                     {{"rtp", std::string("soft-step") + PHYSBENCH_RTP_ISA_SUFFIX, version, host},
                      {"rtp", std::string("soft-step-4") + PHYSBENCH_RTP_ISA_SUFFIX, version, host},
                      {"rtp", std::string("rk4") + PHYSBENCH_RTP_ISA_SUFFIX, version, host}});
      break;
    }
#endif
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

// ---- the second stage: one job in its own process ---------------------------------------------

RunResult run_worker_job(const EngineVariant& ev, const fs::path& scene_file,
                         const fs::path& result_file, const fs::path& log_file, int every_steps,
                         double timing_budget, double timeout, const SolverKnobs& knobs,
                         bool timing_only, double run_cap_seconds) {
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
  if (knobs.iterations > 0)
    for (const std::string& a : {std::string("--iterations"), std::to_string(knobs.iterations)})
      argv.push_back(a);
  if (knobs.substeps > 0)
    for (const std::string& a : {std::string("--substeps"), std::to_string(knobs.substeps)})
      argv.push_back(a);
  if (timing_only) argv.push_back("--timing-only");
  if (run_cap_seconds > 0.0)
    for (const std::string& a : {std::string("--run-cap"), number(run_cap_seconds)})
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

// the converged reference: rtp RK4 at dt/divisor, and again at dt/(2·divisor) to show it converged;
// its scene files go into the folder beside the scene's
ReferenceRun converged_reference(const Scene& scene, const std::string& tag, ResultsFolder& folder,
                                 double timeout) {
  // SciPy's DOP853 at rtol 1e-12, and at 1e-13 to show the first converged (the change bounds
  // its error): an integrator no compared engine uses (rtp's RK4 is a row like any other)
  ReferenceRun reference;
  std::vector<Trajectory> runs;
  const fs::path file = folder.write_scene(tag + ".reference", scene);
  for (const char* variant : {"dop853", "dop853-1e-13"}) {
    const EngineVariant scipy = scipy_reference(variant);
    std::cerr << "  reference for " << tag << ": SciPy " << variant << "\n";
    const RunResult r = run_worker_job(scipy, file, folder.work() / "reference.json",
                                       folder.work() / "reference.log", scene.probe_every_steps(),
                                       0.0, timeout);
    if (r.status != Status::Ok) {
      reference.failed_status = to_string(r.status);
      reference.failure = std::string("reference run (SciPy ") + variant + ") " +
                          to_string(r.status) + ": " + r.message;
      std::cerr << "  reference for " << tag << " failed: " << reference.failure << "\n";
      return reference;
    }
    runs.push_back(r.trajectory);
  }
  reference.available = true;
  reference.trajectory = runs[0];
  // converged when a tenth of the tolerance changes the answer by this little
  Scene check = scene;
  check.probe.metrics = {Metric::Position, Metric::Orientation};
  const ErrorSummary self_check = summarise(compare(check, runs[0], &runs[1]));
  reference.self_error = std::max(self_check.position->max, self_check.orientation->max);
  return reference;
}

// What a converged reference depends on: the scene but its step, and the times the step samples it
// and applies its impulses at (the SciPy integrator never takes the engines' step). A swept scene's
// steps that sample at the same times share one reference, computed once (it was most of a
// free-motion sweep's time: two SciPy runs a step)
std::string reference_key(const Scene& scene) {
  json doc = to_json(scene);
  doc.erase("dt");
  std::string key = doc.dump();
  char text[32];
  const auto time = [&](double t) {
    std::snprintf(text, sizeof text, " %.12g", t);
    key += text;
  };
  const long steps = scene.step_count(), every = scene.probe_every_steps();
  key += "\nsamples";
  for (long k = 0; k < steps; k += every) time(static_cast<double>(k) * scene.dt);
  time(static_cast<double>(steps) * scene.dt);
  key += "\nimpulses";
  for (const ImpulseSpec& p : scene.impulses) time(std::round(p.time / scene.dt) * scene.dt);
  return key;
}

// a finished row in one line of progress
// a job of the scene step being run: run once (its first timing round, with the trajectory),
// waiting for the step's other timing rounds before it is evaluated and written
struct RanJob {
  PlannedJob planned;
  std::string stem;
  RunResult result;
  int rounds = 1;  // the timing rounds its time comes from
};

// Where a run's wall time goes (metadata.json's wall_time, docs/metrics.md, "Where a run's time
// goes"): the jobs' processes in their first round and in the later timing rounds, with the timed
// stepping inside them, the references, and the evaluation and files; by scenario, and the
// processes by engine
class WallTime {
 public:
  using Clock = std::chrono::steady_clock;
  enum Phase { kFirstRuns, kTimingRounds, kReferences, kEvaluation, kPhases };

  // f() timed, its seconds added to the phase, the scenario and the engine (a job's process)
  template <typename F>
  decltype(auto) time(Phase phase, const std::string& scenario, F&& f,
                      const std::string& engine = "") {
    struct Add {
      WallTime& to;
      Phase phase;
      const std::string& scenario;
      const std::string& engine;
      Clock::time_point start = Clock::now();
      ~Add() {
        const double s = std::chrono::duration<double>(Clock::now() - start).count();
        to.phase_[phase] += s;
        to.scenario_[scenario] += s;
        if (!engine.empty()) to.engine_[engine].first += s;
      }
    } add{*this, phase, scenario, engine};
    return f();
  }
  // the timed stepping a job's process reported (its repeats, or its one run)
  void stepped(const RunResult& r, const std::string& engine) {
    for (double s : r.wall_seconds) stepping_ += s, engine_[engine].second += s;
  }

  json summary() const {
    const double total = std::chrono::duration<double>(Clock::now() - start_).count();
    double phases = 0.0;
    for (double s : phase_) phases += s;
    json by_scenario = json::object();
    const auto ms = [](double s) { return std::round(s * 1000) / 1000; };
    for (const auto& [name, s] : scenario_) by_scenario[name] = ms(s);
    json by_engine = json::object();
    for (const auto& [name, s] : engine_)
      by_engine[name] = {{"processes_s", ms(s.first)}, {"timed_stepping_s", ms(s.second)}};
    return {{"total_s", ms(total)},
            {"first_runs_s", ms(phase_[kFirstRuns])},
            {"timing_rounds_s", ms(phase_[kTimingRounds])},
            {"timed_stepping_s", ms(stepping_)},
            {"references_s", ms(phase_[kReferences])},
            {"evaluation_and_files_s", ms(phase_[kEvaluation])},
            {"other_s", ms(total - phases)},
            {"by_scenario_s", by_scenario},
            {"by_engine", by_engine},
            {"note",
             "first_runs_s and timing_rounds_s are the jobs' processes' wall time (start, world "
             "builds, the sampled run, the timed repeats, the result's file); timed_stepping_s "
             "is the stepping inside them that speeds are measured from; evaluation_and_files_s "
             "the metrics, trajectories, poses and rows; other_s planning and scene files; "
             "by_engine the jobs' processes and their timed stepping per engine"}};
  }
  // a summary in one line, for the log
  static std::string line(const json& s) {
    std::ostringstream out;
    out << "wall time " << s["total_s"] << " s: the jobs' first runs " << s["first_runs_s"]
        << " s, timing rounds " << s["timing_rounds_s"] << " s (timed stepping in both "
        << s["timed_stepping_s"] << " s), references " << s["references_s"]
        << " s, evaluation and files " << s["evaluation_and_files_s"] << " s, other "
        << s["other_s"] << " s";
    return out.str();
  }

 private:
  Clock::time_point start_ = Clock::now();
  double phase_[kPhases] = {};
  double stepping_ = 0.0;
  std::map<std::string, double> scenario_;
  std::map<std::string, std::pair<double, double>> engine_;  // processes, timed stepping
};


// The scene step's timing rounds 2…R (docs/metrics.md, "Interleaved timing"): every job that ran
// ok takes one more timed run a round, in its own process, in an order shuffled afresh each round
// (seeded by the step and the round: a run's order is reproducible), so a slow spell of the
// machine falls on every engine of the step alike. A round that fails is that job's failure.
void run_timing_rounds(std::vector<RanJob>& ran, const Plan& plan, const SceneStep& step,
                       const PlannedScene& scene, const fs::path& scene_file,
                       const RunOptions& options, ResultsFolder& folder, WallTime& wall) {
  std::vector<std::size_t> timed;
  for (std::size_t i = 0; i < ran.size(); ++i) {
    const RunResult& r = ran[i].result;
    if (r.status == Status::Ok && !r.wall_seconds.empty() &&
        median(r.wall_seconds) <= options.round_cap_seconds)
      timed.push_back(i);
    else if (r.status == Status::Ok && !r.wall_seconds.empty() && options.rounds > 1)
      append(ran[i].result.message, "timed in one round only (a run takes over " +
                                      number(options.round_cap_seconds) + " s: --round-cap)");
  }
  const auto record = [&](const RanJob& job, int round, int order, const RunResult& r) {
    const EngineVariant& ev = plan.engines[job.planned.engine];
    ResultsFolder::Round row{scene.scene.name, ev.engine, ev.variant, step.dt, job.planned.knobs, round,
                             order, static_cast<int>(r.wall_seconds.size()),
                             median(r.wall_seconds) / static_cast<double>(r.steps)};
    folder.add_round(row);
  };
  for (std::size_t i = 0; i < ran.size(); ++i)
    if (!ran[i].result.wall_seconds.empty() && ran[i].result.status == Status::Ok)
      record(ran[i], 1, static_cast<int>(i + 1), ran[i].result);
  if (timed.empty() || options.rounds < 2) return;
  const double budget = options.timing_budget / options.rounds;
  std::cerr << "  timing rounds 2-" << options.rounds << " of " << timed.size() << " job"
            << (timed.size() == 1 ? "" : "s") << " ..." << std::flush;
  for (int round = 2; round <= options.rounds; ++round) {
    std::mt19937_64 shuffle(step.number * 1000003ULL + static_cast<unsigned>(round));
    std::vector<std::size_t> order = timed;
    std::shuffle(order.begin(), order.end(), shuffle);
    for (std::size_t k = 0; k < order.size(); ++k) {
      RanJob& job = ran[order[k]];
      if (job.result.status != Status::Ok) continue;  // an earlier round failed
      const EngineVariant& ev = plan.engines[job.planned.engine];
      const std::string stem = job.stem + ".round-" + std::to_string(round);
      RunResult r = wall.time(WallTime::kTimingRounds, scene.scene.name, [&] {
        return run_worker_job(ev, scene_file, folder.work() / (stem + ".json"),
                              folder.work() / (stem + ".log"), 0, budget, options.timeout_seconds,
                              job.planned.knobs, true);
      }, ev.engine);
      wall.stepped(r, ev.engine);
      if (r.status != Status::Ok || r.wall_seconds.empty()) {
        job.result.status = r.status == Status::Ok ? Status::Error : r.status;
        append(job.result.message, "timing round " + std::to_string(round) + ": " +
                                     to_string(r.status) + (r.message.empty() ? "" : ", ") +
                                     r.message);
        continue;
      }
      record(job, round, static_cast<int>(k + 1), r);
      ++job.rounds;
      job.result.wall_seconds.insert(job.result.wall_seconds.end(), r.wall_seconds.begin(),
                                     r.wall_seconds.end());
      StageTimes& stages = job.result.stages;
      if (stages.names == r.stages.names && stages.seconds.size() == r.stages.seconds.size()) {
        for (std::size_t s = 0; s < stages.seconds.size(); ++s)
          stages.seconds[s] += r.stages.seconds[s];
        stages.steps += r.stages.steps;
      }
    }
  }
  std::cerr << " done\n";
}

void print_outcome(const ResultRow& row, Status status) {
  std::cerr << row["status"];
  if (!row["steps_per_s"].empty()) std::cerr << "  " << row["steps_per_s"] << " steps/s";
  if (!row["position_err_max"].empty())
    std::cerr << "  pos err max " << row["position_err_max"] << " m";
  if (!row["orientation_err_max"].empty())
    std::cerr << "  orient err max " << row["orientation_err_max"] << " rad";
  if (!row["energy_drift_max"].empty()) std::cerr << "  energy drift " << row["energy_drift_max"];
  if (!row["contact_verdict"].empty()) std::cerr << "  " << row["contact_verdict"];
  if (!row["stack_drift_max"].empty()) std::cerr << "  drift " << row["stack_drift_max"] << " m";
  if (!row["penetration_max"].empty())
    std::cerr << "  penetration max " << row["penetration_max"] << " m";
  if (status != Status::Ok || !row["message"].empty()) std::cerr << "  (" << row["message"] << ")";
  std::cerr << '\n';
}

}  // namespace

fs::path source_directory() { return PHYSBENCH_SOURCE_DIR; }

EngineVariant scipy_reference(const std::string& variant) {
  const char* python = std::getenv("PHYSBENCH_REFERENCE_PYTHON");
  const fs::path interpreter =
      python && *python ? fs::path(python) : source_directory() / ".venv" / "bin" / "python";
  EngineVariant ev{"scipy", variant, "SciPy DOP853", {}};
  ev.command = {interpreter.string(),
                (source_directory() / "validation" / "reference" / "scipy_reference.py").string()};
  return ev;
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

std::vector<int> parse_counts(const std::string& option, const std::string& text) {
  const auto bad = [&](const std::string& why) {
    return RunError(option + " " + text + ": " + why +
                    " (write whole numbers from 1 to 1000 separated by commas, e.g. " + option +
                    " 4,8,16)");
  };
  std::vector<int> counts;
  std::stringstream parts(text);
  std::string part;
  if (text.empty()) throw bad("no value");
  while (std::getline(parts, part, ',')) {
    if (part.empty() || part.size() > 4 ||
        !std::all_of(part.begin(), part.end(), [](char c) { return c >= '0' && c <= '9'; }))
      throw bad("'" + part + "' is not a whole number");
    const int n = std::stoi(part);
    if (n < 1 || n > 1000) throw bad("'" + part + "' is not between 1 and 1000");
    if (std::find(counts.begin(), counts.end(), n) != counts.end())
      throw bad("'" + part + "' is given twice");
    counts.push_back(n);
  }
  if (text.back() == ',') throw bad("a value is missing after the last comma");
  return counts;
}

int run_suite(const RunOptions& options, const fs::path& self) {
  if (options.shard_count < 1 || options.shard_index < 1 ||
      options.shard_index > options.shard_count)
    throw RunError("shard " + std::to_string(options.shard_index) + "/" +
                   std::to_string(options.shard_count) + " is not a slice of the plan");
  // ---- plan: every name and scene checked before anything runs
  const Plan plan = plan_run(options, engine_catalog(self));
  const std::vector<PlannedJob> jobs = plan.shard(options.shard_index, options.shard_count);
  ResultsFolder::refuse_used(options.out);
  // from here on SIGINT and SIGTERM stop the running job and leave the folder marked incomplete
  install_interrupt_handlers();
  ResultsFolder folder(options.out, plan, options, jobs.size());

  int failures = 0;
  std::size_t done = 0;
  WallTime wall;
  // the scene step being run: its scene, scene file and reference, made at its first job
  const SceneStep* step = nullptr;
  Scene scene;
  fs::path scene_file;
  ReferenceRun reference;
  std::optional<std::pair<std::size_t, std::size_t>> not_applicable;  // (step, engine)
  std::map<std::string, std::pair<std::string, ReferenceRun>> references;  // by reference_key: tag, run
  // the step's jobs, run once; timed in rounds, evaluated and written when the step ends
  std::vector<RanJob> ran;
  const auto finish_step = [&] {
    if (!step) return;
    const PlannedScene& p = plan.scenes[step->scene];
    run_timing_rounds(ran, plan, *step, p, scene_file, options, folder, wall);
    for (RanJob& r : ran) {
      const EngineVariant& ev = plan.engines[r.planned.engine];
      EvaluatedJob job = wall.time(WallTime::kEvaluation, p.scene.name, [&] {
        return evaluate_job(p, scene, ev, r.planned.knobs, std::move(r.result), reference);
      });
      if (job.status == Status::Crashed || job.status == Status::Timeout ||
          job.status == Status::Error)
        ++failures;
      if (!job.row["steps_per_s"].empty()) job.row.integer("timing_rounds", r.rounds);
      wall.time(WallTime::kEvaluation, p.scene.name,
                [&] { folder.add(job, r.stem, step->own_step, r.planned.number); });
      std::cerr << "  " << ev.engine << "/" << ev.variant
                << (r.planned.knobs.any() ? " " + knob_tag(r.planned.knobs) : "") << ": ";
      print_outcome(job.row, job.status);
    }
    ran.clear();
  };
  try {
    for (const PlannedJob& planned : jobs) {
      const PlannedScene& p = plan.scenes[plan.steps[planned.step].scene];
      if (!step || step->number != planned.step) {
        finish_step();
        if (!step || step->scene != plan.steps[planned.step].scene) folder.describe_scenario(p);
        step = &plan.steps[planned.step];
        scene = plan.scene_at(*step);
        scene_file = folder.write_scene(step->tag, scene);
        reference = ReferenceRun{};
        if (scene.reference.kind == ReferenceKind::Converged) {
          const std::string key = reference_key(scene);
          if (const auto same = references.find(key); same != references.end()) {
            reference = same->second.second;
            std::cerr << "  reference for " << step->tag << ": " << same->second.first
                      << "'s (the same sample and impulse times)\n";
          } else {
            reference = wall.time(WallTime::kReferences, p.scene.name, [&] {
              return converged_reference(scene, step->tag, folder, options.timeout_seconds);
            });
            references.emplace(key, std::pair(step->tag, reference));
          }
        }
        folder.record_step(p, step->dt, scene_file, reference);
      }

      // ---- run
      const EngineVariant& ev = plan.engines[planned.engine];
      ++done;
      // a swept knob's jobs: "tower-10__rtp__soft-step.substeps-2"
      const std::string knobs = knob_tag(planned.knobs);
      const std::string stem = step->tag + "__" + safe_name(ev.engine + "__" + ev.variant) +
                               (knobs.empty() ? "" : "." + knobs);
      std::cerr << "[" << done << "/" << jobs.size() << "] " << step->tag << "  " << ev.engine
                << "/" << ev.variant << (knobs.empty() ? "" : " " + knobs) << " ... "
                << std::flush;
      // a variant that does not apply to the scene applies at no knob setting: its own job, just
      // before, said so (an external worker says it only when run)
      if (planned.knobs.any() && not_applicable == std::pair(planned.step, planned.engine)) {
        std::cerr << "not applicable here\n";
        continue;
      }
      // the first timing round: the sampled run and its share of the timing budget
      RunResult result = wall.time(WallTime::kFirstRuns, p.scene.name, [&] {
        return run_worker_job(ev, scene_file, folder.work() / (stem + ".json"),
                              folder.work() / (stem + ".log"), scene.probe_every_steps(),
                              options.timing_budget / std::max(1, options.rounds),
                              options.timeout_seconds, planned.knobs, false,
                              options.run_cap_seconds);
      }, ev.engine);
      wall.stepped(result, ev.engine);
      if (result.status == Status::NotApplicable) {
        not_applicable = {planned.step, planned.engine};
        std::cerr << "not applicable here\n";
        continue;
      }
      std::cerr << to_string(result.status) << '\n';
      ran.push_back({planned, stem, std::move(result)});
    }
    // ---- the last step's timing rounds; evaluate, write
    finish_step();
  } catch (const RunInterrupted& e) {
    folder.mark_interrupted(e.signal, done, jobs.size());
    throw;
  } catch (const RunError& e) {
    folder.mark_stopped(e.what(), done, jobs.size());
    throw;
  }
  const json wall_time = wall.summary();
  folder.finish(wall_time);
  std::cerr << WallTime::line(wall_time) << '\n';
  return failures;
}

}  // namespace physbench
