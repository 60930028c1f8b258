// The runner: every selected scene on every selected engine and variant, each job in its own
// process; writes results.csv, trajectories/, scenes/ and metadata.json into one folder.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "physbench/scene.h"

namespace physbench {

// an engine variant and the executable that hosts it
struct EngineVariant {
  std::string engine;
  std::string variant;
  std::string version;
  std::filesystem::path host;
};

// every engine variant this build can run; self is this executable's path
std::vector<EngineVariant> engine_catalog(const std::filesystem::path& self);

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
  double timing_budget = 0.2;  // s of measured stepping per job
  std::string command_line;
};

struct RunError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Checks every name and scene file before any job runs (RunError names the culprit), then runs.
// Returns the number of jobs that ended in crash, timeout or error.
int run_suite(const RunOptions& options, const std::filesystem::path& self);

}  // namespace physbench
