// physbench-bullet64: hosts the double-precision Bullet adapter, which cannot share a process
// with the single-precision one. It only runs worker jobs for the main physbench executable.
#include <CLI/CLI.hpp>

#include "physbench/worker_cli.h"

int main(int argc, char** argv) {
  CLI::App app{"physbench-bullet64: worker for Bullet's double-precision build (run by physbench)"};
  app.require_subcommand(1);
  physbench::WorkerJob job;
  physbench::add_worker_subcommand(app, job);
  CLI11_PARSE(app, argc, argv);
  return physbench::run_worker(job);
}
