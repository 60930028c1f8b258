// The runner: every selected scene on every selected engine and variant, each job in its own
// process; writes results.csv, trajectories/, scenes/ and metadata.json into one folder.
#pragma once

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "physbench/scene.h"
#include "physbench/simulate.h"

namespace physbench {

// an engine variant and the executable that hosts it
struct EngineVariant {
  std::string engine;
  std::string variant;
  std::string version;
  std::filesystem::path host;
  bool test_only = false;  // test-fault: not listed, and scheduled only when -e names it
  // an external worker's command line (workers/catalog.tsv, docs/worker-protocol.md), run in
  // place of `host worker`; empty for the engines linked into host
  std::vector<std::string> command{};
};

// one line of the worker catalog: an engine outside this executable, run by its command
struct CatalogEntry {
  std::string engine;
  std::vector<std::string> variants;
  std::vector<std::string> command;  // the first word resolved against the workers folder
  std::string missing;               // why it cannot run here (not built); empty when it can
};

// The catalog file: PHYSBENCH_WORKER_CATALOG when set (empty: no external workers), else the
// repository's workers/catalog.tsv. A command's first word without a '/' names a program in
// workers_dir (the build's cargo output), else a path as written.
std::filesystem::path worker_catalog_file();
// the source tree this build came from (its .venv and reports/ hold merge and compare)
std::filesystem::path source_directory();
std::filesystem::path default_workers_dir();
std::vector<CatalogEntry> read_worker_catalog(const std::filesystem::path& file,
                                              const std::filesystem::path& workers_dir);

// every engine variant this build can run; self is this executable's path
std::vector<EngineVariant> engine_catalog(const std::filesystem::path& self);

// One job in a child process through run_child, for an in-process engine (`host worker ...`)
// and an external worker (its command) alike: the same timeout, interrupt handling and crash
// classification. Throws RunInterrupted when this process got SIGINT or SIGTERM.
RunResult run_worker_job(const EngineVariant& ev, const std::filesystem::path& scene_file,
                         const std::filesystem::path& result_file,
                         const std::filesystem::path& log_file, int every_steps,
                         double timing_budget, double timeout_seconds,
                         const SolverKnobs& knobs = {}, bool timing_only = false,
                         double run_cap_seconds = 0.0);

// The converged reference of a scene without contacts (docs/metrics.md, "References"): SciPy's
// DOP853 on the rigid-body equations of motion (validation/reference/scipy_reference.py), a worker
// of its own run by the project's Python (.venv/bin/python, or PHYSBENCH_REFERENCE_PYTHON), at
// `variant` "dop853" (rtol 1e-12) or "dop853-1e-13"
EngineVariant scipy_reference(const std::string& variant);

struct RunOptions {
  std::vector<std::string>
      scenarios;  // names; empty: every built-in (unless scene files are given)
  std::vector<std::string> scene_files;
  std::vector<std::string> engines;    // empty: every engine
  std::vector<std::string> variants;   // empty: every variant
  std::optional<double> dt, duration;  // dt: one step for every scene, no sweep
  std::vector<double> sweep_dt;  // steps to sweep every scene over; empty: each scenario's own
  bool no_sweep = false;         // only each scene's own step
  std::filesystem::path out;
  double timeout_seconds = 300.0;
  double timing_budget = 0.2;  // s of measured stepping per job, over all its timing rounds
  // --rounds: a scene step's jobs are timed in this many rounds, each job once a round in a fresh
  // order (docs/metrics.md, "Interleaved timing"); the first round also samples the trajectory
  int rounds = 5;
  // --round-cap: a job whose one run takes longer (s) is timed in its first round only
  double round_cap_seconds = 3.0;
  // --run-cap: a job's sampled run stops after this much stepping (s) and is a timeout, its speed
  // from the steps it took (docs/metrics.md, "Status"); 0: none
  double run_cap_seconds = 30.0;
  // --all-trajectories: every row keeps a trajectory with every probed body's states; by default
  // only the rows the report draws over time (own step, own knobs), with at most 8 bodies' states
  // (4 on a contact scene)
  bool all_trajectories = false;
  // --shard K/N: the K-th of N disjoint slices of the planned jobs (K from 1), a stride over the
  // plan's scene steps (steps K−1, K−1+N, …, each with all its engine variants), so a scene's
  // engines are timed on one machine; `physbench merge` joins the N folders (docs/regression.md)
  int shard_index = 1, shard_count = 1;
  // --sweep-iterations, --sweep-substeps: every engine variant runs once more per value, with its
  // nearest native knob set (each knob on its own, the other at the variant's own);
  // docs/regression.md
  std::vector<int> sweep_iterations, sweep_substeps;
  std::string command_line;
};

// a results row against harness/results-schema.json: every key a column, every required column
// filled, every value of its column's type; RunError names the row and column otherwise
void check_row(const std::map<std::string, std::string>& row);

// "K/N" → {K, N}; RunError names the value and what is wrong with it
std::pair<int, int> parse_shard(const std::string& text);

// "4,8,16" → {4, 8, 16}: whole numbers from 1 to 1000, each once; RunError names the option and
// the value otherwise
std::vector<int> parse_counts(const std::string& option, const std::string& text);

struct RunError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// SIGINT or SIGTERM during a run: the running job's process group is killed, the results folder
// keeps results.csv.partial and metadata.json.partial beside an INCOMPLETE file saying so, and
// run_suite throws this
struct RunInterrupted : std::runtime_error {
  RunInterrupted(int signal, const std::string& what) : std::runtime_error(what), signal(signal) {}
  int signal;
};

// Checks every name and scene file before any job runs (RunError names the culprit), then runs.
// Refuses a results folder that already holds files, so an earlier run is never written into.
// Returns the number of jobs that ended in crash, timeout or error.
int run_suite(const RunOptions& options, const std::filesystem::path& self);

}  // namespace physbench
