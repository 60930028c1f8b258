// The worker subcommand's options, shared by physbench and physbench-bullet64.
#pragma once

#include <CLI/CLI.hpp>

#include "physbench/worker.h"

namespace physbench {

inline CLI::App* add_worker_subcommand(CLI::App& app, WorkerJob& job) {
  auto* worker = app.add_subcommand("worker", "(internal) run one job and write its result");
  worker->add_option("--scene", job.scene_path, "scene file")->required();
  worker->add_option("--engine", job.engine)->required();
  worker->add_option("--variant", job.variant)->required();
  worker->add_option("--every", job.every_steps, "steps between samples");
  worker->add_option("--budget", job.timing_budget, "seconds of timed stepping");
  worker->add_option("--out", job.out_path, "result file (JSON)")->required();
  // a sweep's solver knobs (docs/regression.md): given only when set
  worker->add_option("--iterations", job.knobs.iterations, "solver iterations (0: the variant's)");
  worker->add_option("--substeps", job.knobs.substeps, "substeps per step (0: the variant's)");
  worker->add_option("--run-cap", job.run_cap_seconds,
                     "seconds of stepping after which the sampled run stops, a timeout (0: none)");
  worker->add_flag("--timing-only", job.timing_only,
                   "a timing round: no sampled run, timed repeats only (at least one)");
  return worker;
}

}  // namespace physbench
