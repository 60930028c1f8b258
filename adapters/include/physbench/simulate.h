// Drive one engine through one scene: step, sample the probed bodies, detect explosions,
// time the steps. Tests call it in-process; the harness calls it in an isolated worker.
#pragma once

#include <string>
#include <vector>

#include "physbench/engine.h"

namespace physbench {

// NotApplicable: the variant would not differ from another on this scene; the run makes no row
// Diverged: the run finished with finite state, but its energy grew by more than 100 % of the energy
// in play (docs/metrics.md, "Status"): a result, but not one to read as success
enum class Status { Ok, Unsupported, Exploded, Crashed, Timeout, Error, NotApplicable, Diverged };
const char* to_string(Status status);
Status status_from_string(const std::string& name);

struct Sample {
  double time = 0.0;              // s
  std::vector<SampledState> bodies;  // in Trajectory::bodies order
};

struct Trajectory {
  std::vector<int> bodies;  // scene indices of the probed bodies
  std::vector<Sample> samples;
};

struct SimulateOptions {
  int every_steps = 0;         // steps between samples; 0: the scene's probe interval
  double timing_budget = 0.3;  // s: timed repeats go on until this much stepping is measured
  int min_timed_repeats = 3;
  // a timing round (the harness's interleaved rounds, docs/metrics.md): no sampled run, no
  // trajectory; timed repeats from the first, at least one, until the budget
  bool timing_only = false;
  // at most this many timed repeats a round: each rebuilds the world, untimed, and a cheap scene's
  // rebuilds were most of the default suite's time beside its stepping (380,000 of them at 50);
  // five rounds of ten still give a median over 50 repeats
  int max_timed_repeats = 10;
  // s of stepping after which the first run stops (0: none): the run is a timeout, timed over
  // the steps it took (`physbench run --run-cap`, docs/metrics.md, "Status")
  double run_cap_seconds = 0.0;
  double explosion_distance = 1e6;  // m from the origin: a body beyond it has exploded
  // for the harness's own tests only: each timed stretch of stepping is stretched by this share
  // of its time (busy waiting), so that `physbench compare` can be shown to flag a slower build
  // (PHYSBENCH_TEST_SLOWDOWN, harness/src/worker.cpp)
  double slowdown = 0.0;
  // a sweep's solver iterations or substeps (Engine::tune); none: the variant's own
  SolverKnobs knobs;
};

struct RunResult {
  Status status = Status::Ok;
  std::string message;  // why, for anything but ok
  std::string engine_version;
  std::vector<Setting> settings;
  long steps = 0;                    // steps per run (a run stopped at the cap: the steps it took)
  std::vector<double> wall_seconds;  // stepping time of each timed repeat (s)
  // the engine's stages (Engine::stage_times) summed over the timed repeats; empty names when
  // the engine does not time them
  StageTimes stages;
  // the contact points of the first run's steps (Engine::contact_count); steps 0 when the engine
  // does not report them
  ContactCount contacts;
  Trajectory trajectory;             // from the first run
};

// A first run records the trajectory and warms caches; timed repeats then rebuild the world
// and step it again with the same sampling work. A run that took longer than the budget is
// timed once.
RunResult simulate(const EngineInfo& engine, const std::string& variant, const Scene& scene,
                   const SimulateOptions& options = {});

// true when every probed state is finite and within the explosion distance
bool is_sane(const Sample& sample, double explosion_distance);

}  // namespace physbench
