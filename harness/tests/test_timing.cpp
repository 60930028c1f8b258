// The physbench command's timing end to end: interleaved rounds in a fresh order, a round that
// crashes, the run cap, and the converged reference a swept scene's steps share
// (docs/metrics.md, "Interleaved timing" and "Status").
#include "runner_support.h"

namespace {

// docs/metrics.md, "Interleaved timing": a scene step's jobs are timed in rounds, each job once a
// round; the first round in plan order (it also samples the trajectory), every later one in a
// fresh order, so a slow spell of the machine falls on every engine alike
TEST(Runner, EveryJobIsTimedOnceARoundInAFreshOrder) {
  const fs::path dir = fresh_dir("rounds");
  std::ofstream(dir / "spring.json")
      << R"({"name": "spring", "dt": 0.01, "duration": 1, "collisions": false,
    "bodies": [{"shape": {"type": "sphere", "radius": 0.1}, "mass": 1, "position": [1, 0, 0]}],
    "springs": [{"body_a": 0, "body_b": -1, "point_b": [0, 0, 0], "stiffness": 10}],
    "probe": {"metrics": ["energy"]}})";
  const Invocation inv =
      physbench({"run", "--scene", (dir / "spring.json").string(), "-e", "rtp", "--variant",
                 "rk4,euler,symplectic,midpoint", "--rounds", "4", "--budget", "0.004", "--out",
                 (dir / "r").string()},
                dir);
  ASSERT_EQ(inv.outcome.exit_code, 0) << inv.output;
  const auto rows = read_rows(dir / "r" / "results.csv");
  ASSERT_EQ(rows.size(), 4u) << inv.output;
  std::vector<std::string> plan_order;
  for (const auto& row : rows) {
    plan_order.push_back(row.at("variant"));
    EXPECT_EQ(row.at("timing_rounds"), "4") << row.at("variant");
    // at least one repeat a round (the first round's sampled run is its one repeat when it takes
    // longer than the round's share of the budget, as under the sanitizers)
    EXPECT_GE(std::stoi(row.at("repeats")), 4) << row.at("variant");
  }
  const auto rounds = read_rows(dir / "r" / "timing_rounds.csv");
  ASSERT_EQ(rounds.size(), 16u) << "four jobs, four rounds";
  std::map<int, std::vector<std::string>> order;  // round → variants in the order they ran
  for (int round = 1; round <= 4; ++round) order[round].assign(4, "");
  for (const auto& r : rounds) {
    const int round = std::stoi(r.at("round")), place = std::stoi(r.at("order"));
    ASSERT_TRUE(round >= 1 && round <= 4 && place >= 1 && place <= 4) << round << " " << place;
    EXPECT_EQ(order[round][place - 1], "") << "two jobs at one place of round " << round;
    order[round][place - 1] = r.at("variant");
    EXPECT_GT(std::stod(r.at("seconds_per_step")), 0.0);
    EXPECT_EQ(r.at("scenario"), "spring");
  }
  EXPECT_EQ(order[1], plan_order) << "the first round runs in plan order";
  int shuffled = 0;
  for (int round = 2; round <= 4; ++round) {
    std::vector<std::string> sorted = order[round], expected = plan_order;
    std::sort(sorted.begin(), sorted.end());
    std::sort(expected.begin(), expected.end());
    EXPECT_EQ(sorted, expected) << "round " << round << " runs every job once";
    shuffled += order[round] != plan_order;
  }
  EXPECT_GT(shuffled, 0) << "no later round changed the order";

  // where the run's time went: the phases within the total, the timed stepping within the jobs'
  // processes, and the one scenario's share the sum of the phases it ran in
  std::ifstream meta_file(dir / "r" / "metadata.json");
  const nlohmann::json wall = nlohmann::json::parse(meta_file).at("wall_time");
  const double first = wall.at("first_runs_s"), later = wall.at("timing_rounds_s"),
               stepping = wall.at("timed_stepping_s"), references = wall.at("references_s"),
               evaluation = wall.at("evaluation_and_files_s"), total = wall.at("total_s");
  EXPECT_GT(first, 0.0);
  EXPECT_GT(later, 0.0) << "rounds 2-4 ran in processes of their own";
  EXPECT_GT(stepping, 0.0);
  EXPECT_LE(stepping, first + later + 0.002);
  EXPECT_EQ(references, 0.0) << "the scene has no converged reference";
  EXPECT_GE(wall.at("other_s").get<double>(), -0.002);
  EXPECT_NEAR(first + later + references + evaluation + wall.at("other_s").get<double>(), total,
              0.005);
  EXPECT_NEAR(wall.at("by_scenario_s").at("spring").get<double>(),
              first + later + references + evaluation, 0.005);
  EXPECT_NEAR(wall.at("by_engine").at("rtp").at("processes_s").get<double>(), first + later, 0.005);
  EXPECT_NEAR(wall.at("by_engine").at("rtp").at("timed_stepping_s").get<double>(), stepping, 0.005);
}

// a job that crashes in a later timing round is a crash, not a row timed in fewer rounds
TEST(Runner, AJobThatCrashesInALaterTimingRoundIsCrashed) {
  const fs::path dir = fresh_dir("round_crash");
  const fs::path marker = dir / "fault-marker";
  ::setenv("PHYSBENCH_TEST_FAULT_MARKER", marker.c_str(), 1);
  std::ofstream(dir / "free.json")
      << R"({"name": "free", "dt": 0.01, "duration": 0.1, "collisions": false,
    "bodies": [{"shape": {"type": "sphere", "radius": 0.1}, "mass": 1}],
    "probe": {"metrics": ["energy"]}})";
  const Invocation inv =
      physbench({"run", "--scene", (dir / "free.json").string(), "-e", "test-fault", "--variant",
                 "abort-later", "--rounds", "3", "--budget", "0", "--out", (dir / "r").string()},
                dir);
  ::unsetenv("PHYSBENCH_TEST_FAULT_MARKER");
  ASSERT_EQ(inv.outcome.exit_code, 0) << inv.output;
  const auto rows = read_rows(dir / "r" / "results.csv");
  ASSERT_EQ(rows.size(), 1u) << inv.output;
  EXPECT_EQ(rows[0].at("status"), "crashed") << rows[0].at("message");
  EXPECT_NE(rows[0].at("message").find("timing round 2"), std::string::npos)
      << rows[0].at("message");
}

// a job too slow to finish within the run cap is stopped there and reported as such: a timeout
// row with its speed from the steps it took, the steps named in its message, and no verdict or
// trajectory from part of a run; a job that finishes inside the cap is untouched. rtp's seed
// solver and Rapier on the 1,275-box pyramid take far longer than 0.2 s of stepping; the one-box
// bounce far less, even under the sanitizers on a busy machine
TEST(Runner, AJobOverTheRunCapIsATimeoutTimedOverTheStepsItTook) {
  const fs::path dir = fresh_dir("run_cap");
  std::vector<std::string> engines = {"rtp"};
#ifdef PHYSBENCH_WORKERS_BUILT
  engines.push_back("rapier");  // an external worker stops at the cap the same way
#endif
  std::string engine_list;
  for (const std::string& e : engines) engine_list += (engine_list.empty() ? "" : ",") + e;
  const Invocation inv = physbench({"run", "-s", "pyramid-50,bounce-e1-box", "-e", engine_list,
                                    "--variant", "seed,default", "--no-sweep", "--budget", "0",
                                    "--run-cap", "0.2", "--out", (dir / "r").string()},
                                   dir);
  ASSERT_EQ(inv.outcome.exit_code, 0) << inv.output;
  const std::string failed = std::to_string(engines.size()) + " job(s) crashed, timed out or failed";
  EXPECT_NE(inv.output.find(failed), std::string::npos) << inv.output;
  std::map<std::string, std::map<std::string, std::string>> by;
  for (const auto& row : read_rows(dir / "r" / "results.csv"))
    by[row.at("scenario") + " " + row.at("engine")] = row;
  for (const std::string& engine : engines) {
    const auto& slow = by[std::string("pyramid-50 ") + engine];
    ASSERT_EQ(slow.at("status"), "timeout") << engine << ": " << slow.at("message");
    EXPECT_NE(slow.at("message").find("too slow: stopped at the run cap after"), std::string::npos)
        << slow.at("message");
    EXPECT_NE(slow.at("message").find("of 600 steps"), std::string::npos) << slow.at("message");
    ASSERT_FALSE(slow.at("steps_per_s").empty()) << engine;
    // the speed is the steps taken over the stepping time, about the cap: under 600 steps' worth
    const double speed = std::stod(slow.at("steps_per_s"));
    EXPECT_GT(speed, 0.0);
    EXPECT_LT(speed * 0.2, 600.0 * 1.05) << engine << " took every step, yet timed out";
    EXPECT_TRUE(slow.at("contact_verdict").empty()) << slow.at("contact_verdict");
    EXPECT_TRUE(slow.at("trajectory").empty()) << slow.at("trajectory");
    const auto& quick = by[std::string("bounce-e1-box ") + engine];
    EXPECT_EQ(quick.at("status"), "ok") << engine << ": " << quick.at("message");
  }
}

// the steps of a swept free-motion scene that sample at the same times share one converged
// reference, computed once: the 120 Hz row of a 60,120 Hz sweep is measured against the 60 Hz
// step's SciPy run, and its errors are those of a run at 120 Hz alone, which computes its own
TEST(Runner, SweptStepsSampledAtTheSameTimesShareOneReference) {
  const fs::path dir = fresh_dir("shared_reference");
  const Invocation swept = physbench({"run", "-s", "tumbling-box", "-e", "rtp", "--variant", "rk4",
                                      "--sweep-hz", "60,120", "--duration", "2", "--budget", "0",
                                      "--out", (dir / "swept").string()},
                                     dir);
  ASSERT_EQ(swept.outcome.exit_code, 0) << swept.output;
  EXPECT_NE(swept.output.find("reference for tumbling-box.dt-120hz: tumbling-box.dt-60hz's"),
            std::string::npos)
      << swept.output;
  EXPECT_EQ(swept.output.find("reference for tumbling-box.dt-120hz: SciPy"), std::string::npos);
  const Invocation alone = physbench({"run", "-s", "tumbling-box", "-e", "rtp", "--variant", "rk4",
                                      "--dt", "0.008333333333333333", "--duration", "2", "--budget",
                                      "0", "--out", (dir / "alone").string()},
                                     dir);
  ASSERT_EQ(alone.outcome.exit_code, 0) << alone.output;
  const auto at_120 = [](const std::vector<std::map<std::string, std::string>>& rows) {
    for (const auto& r : rows)
      if (std::abs(std::stod(r.at("dt")) - 1.0 / 120.0) < 1e-12) return r;
    return std::map<std::string, std::string>{};
  };
  const auto shared = at_120(read_rows(dir / "swept" / "results.csv"));
  const auto own = at_120(read_rows(dir / "alone" / "results.csv"));
  ASSERT_FALSE(shared.empty() || own.empty()) << swept.output << alone.output;
  EXPECT_EQ(shared.at("reference_status"), "ok");
  for (const char* column : {"orientation_err_max", "reference_self_error"})
    EXPECT_NEAR(std::stod(shared.at(column)), std::stod(own.at(column)),
                1e-9 * std::abs(std::stod(own.at(column))))
        << column;
}

}  // namespace
