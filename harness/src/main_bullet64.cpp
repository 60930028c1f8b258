// physbench-bullet64: hosts the double-precision Bullet adapter, which cannot share a process
// with the single-precision one. It only runs worker jobs for the main physbench executable.
#include <CLI/CLI.hpp>

#include "physbench/worker.h"

int main(int argc, char** argv) {
  CLI::App app{"physbench-bullet64: worker for Bullet's double-precision build (run by physbench)"};
  app.require_subcommand(1);
  physbench::WorkerJob job;
  auto* worker = app.add_subcommand("worker", "run one job and write its result");
  worker->add_option("--scene", job.scene_path)->required();
  worker->add_option("--engine", job.engine)->required();
  worker->add_option("--variant", job.variant)->required();
  worker->add_option("--every", job.every_steps);
  worker->add_option("--budget", job.timing_budget);
  worker->add_option("--out", job.out_path)->required();
  CLI11_PARSE(app, argc, argv);
  return physbench::run_worker(job);
}
