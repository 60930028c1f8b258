// physbench: run identical scenes on rtp and the peer engines; report speed against error.
#include <CLI/CLI.hpp>
#include <chrono>
#include <csignal>
#include <ctime>
#include <filesystem>
#include <cerrno>
#include <cstring>
#include <iostream>
#include <tuple>
#include <unistd.h>

#include "physbench/metrics.h"
#include "physbench/registry.h"
#include "physbench/runner.h"
#include "physbench/scenarios.h"
#include "physbench/scene_json.h"
#include "physbench/worker_cli.h"

namespace fs = std::filesystem;
using namespace physbench;

namespace {

fs::path self_path(const char* argv0) {
  std::error_code ec;
  fs::path self = fs::read_symlink("/proc/self/exe", ec);
  return ec ? fs::absolute(argv0) : self;
}

std::string default_out_dir() {
  const std::time_t now = std::time(nullptr);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "%Y%m%d-%H%M%S", std::localtime(&now));
  return std::string("results/") + stamp;
}

void print_list(const fs::path& self) {
  std::cout << "scenarios:\n";
  for (const Scenario& s : scenarios()) {
    const Scene scene = s.build();
    std::cout << "  " << s.name << (scene.planar ? "  [planar]" : "") << "\n      " << s.question
              << "\n";
  }
  std::cout << "engines (variants; the first is the default):\n";
  std::string current;
  for (const EngineVariant& ev : engine_catalog(self)) {
    if (ev.test_only) continue;  // test-fault is for the harness's own tests
    if (ev.engine != current) {
      current = ev.engine;
      std::cout << "\n  " << ev.engine << "  " << ev.version << "\n     ";
    }
    std::cout << " " << ev.variant;
  }
  std::cout << "\n";
#ifdef PHYSBENCH_MUJOCO4_MISSING
  std::cout << "\n  MuJoCo 4  (not built: no mujoco-core wheel in the project's .venv when CMake "
               "configured; scripts/setup.sh installs it, then reconfigure; Debian's 2.2.2 is the "
               "mujoco row)";
#endif
  const fs::path file = worker_catalog_file();
  for (const CatalogEntry& entry : read_worker_catalog(file, default_workers_dir()))
    if (!entry.missing.empty())
      std::cout << "\n  " << entry.engine << "  (in " << file.string() << ", not runnable: "
                << entry.missing << ")";
  std::cout << "\n";
}

// runs reports/<tool> with the project's Python (.venv), passing the arguments on; returns its
// exit code. The tools read results folders with the report builder's own readers
int run_python_tool(const std::string& tool, const std::vector<std::string>& args) {
  const fs::path source = source_directory();
  const fs::path python = source / ".venv" / "bin" / "python";
  const fs::path script = source / "reports" / tool;
  if (!fs::exists(python)) {
    std::cerr << "physbench: " << python.string()
              << " is missing: run scripts/setup.sh (it makes the project's Python environment)\n";
    return 2;
  }
  std::vector<std::string> words = {python.string(), script.string()};
  words.insert(words.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& w : words) argv.push_back(w.data());
  argv.push_back(nullptr);
  execv(argv[0], argv.data());
  std::cerr << "physbench: cannot run " << python.string() << ": " << std::strerror(errno) << '\n';
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "physbench: identical scenes on rtp, Bullet, ODE, Box2D and MuJoCo; speed against error"};
  app.require_subcommand(1);

  auto* list = app.add_subcommand("list", "list scenarios, engines and variants");

  RunOptions options;
  std::string out;
  std::string scenarios_csv, engines_csv, variants_csv;
  double dt = 0.0, duration = 0.0;
  auto* run = app.add_subcommand(
      "run", "run scenes on engines; write results.csv, trajectories and metadata");
  run->add_option("-s,--scenario", options.scenarios, "built-in scenario(s) to run (default: all)")
      ->delimiter(',');
  run->add_option("--scene", options.scene_files,
                  "scene file(s) in JSON (see docs/scene-format.md)")
      ->check(CLI::ExistingFile);
  run->add_option("-e,--engine", options.engines, "engine(s) to run (default: all)")
      ->delimiter(',');
  run->add_option("--variant", options.variants, "variant(s) to run (default: all)")
      ->delimiter(',');
  run->add_option("--dt", dt, "override every scene's fixed time step (s)")
      ->check(CLI::PositiveNumber);
  run->add_option("--duration", duration, "override every scene's simulated time (s)")
      ->check(CLI::PositiveNumber);
  std::vector<double> sweep_hz;
  run->add_option("--sweep-hz", sweep_hz,
                  "sweep every scene over these step rates (Hz), e.g. 30,60,120 (default: each "
                  "scenario's own sweep)")
      ->delimiter(',')
      ->check(CLI::PositiveNumber);
  run->add_flag("--no-sweep", options.no_sweep, "run each scene at its own step only");
  run->add_option("-o,--out", out, "results folder (default: results/<timestamp>)");
  run->add_option("--timeout", options.timeout_seconds,
                  "seconds before a job is killed and recorded as timeout")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  run->add_option("--budget", options.timing_budget,
                  "seconds of measured stepping per job (repeats)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  run->add_option("--rounds", options.rounds,
                  "timing rounds per scene step: each job timed once a round, in a fresh order "
                  "each round, so a slow spell falls on every engine alike (1: no interleaving)")
      ->capture_default_str()
      ->check(CLI::Range(1, 50));
  run->add_option("--round-cap", options.round_cap_seconds,
                  "a job whose one run takes longer (s) is timed in its first round only (the "
                  "rounds would multiply the suite's slowest jobs)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  run->add_option("--run-cap", options.run_cap_seconds,
                  "seconds of stepping after which a job's run stops: a timeout row, its speed "
                  "from the steps it took (0: no cap; --timeout still kills a hung job)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  run->add_flag("--all-trajectories", options.all_trajectories,
                "keep a trajectory for every row (a sweep's too), with every probed body's states "
                "(default: the rows at each scene's own step and knobs, at most 8 bodies' states, "
                "4 on a contact scene; the error and energy columns always come from every probed "
                "body)");
  std::string sweep_iterations, sweep_substeps;
  run->add_option("--sweep-iterations", sweep_iterations,
                  "run every engine variant once more per value, with its solver's iterations "
                  "(its nearest native knob) set to it, e.g. 4,8,16");
  run->add_option("--sweep-substeps", sweep_substeps,
                  "run every engine variant once more per value, with its substeps per step set "
                  "to it, e.g. 1,2,4 (engines without substeps: an unsupported row saying so)");
  std::string shard;
  run->add_option("--shard", shard,
                  "run the K-th of N disjoint slices of the planned jobs, K/N with K from 1 "
                  "(join the N folders with `physbench merge`)");

  // merge and compare read results folders; they are the report builder's Python (reports/),
  // run with the project's .venv
  auto* merge = app.add_subcommand(
      "merge", "join the results folders of a sharded run (--shard K/N) into one: "
               "merge -o OUT SHARD_DIR... (merge --help for its options)");
  merge->prefix_command();
  merge->set_help_flag();  // --help goes on to the tool, which knows its options
  auto* compare = app.add_subcommand(
      "compare", "compare two results folders, OLD then NEW: faster, slower, more or less "
                 "accurate; exit 1 on a regression (compare --help for its options)");
  compare->prefix_command();
  compare->set_help_flag();

  auto* check = app.add_subcommand("check", "validate scene files and print what is wrong");
  std::vector<std::string> check_files;
  check->add_option("files", check_files, "scene files")->required();

  // every scene a default run writes, without running it (the scene loader's fuzz seeds)
  auto* export_scenes = app.add_subcommand(
      "export-scenes", "write every built-in scene, at each swept step, as JSON (a converged reference reads the scene itself)");
  std::string export_dir;
  export_scenes->add_option("dir", export_dir, "folder to write into")->required();
  export_scenes->group("");  // hidden from --help

  WorkerJob job;
  auto* worker = add_worker_subcommand(app, job);
  worker->group("");  // hidden from --help

  CLI11_PARSE(app, argc, argv);
  const fs::path self = self_path(argv[0]);

  if (*list) {
    print_list(self);
    return 0;
  }
  if (*worker) return run_worker(job);
  if (*merge) return run_python_tool("merge.py", merge->remaining());
  if (*compare) return run_python_tool("compare.py", compare->remaining());
  if (*export_scenes) try {
    fs::create_directories(export_dir);
    int written = 0;
    for (const Scenario& s : scenarios()) {
      std::vector<double> dts = s.sweep_dt;
      const Scene base = s.build();
      dts.insert(dts.begin(), base.dt);
      for (std::size_t i = 0; i < dts.size(); ++i) {
        Scene scene = base;
        scene.dt = dts[i];
        const std::string stem = (fs::path(export_dir) / (scene.name + "." + std::to_string(i))).string();
        save_scene_file(scene, stem + ".json");
        load_scene_file(stem + ".json");  // what a run writes, its workers must read
        ++written;
      }
    }
    std::cout << written << " scenes in " << export_dir << "\n";
    return 0;
  } catch (const SceneError& e) {
    std::cerr << "physbench: a built-in scene fails its own checks: " << e.what() << '\n';
    return 1;
  }
  if (*check) {
    int bad = 0;
    for (const std::string& f : check_files) {
      try {
        const Scene scene = load_scene_file(f);
        std::cout << f << ": ok (" << scene.name << ", " << scene.bodies.size() << " bodies)\n";
      } catch (const SceneError& e) {
        std::cerr << e.what() << '\n';
        ++bad;
      }
    }
    return bad ? 1 : 0;
  }

  if (!shard.empty()) try {
    std::tie(options.shard_index, options.shard_count) = parse_shard(shard);
  } catch (const RunError& e) {
    std::cerr << "physbench: " << e.what() << '\n';
    return 2;
  }
  try {
    if (!sweep_iterations.empty())
      options.sweep_iterations = parse_counts("--sweep-iterations", sweep_iterations);
    if (!sweep_substeps.empty())
      options.sweep_substeps = parse_counts("--sweep-substeps", sweep_substeps);
  } catch (const RunError& e) {
    std::cerr << "physbench: " << e.what() << '\n';
    return 2;
  }
  if (dt > 0.0) options.dt = dt;
  for (double hz : sweep_hz) options.sweep_dt.push_back(1.0 / hz);
  if (duration > 0.0) options.duration = duration;
  if (out.empty()) {
    // two runs started in the same second get two folders
    out = default_out_dir();
    for (int n = 2; fs::exists(out); ++n) out = default_out_dir() + "-" + std::to_string(n);
  }
  options.out = out;
  for (int i = 0; i < argc; ++i) options.command_line += (i ? " " : "") + std::string(argv[i]);
  try {
    const int failures = run_suite(options, self);
    std::cout << "results: " << fs::absolute(options.out).string() << "/results.csv\n";
    if (failures)
      std::cerr << failures << " job(s) crashed, timed out or failed: see the status column\n";
    return 0;
  } catch (const RunInterrupted& e) {
    std::cerr << "physbench: interrupted (" << e.what() << "); " << options.out.string()
              << " is marked INCOMPLETE\n";
    // end as the signal would have ended us, so a calling shell or script sees it
    std::signal(e.signal, SIG_DFL);
    std::raise(e.signal);
    return 128 + e.signal;
  } catch (const RunError& e) {
    std::cerr << "physbench: " << e.what() << '\n';
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "physbench: " << e.what() << '\n';
    return 1;
  }
}
