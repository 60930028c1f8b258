// The plan, the runner's first stage, by itself: no job runs and no file is written, so these
// tests take milliseconds. A shard is a stride over the plan's scene steps, and the fingerprint
// covers what the jobs will run and nothing else.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <set>
#include <utility>

#include "physbench/plan.h"

namespace {

using physbench::EngineVariant;
using physbench::Plan;
using physbench::PlannedJob;
using physbench::RunOptions;

// engine variants as a catalog lists them; the hosts are never started here
std::vector<EngineVariant> catalog() {
  return {{"rtp", "rk4", "0", "/nonexistent/physbench"},
          {"rtp", "euler", "0", "/nonexistent/physbench"},
          {"bullet", "float", "0", "/nonexistent/physbench"},
          {"test-fault", "hang", "0", "/nonexistent/physbench", true}};
}

RunOptions options() {
  RunOptions o;
  // tumbling-box and spring-oscillator are swept over their own steps, projectile is not
  o.scenarios = {"projectile", "tumbling-box", "spring-oscillator"};
  o.timing_budget = 0.05;
  return o;
}

TEST(Plan, JobsAreEveryStepOnEveryEngineVariantNumberedInOrder) {
  const Plan plan = physbench::plan_run(options(), catalog());
  // the test-only engine is planned only when named
  ASSERT_EQ(plan.engines.size(), 3u);
  ASSERT_GT(plan.steps.size(), 3u) << "tumbling-box's dt sweep gives more than one step";
  ASSERT_EQ(plan.jobs.size(), plan.steps.size() * plan.engines.size());
  for (std::size_t i = 0; i < plan.jobs.size(); ++i) {
    EXPECT_EQ(plan.jobs[i].number, i);
    EXPECT_EQ(plan.jobs[i].step, i / plan.engines.size());
    EXPECT_EQ(plan.jobs[i].engine, i % plan.engines.size());
  }
  // a swept scene runs its own step first, each step in a file of its own
  std::map<std::size_t, std::vector<const physbench::SceneStep*>> by_scene;
  for (const auto& step : plan.steps) by_scene[step.scene].push_back(&step);
  for (const auto& [scene, steps] : by_scene) {
    EXPECT_EQ(steps.front()->dt, plan.scenes[scene].scene.dt);
    EXPECT_TRUE(steps.front()->own_step);
    for (std::size_t i = 1; i < steps.size(); ++i) EXPECT_FALSE(steps[i]->own_step);
    if (steps.size() > 1) {
      for (const auto* step : steps)
        EXPECT_NE(step->tag.find(".dt-"), std::string::npos) << step->tag;
    }
  }
  RunOptions named = options();
  named.engines = {"test-fault"};
  EXPECT_EQ(physbench::plan_run(named, catalog()).engines.size(), 1u);
}

TEST(Plan, ShardsAreAStrideOverSceneStepsThatTogetherAreThePlan) {
  const Plan plan = physbench::plan_run(options(), catalog());
  for (int count = 1; count <= 5; ++count) {
    std::vector<std::size_t> seen;
    std::map<std::size_t, int> shard_of_step;
    for (int index = 1; index <= count; ++index) {
      const std::vector<PlannedJob> shard = plan.shard(index, count);
      for (std::size_t i = 0; i < shard.size(); ++i) {
        const PlannedJob& job = shard[i];
        if (i) {
          EXPECT_LT(shard[i - 1].number, job.number) << "a shard keeps the plan's order";
        }
        EXPECT_EQ(job.step % std::size_t(count), std::size_t(index - 1));
        // every engine of a scene step in one shard: their speed ratios never cross machines
        const auto [it, first] = shard_of_step.emplace(job.step, index);
        EXPECT_EQ(it->second, index) << "step " << job.step << " split over shards";
        seen.push_back(job.number);
      }
    }
    // the shards together are the plan, each job once
    std::sort(seen.begin(), seen.end());
    ASSERT_EQ(seen.size(), plan.jobs.size()) << count << " shards";
    for (std::size_t i = 0; i < seen.size(); ++i) EXPECT_EQ(seen[i], i);
  }
  EXPECT_THROW(plan.shard(0, 2), physbench::RunError);
  EXPECT_THROW(plan.shard(3, 2), physbench::RunError);
}

TEST(Plan, FingerprintCoversWhatRunsAndNotWhereItRuns) {
  const std::string base = physbench::plan_run(options(), catalog()).fingerprint;
  EXPECT_EQ(base.size(), 16u);
  EXPECT_EQ(physbench::plan_run(options(), catalog()).fingerprint, base) << "not deterministic";
  // the shard, the output folder and the timeout do not change what the jobs run
  RunOptions elsewhere = options();
  elsewhere.shard_index = 2;
  elsewhere.shard_count = 3;
  elsewhere.out = "/somewhere/else";
  elsewhere.timeout_seconds = 7;
  EXPECT_EQ(physbench::plan_run(elsewhere, catalog()).fingerprint, base);
  // a different budget, engine set, step or duration does
  RunOptions budget = options();
  budget.timing_budget = 0.1;
  RunOptions engines = options();
  engines.engines = {"rtp"};
  RunOptions duration = options();
  duration.duration = 1.0;
  RunOptions no_sweep = options();
  no_sweep.no_sweep = true;
  std::set<std::string> prints = {base};
  for (const RunOptions& o : {budget, engines, duration, no_sweep})
    EXPECT_TRUE(prints.insert(physbench::plan_run(o, catalog()).fingerprint).second);
}

TEST(Plan, AKnobSweepRunsEveryVariantOncePerValueWithinItsSceneStep) {
  RunOptions swept = options();
  swept.sweep_iterations = {4, 16};
  swept.sweep_substeps = {2};
  const Plan plan = physbench::plan_run(swept, catalog());
  const Plan plain = physbench::plan_run(options(), catalog());
  // each variant at its own settings, then each value of one knob at a time
  ASSERT_EQ(plan.knob_settings.size(), 4u);
  ASSERT_EQ(plan.steps.size(), plain.steps.size());
  ASSERT_EQ(plan.jobs.size(), plan.steps.size() * plan.engines.size() * 4);
  for (std::size_t i = 0; i < plan.jobs.size(); ++i) {
    const PlannedJob& job = plan.jobs[i];
    EXPECT_EQ(job.number, i);
    EXPECT_EQ(job.step, i / (plan.engines.size() * 4));
    EXPECT_EQ(job.engine, i / 4 % plan.engines.size());
    const physbench::SolverKnobs& k = plan.knob_settings[i % 4];
    EXPECT_EQ(job.knobs.iterations, k.iterations);
    EXPECT_EQ(job.knobs.substeps, k.substeps);
  }
  EXPECT_FALSE(plan.jobs[0].knobs.any());
  EXPECT_EQ(plan.jobs[1].knobs.iterations, 4);
  EXPECT_EQ(plan.jobs[2].knobs.iterations, 16);
  EXPECT_EQ(plan.jobs[3].knobs.substeps, 2);
  EXPECT_EQ(plan.jobs[3].knobs.iterations, 0);
  EXPECT_EQ(physbench::knob_tag(plan.jobs[2].knobs), "iterations-16");
  // a shard still takes whole scene steps: every knob of every engine of a step on one machine
  for (const PlannedJob& job : plan.shard(2, 3)) EXPECT_EQ(job.step % 3, 1u);
  EXPECT_EQ(plan.shard(1, 3).size() + plan.shard(2, 3).size() + plan.shard(3, 3).size(),
            plan.jobs.size());
  // the swept values are part of the fingerprint; no sweep fingerprints as before knobs
  RunOptions other = swept;
  other.sweep_iterations = {4, 8};
  EXPECT_NE(plan.fingerprint, plain.fingerprint);
  EXPECT_NE(plan.fingerprint, physbench::plan_run(other, catalog()).fingerprint);
}

// tower-20 carries its own knob grid: every engine variant at its own settings, at 20 iterations
// and at 1, 2, 4 and 8 substeps, in the default suite; tower-10 none; a run's own sweep replaces
// the grid and --no-sweep drops it
TEST(Plan, AScenariosOwnSubstepGridRunsUnlessARunSweepsOrSaysNoSweep) {
  RunOptions towers = options();
  towers.scenarios = {"tower-10", "tower-20"};
  const Plan plan = physbench::plan_run(towers, catalog());
  ASSERT_EQ(plan.steps.size(), 2u);
  std::map<std::size_t, std::vector<std::pair<int, int>>> knobs_of_step;  // (iterations, substeps)
  for (const PlannedJob& job : plan.jobs)
    if (job.engine == 0) knobs_of_step[job.step].push_back({job.knobs.iterations, job.knobs.substeps});
  using Knobs = std::vector<std::pair<int, int>>;
  EXPECT_EQ(knobs_of_step[0], (Knobs{{0, 0}}));  // tower-10: its own only
  EXPECT_EQ(knobs_of_step[1], (Knobs{{0, 0}, {20, 0}, {0, 1}, {0, 2}, {0, 4}, {0, 8}}));  // tower-20
  for (std::size_t i = 0; i < plan.jobs.size(); ++i) EXPECT_EQ(plan.jobs[i].number, i);
  RunOptions none = towers;
  none.no_sweep = true;
  EXPECT_EQ(physbench::plan_run(none, catalog()).jobs.size(), 2u * plan.engines.size());
  EXPECT_NE(physbench::plan_run(none, catalog()).fingerprint, plan.fingerprint);
  RunOptions swept = towers;
  swept.sweep_substeps = {3};
  const Plan replaced = physbench::plan_run(swept, catalog());
  EXPECT_EQ(replaced.jobs.size(), 2u * 2u * plan.engines.size());
  for (const PlannedJob& job : replaced.jobs)
    EXPECT_TRUE(job.knobs.substeps == 0 || job.knobs.substeps == 3);
}

TEST(Plan, BadNamesAreRefusedBeforeAnythingIsPlanned) {
  RunOptions engine = options();
  engine.engines = {"havok"};
  EXPECT_THROW(physbench::plan_run(engine, catalog()), physbench::RunError);
  RunOptions scenario = options();
  scenario.scenarios = {"no-such-scene"};
  EXPECT_THROW(physbench::plan_run(scenario, catalog()), physbench::RunError);
  RunOptions none = options();
  none.engines = {"rtp"};
  none.variants = {"float"};  // a variant that exists, but not on rtp
  EXPECT_THROW(physbench::plan_run(none, catalog()), physbench::RunError);
}

// a build of another variant at another instruction set (rtp's baseline build, a peer's native
// one) runs at each scene's own step only, where speeds are compared; its knobs are swept there
TEST(Plan, AnInstructionSetBuildRunsAtTheScenesOwnStepOnly) {
  std::vector<EngineVariant> with_builds = catalog();
  with_builds.push_back({"rtp", "rk4-x86-64", "0", "/nonexistent/physbench-rtp-baseline"});
  with_builds.push_back({"rapier", "default-native", "0", "/nonexistent/physbench-rapier-native"});
  RunOptions o = options();
  o.sweep_substeps = {1, 4};
  const Plan plan = physbench::plan_run(o, with_builds);
  std::map<std::string, std::set<std::pair<bool, int>>> ran;  // variant: (own step, substeps)
  for (const PlannedJob& job : plan.jobs)
    ran[plan.engines[job.engine].variant].insert({plan.steps[job.step].own_step, job.knobs.substeps});
  const std::set<std::pair<bool, int>> own_only = {{true, 0}, {true, 1}, {true, 4}};
  EXPECT_EQ(ran["rk4-x86-64"], own_only);
  EXPECT_EQ(ran["default-native"], own_only);
  EXPECT_TRUE(ran["rk4"].count({false, 0})) << "the generic build runs the whole sweep";
  EXPECT_EQ(ran["rk4"].size(), 6u);
}

}  // namespace
