// The worker: one (scene, engine, variant) job in its own process, result as JSON.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "physbench/simulate.h"

namespace physbench {

nlohmann::json result_to_json(const RunResult& result);
RunResult result_from_json(const nlohmann::json& document);

struct WorkerJob {
  std::string scene_path;
  std::string engine;
  std::string variant;
  int every_steps = 0;
  double timing_budget = 0.3;
  std::string out_path;
  SolverKnobs knobs;  // a sweep's iterations or substeps; none: the variant's own
  bool timing_only = false;  // a timing round: timed repeats only, no trajectory
  double run_cap_seconds = 0.0;  // the sampled run stops after this much stepping (0: none)
};

// Runs the job with the engines linked into this executable and writes out_path.
// Returns the process exit code: 0 whenever a result (of any status) was written.
int run_worker(const WorkerJob& job);

}  // namespace physbench
