// A second executable that hosts one engine build which cannot share a process with the main
// one (the two export the same symbols): physbench-bullet64 (Bullet's double-precision build)
// and physbench-mujoco4 (MuJoCo 4, beside Debian's 2.2.2). It only runs worker jobs for the
// main physbench executable; PHYSBENCH_HOST_ENGINE names the engine it hosts.
#include <CLI/CLI.hpp>
#include <string>

#include "physbench/worker_cli.h"

int main(int argc, char** argv) {
  CLI::App app{std::string("worker for ") + PHYSBENCH_HOST_ENGINE + ", run by physbench"};
  app.require_subcommand(1);
  physbench::WorkerJob job;
  physbench::add_worker_subcommand(app, job);
  CLI11_PARSE(app, argc, argv);
  return physbench::run_worker(job);
}
