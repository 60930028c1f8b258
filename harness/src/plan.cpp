#include "physbench/plan.h"

#include <algorithm>

#include "physbench/scenarios.h"
#include "physbench/scene_json.h"
#include "text.h"

namespace physbench {

namespace {

bool selected(const std::vector<std::string>& filter, const std::string& name) {
  return filter.empty() || std::find(filter.begin(), filter.end(), name) != filter.end();
}

// every engine and variant the options name must exist in the catalog
void check_names(const RunOptions& options, const std::vector<EngineVariant>& catalog) {
  auto known_engines = [&] {
    std::string names;
    for (const EngineVariant& ev : catalog)
      if (!ev.test_only && names.find(ev.engine) == std::string::npos)
        names += (names.empty() ? "" : ", ") + ev.engine;
    return names;
  };
  for (const std::string& e : options.engines)
    if (std::none_of(catalog.begin(), catalog.end(),
                     [&](const EngineVariant& ev) { return ev.engine == e; }))
      throw RunError("unknown engine '" + e + "' (this build has: " + known_engines() + ")");
  for (const std::string& v : options.variants)
    if (std::none_of(catalog.begin(), catalog.end(),
                     [&](const EngineVariant& ev) { return ev.variant == v; }))
      throw RunError("unknown variant '" + v + "' (see `physbench list`)");
}

// the built-in scenarios asked for (all of them when neither they nor scene files are named),
// then the scene files, each at the steps it will run
std::vector<PlannedScene> planned_scenes(const RunOptions& options) {
  std::vector<PlannedScene> scenes;
  std::vector<std::string> wanted = options.scenarios;
  if (wanted.empty() && options.scene_files.empty())
    for (const Scenario& s : physbench::scenarios()) wanted.push_back(s.name);
  for (const std::string& name : wanted) {
    const Scenario* scenario = find_scenario(name);
    if (!scenario) {
      std::string names;
      for (const Scenario& s : physbench::scenarios())
        names += (names.empty() ? "" : ", ") + s.name;
      throw RunError("unknown scenario '" + name + "' (built in: " + names + ")");
    }
    PlannedScene p{scenario->build(),  scenario->question,       scenario->sweep_dt,
                   scenario->family,   scenario->parameter_name, scenario->parameter,
                   {}};
    for (int n : scenario->sweep_iterations) p.knobs.push_back({n, 0});
    for (int n : scenario->sweep_substeps) p.knobs.push_back({0, n});
    scenes.push_back(std::move(p));
  }
  for (const std::string& file : options.scene_files) {
    try {
      PlannedScene p;  // no dt sweep and no family: the file's own step only
      p.scene = load_scene_file(file);
      p.question = "scene file " + file;
      scenes.push_back(std::move(p));
    } catch (const SceneError& e) {
      throw RunError(e.what());
    }
  }
  for (PlannedScene& p : scenes) {
    if (options.dt) p.scene.dt = *options.dt;
    if (options.duration) p.scene.duration = *options.duration;
    if (!options.sweep_dt.empty()) p.dts = options.sweep_dt;
    if (options.dt || options.no_sweep) p.dts.clear();
    // the run's own knob sweep replaces the scenario's grid; --no-sweep drops it
    if (options.no_sweep || !options.sweep_iterations.empty() || !options.sweep_substeps.empty())
      p.knobs.clear();
    p.knobs.insert(p.knobs.begin(), SolverKnobs{});
    // the scene's own step first; the sweep's other steps after it
    std::erase_if(p.dts, [&](double dt) { return std::abs(dt - p.scene.dt) < 1e-12 * p.scene.dt; });
    p.dts.insert(p.dts.begin(), p.scene.dt);
    for (double dt : p.dts) {
      Scene instance = p.scene;
      instance.dt = dt;
      try {
        validate(instance);
      } catch (const SceneError& e) {
        throw RunError(p.scene.name + " at dt = " + number(dt) +
                       " with the overrides given: " + e.what());
      }
    }
  }
  return scenes;
}

// a build of another variant at another instruction set (rtp's baseline-ISA build, a peer's native
// one: workers/catalog.tsv): its accuracy at a swept step repeats its sibling's, and its speed is
// compared at the scene's own step, so it runs there only (its knobs are swept as its sibling's)
bool isa_build(const std::string& variant) {
#ifdef PHYSBENCH_RTP_ISA_SUFFIX
  const char* rtp_baseline = PHYSBENCH_RTP_ISA_SUFFIX;
#else
  const char* rtp_baseline = "-x86-64";
#endif
  for (const std::string suffix : {"-native", "-avx2", rtp_baseline})
    if (variant.size() > suffix.size() &&
        variant.compare(variant.size() - suffix.size(), suffix.size(), suffix) == 0)
      return true;
  return false;
}

}  // namespace

std::string step_tag(double dt) {
  const double rate = 1.0 / dt;
  if (std::abs(rate - std::round(rate)) < 1e-9 * rate)
    return std::to_string(std::lround(rate)) + "hz";
  return number(dt) + "s";
}

std::string knob_tag(const SolverKnobs& knobs) {
  if (knobs.iterations > 0) return "iterations-" + std::to_string(knobs.iterations);
  if (knobs.substeps > 0) return "substeps-" + std::to_string(knobs.substeps);
  return "";
}

Scene Plan::scene_at(const SceneStep& step) const {
  Scene scene = scenes.at(step.scene).scene;
  scene.dt = step.dt;
  return scene;
}

std::vector<PlannedJob> Plan::shard(int index, int count) const {
  if (count < 1 || index < 1 || index > count)
    throw RunError("shard " + std::to_string(index) + "/" + std::to_string(count) +
                   " is not a slice of the plan");
  std::vector<PlannedJob> slice;
  for (const PlannedJob& job : jobs)
    if (job.step % std::size_t(count) == std::size_t(index - 1)) slice.push_back(job);
  return slice;
}

Plan plan_run(const RunOptions& options, const std::vector<EngineVariant>& catalog) {
  check_names(options, catalog);
  Plan plan;
  plan.scenes = planned_scenes(options);
  for (const EngineVariant& ev : catalog)
    // a test-only engine runs only when named: "every engine" never includes it
    if (selected(options.engines, ev.engine) && selected(options.variants, ev.variant) &&
        (!ev.test_only || !options.engines.empty()))
      plan.engines.push_back(ev);
  if (plan.engines.empty()) throw RunError("no engine variant matches the filters given");
  plan.timing_budget = options.timing_budget;

  // each engine variant at its own settings, then at each swept value of one knob
  plan.knob_settings = {SolverKnobs{}};
  for (int n : options.sweep_iterations) plan.knob_settings.push_back({n, 0});
  for (int n : options.sweep_substeps) plan.knob_settings.push_back({0, n});

  // every scene step (a scene at one of its steps) in order, numbered from 0, each with every
  // engine variant at every knob setting of its scene (the run's sweep, or the scenario's own
  // grid), in that order. The fingerprint covers each scene as it will run, the engine variants,
  // the swept knobs and the timing budget
  std::string plan_text = "budget " + exact(options.timing_budget) + "\n";
  // (a plan timed in the default five rounds fingerprints as one before rounds existed)
  if (options.rounds != 5) plan_text += "rounds " + std::to_string(options.rounds) + "\n";
  if (options.round_cap_seconds != 3.0) plan_text += "round cap " + exact(options.round_cap_seconds) + "\n";
  if (options.run_cap_seconds != 30.0) plan_text += "run cap " + exact(options.run_cap_seconds) + "\n";
  // (a plan without a knob sweep fingerprints as it did before knobs were swept)
  if (!options.sweep_iterations.empty() || !options.sweep_substeps.empty()) {
    plan_text += "knobs";
    for (const SolverKnobs& k : plan.knob_settings) plan_text.append(" ").append(knob_tag(k));
    plan_text += "\n";
  }
  for (std::size_t s = 0; s < plan.scenes.size(); ++s) {
    PlannedScene& p = plan.scenes[s];
    if (plan.knob_settings.size() > 1) p.knobs = plan.knob_settings;
    // (a scene at its own settings only fingerprints as it did before knobs were swept)
    const bool grid = p.knobs.size() > 1 && plan.knob_settings.size() <= 1;
    if (grid) {
      plan_text += "scene knobs";
      for (const SolverKnobs& k : p.knobs) plan_text.append(" ").append(knob_tag(k));
      plan_text += "\n";
    }
    for (double dt : p.dts) {
      SceneStep step{plan.steps.size(), s, dt,
                     // one file per step when the scene is swept, else the scene's own name
                     safe_name(p.dts.size() > 1 ? p.scene.name + ".dt-" + step_tag(dt)
                                                : p.scene.name),
                     std::abs(dt - p.scene.dt) <= 1e-9 * p.scene.dt};
      plan_text += to_json(plan.scene_at(step)).dump() + "\n";
      for (std::size_t e = 0; e < plan.engines.size(); ++e) {
        const EngineVariant& ev = plan.engines[e];
        if (!step.own_step && isa_build(ev.variant)) continue;
        plan_text += ev.engine + "/" + ev.variant + "\n";
        for (const SolverKnobs& knobs : p.knobs)
          plan.jobs.push_back({plan.jobs.size(), step.number, e, knobs});
      }
      plan.steps.push_back(std::move(step));
    }
  }
  plan.fingerprint = fingerprint(plan_text);
  return plan;
}

}  // namespace physbench
