// The run's first stage: every job of a run, in order, from the options, the scenes and the
// engine catalog alone. No process runs and no file is written here, so the plan can be tested
// by itself, and a shard is a stride over it (docs/regression.md, "Shards").
#pragma once

#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include "physbench/runner.h"
#include "physbench/scene.h"

namespace physbench {

// a built-in scenario or a scene file, with the steps it runs at
struct PlannedScene {
  Scene scene;
  std::string question;
  std::vector<double> dts;  // the scene's own step first, then its sweep's other steps
  std::string family;       // scenarios that map one parameter, e.g. stiff-spring
  std::string parameter_name;
  double parameter = std::nan("");
  std::vector<SolverKnobs> knobs;  // every engine variant's settings here: its own, then a sweep's
};

// a scene at one of its steps: the unit a shard takes whole, with every engine variant
struct SceneStep {
  std::size_t number = 0;  // in the whole plan, from 0
  std::size_t scene = 0;   // index into Plan::scenes
  double dt = 0.0;
  std::string tag;  // file stem of its scene, trajectories and poses: the scene's name, with
                    // ".dt-120hz" (say) when the scene is swept
  bool own_step = true;  // the scene's own step (the replay viewer's poses are written there)
};

// one (scene step, engine variant, solver knobs) job
struct PlannedJob {
  std::size_t number = 0;  // in the whole plan: (step · engines + engine) · knob settings + knob
  std::size_t step = 0;    // index into Plan::steps
  std::size_t engine = 0;  // index into Plan::engines
  SolverKnobs knobs;       // a sweep's iterations or substeps; none: the variant's own
};

struct Plan {
  std::vector<PlannedScene> scenes;
  std::vector<SceneStep> steps;        // every scene step in order
  std::vector<EngineVariant> engines;  // the engine variants every step runs, in order
  // what each engine variant runs with at every step: its own settings first, then each value
  // of --sweep-iterations, then of --sweep-substeps (one knob at a time)
  std::vector<SolverKnobs> knob_settings;  // the run's own sweep (--sweep-*), or none
  std::vector<PlannedJob> jobs;        // the whole plan in order; jobs[i].number == i
  double timing_budget = 0.0;
  // 64-bit FNV-1a, in hex, of each scene as it will run (its JSON at each step), the engine
  // variants, the swept knobs and the timing budget: `merge` refuses shards whose plans differ
  std::string fingerprint;

  // the scene as it runs at a step
  Scene scene_at(const SceneStep& step) const;
  // the K-th of N slices (K from 1): the jobs of the scene steps whose number is K−1 modulo N,
  // in plan order, so every engine of a step runs in one shard, on one machine
  std::vector<PlannedJob> shard(int index, int count) const;
};

// Checks every engine, variant and scenario name and every scene file (RunError names the
// culprit), applies the options' step, duration and sweep, and numbers the jobs.
Plan plan_run(const RunOptions& options, const std::vector<EngineVariant>& catalog);

// "120hz" for a step that is a whole rate, else the step in seconds
std::string step_tag(double dt);

// "iterations-8", "substeps-2": a job's knobs in its file names; empty for none
std::string knob_tag(const SolverKnobs& knobs);

}  // namespace physbench
