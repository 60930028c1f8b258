// The physbench command end to end: rows for every engine, isolation of failures, and clear
// errors with no results file for bad input. Each test runs the real command on a scene of its
// own (the helpers are in runner_support.h; the timing rounds' tests in test_timing.cpp).
#include "runner_support.h"

namespace {

#if defined(PHYSBENCH_HAVE_BULLET) && defined(PHYSBENCH_HAVE_ODE) && \
    defined(PHYSBENCH_HAVE_BOX2D) && defined(PHYSBENCH_HAVE_MUJOCO)
TEST(Runner, ProjectileOnEveryEngineVariant) {
  const fs::path dir = fresh_dir("all_engines");
  const Invocation inv = physbench(
      {"run", "--scenario", "projectile-planar", "--budget", "0.01", "--out", (dir / "r").string()},
      dir);
  ASSERT_EQ(inv.outcome.kind, ChildOutcome::Kind::Exited) << inv.output;
  ASSERT_EQ(inv.outcome.exit_code, 0) << inv.output;
  const auto rows = read_rows(dir / "r" / "results.csv");
  for (const auto& [engine, variant] :
       std::vector<std::pair<std::string, std::string>>{{"rtp", "rk4"},
                                                        {"bullet", "float"},
                                                        {"bullet", "double"},
                                                        {"ode", "quickstep"},
                                                        {"box2d", "default"},
                                                        {"mujoco", "euler"}}) {
    const auto* row = find_row(rows, engine, variant);
    ASSERT_NE(row, nullptr) << "no row for " << engine << "/" << variant;
    EXPECT_EQ(row->at("status"), "ok") << engine << "/" << variant << ": " << row->at("message");
    EXPECT_GT(std::stod(row->at("steps_per_s")), 0.0);
    EXPECT_TRUE(fs::exists(dir / "r" / row->at("trajectory")));
  }
  // the double-precision build ran in its own process: closer to the closed form than float
  const double single = std::stod(find_row(rows, "bullet", "float")->at("position_err_final"));
  const double dbl = std::stod(find_row(rows, "bullet", "double")->at("position_err_final"));
  const double semi_implicit = 0.5 * 9.81 / 60.0 * 2.5;
  EXPECT_LT(std::abs(dbl - semi_implicit), 1e-9);
  EXPECT_GT(std::abs(single - semi_implicit), 1e-7);
  EXPECT_TRUE(fs::exists(dir / "r" / "metadata.json"));
  EXPECT_FALSE(fs::exists(dir / "r" / ".work"));
}
#endif

#if defined(PHYSBENCH_HAVE_BULLET) && defined(PHYSBENCH_HAVE_ODE) && \
    defined(PHYSBENCH_HAVE_BOX2D) && defined(PHYSBENCH_HAVE_MUJOCO)
// the contact smoke run: every peer variant makes a row on a tower and a bounce, none crashes,
// the contact columns are filled, and a failure of the scene's question is named in the message
TEST(Runner, ContactScenesOnEveryPeer) {
  const fs::path dir = fresh_dir("contacts");
  const Invocation inv =
      physbench({"run", "-s", "tower-10,bounce-e0.5", "-e", "bullet,ode,box2d,mujoco", "--budget",
                 "0", "--out", (dir / "r").string()},
                dir);
  ASSERT_EQ(inv.outcome.kind, ChildOutcome::Kind::Exited) << inv.output;
  ASSERT_EQ(inv.outcome.exit_code, 0) << inv.output;
  const auto rows = read_rows(dir / "r" / "results.csv");
  int ok = 0;
  for (const auto& row : rows) {
    const std::string what = row.at("scenario") + " " + row.at("engine") + "/" + row.at("variant");
    EXPECT_NE(row.at("status"), "crashed") << what;
    EXPECT_NE(row.at("status"), "timeout") << what;
    if (row.at("status") != "ok") {
      EXPECT_FALSE(row.at("message").empty()) << what;
      continue;
    }
    ++ok;
    EXPECT_FALSE(row.at("penetration_max").empty()) << what;
    if (row.at("scenario") == "tower-10") {
      EXPECT_FALSE(row.at("stack_drift_max").empty()) << what;
      EXPECT_FALSE(row.at("contact_verdict").empty()) << what;
      if (row.at("contact_verdict") != "stands") {
        EXPECT_NE(row.at("message").find(row.at("contact_verdict")), std::string::npos) << what;
      }
    } else {
      EXPECT_FALSE(row.at("apex_rel_err").empty()) << what;
      EXPECT_TRUE(row.at("stack_drift_max").empty()) << what;  // not asked for: empty, not 0
    }
  }
  for (const std::string engine : {"bullet", "ode", "box2d", "mujoco"})
    for (const std::string scenario : {"tower-10", "bounce-e0.5"})
      EXPECT_TRUE(std::any_of(rows.begin(), rows.end(), [&](const auto& r) {
        return r.at("engine") == engine && r.at("scenario") == scenario && r.at("status") == "ok";
      })) << engine << " has no ok row on " << scenario;
  EXPECT_GE(ok, 16);
}
#endif

#ifdef PHYSBENCH_HAVE_BOX2D
TEST(Runner, UnsupportedSceneIsARowWithItsReason) {
  const fs::path dir = fresh_dir("unsupported");
  const Invocation inv =
      physbench({"run", "-s", "projectile", "-e", "box2d", "--out", (dir / "r").string()}, dir);
  ASSERT_EQ(inv.outcome.exit_code, 0) << inv.output;
  const auto rows = read_rows(dir / "r" / "results.csv");
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].at("status"), "unsupported");
  EXPECT_NE(rows[0].at("message").find("not marked planar"), std::string::npos);
}
#endif

TEST(Runner, RunawaySceneIsRecordedAsExploded) {
  const fs::path dir = fresh_dir("exploded");
  std::ofstream(dir / "runaway.json")
      << R"({"name": "runaway", "dt": 0.01, "duration": 1, "collisions": false,
    "bodies": [{"shape": {"type": "sphere", "radius": 0.1}, "mass": 1e-3, "position": [1, 0, 0]}],
    "springs": [{"body_a": 0, "body_b": -1, "point_b": [0, 0, 0], "stiffness": 1e12}],
    "probe": {"metrics": ["energy"]}})";  // omega dt = 3e5: every explicit integrator overflows
  const Invocation inv = physbench({"run", "--scene", (dir / "runaway.json").string(), "-e", "rtp",
                                    "--out", (dir / "r").string()},
                                   dir);
  ASSERT_EQ(inv.outcome.exit_code, 0) << inv.output;
  const auto rows = read_rows(dir / "r" / "results.csv");
  ASSERT_GE(rows.size(), 3u);  // one per rtp variant
  for (const auto& row : rows) {
    EXPECT_EQ(row.at("status"), "exploded");
    EXPECT_TRUE(row.at("steps_per_s").empty()) << "an early stop has no comparable speed";
  }
}

// one suite: a scene that sends rtp to infinity, and the test-only engine whose adapter aborts or
// hangs in its first step, beside a normal scene; every failure is its own row and the jobs after
// each (the normal scene's rtp job runs after both faults on the runaway scene) still finish
TEST(Runner, ExplodedHungAndAbortingJobsAreRowsAndTheOthersStillComplete) {
  const fs::path dir = fresh_dir("faults");
  std::ofstream(dir / "runaway.json")
      << R"({"name": "runaway", "dt": 0.01, "duration": 1, "collisions": false,
    "bodies": [{"shape": {"type": "sphere", "radius": 0.1}, "mass": 1e-3, "position": [1, 0, 0]}],
    "springs": [{"body_a": 0, "body_b": -1, "point_b": [0, 0, 0], "stiffness": 1e12}],
    "probe": {"metrics": ["energy"]}})";  // omega dt = 3e5: RK4 overflows to inf, then NaN
  std::ofstream(dir / "normal.json")
      << R"({"name": "normal", "dt": 0.01, "duration": 1, "collisions": false,
    "bodies": [{"shape": {"type": "sphere", "radius": 0.1}, "mass": 1, "position": [1, 0, 0]}],
    "springs": [{"body_a": 0, "body_b": -1, "point_b": [0, 0, 0], "stiffness": 10}],
    "probe": {"metrics": ["energy"]}})";
  const Invocation inv = physbench(
      {"run", "--scene", (dir / "runaway.json").string(), "--scene", (dir / "normal.json").string(),
       "-e", "rtp,test-fault", "--variant", "rk4,abort,hang", "--budget", "0", "--timeout", "3",
       "--out", (dir / "r").string()},
      dir);
  ASSERT_EQ(inv.outcome.kind, ChildOutcome::Kind::Exited) << inv.output;
  ASSERT_EQ(inv.outcome.exit_code, 0) << inv.output;
  EXPECT_NE(inv.output.find("4 job(s) crashed, timed out or failed"), std::string::npos)
      << inv.output;
  const auto rows = read_rows(dir / "r" / "results.csv");
  ASSERT_EQ(rows.size(), 6u) << inv.output;
  auto status_of = [&](const std::string& scenario, const std::string& variant) {
    for (const auto& r : rows)
      if (r.at("scenario") == scenario && r.at("variant") == variant) return r;
    ADD_FAILURE() << "no row for " << scenario << " " << variant;
    return std::map<std::string, std::string>{{"status", ""}, {"message", ""}};
  };
  const auto exploded = status_of("runaway", "rk4");
  EXPECT_EQ(exploded.at("status"), "exploded") << exploded.at("message");
  EXPECT_NE(exploded.at("message").find("non-finite or runaway state"), std::string::npos)
      << exploded.at("message");
  for (const std::string scenario : {"runaway", "normal"}) {
    const auto crashed = status_of(scenario, "abort");
    EXPECT_EQ(crashed.at("status"), "crashed") << crashed.at("message");
    EXPECT_NE(crashed.at("message").find("killed by signal 6"), std::string::npos)
        << crashed.at("message");
    const auto hung = status_of(scenario, "hang");
    EXPECT_EQ(hung.at("status"), "timeout") << hung.at("message");
    EXPECT_NE(hung.at("message").find("timed out after"), std::string::npos) << hung.at("message");
  }
  const auto normal = status_of("normal", "rk4");
  EXPECT_EQ(normal.at("status"), "ok") << normal.at("message");
  EXPECT_FALSE(normal.at("steps_per_s").empty());
  EXPECT_FALSE(normal.at("energy_drift_max").empty());
  EXPECT_TRUE(fs::exists(dir / "r" / normal.at("trajectory")));
  EXPECT_FALSE(fs::exists(dir / "r" / ".work")) << "no worker's files are left behind";
}

TEST(Runner, TestOnlyEngineIsNeitherListedNorRunByDefault) {
  const fs::path dir = fresh_dir("test_only");
  const Invocation list = physbench({"list"}, dir);
  ASSERT_EQ(list.outcome.exit_code, 0) << list.output;
  EXPECT_EQ(list.output.find("test-fault"), std::string::npos) << list.output;
  // every engine, every variant: not the test-only one
  const Invocation inv =
      physbench({"run", "-s", "projectile", "--budget", "0", "--out", (dir / "r").string()}, dir);
  ASSERT_EQ(inv.outcome.exit_code, 0) << inv.output;
  for (const auto& row : read_rows(dir / "r" / "results.csv"))
    EXPECT_NE(row.at("engine"), "test-fault");
  // an unknown engine's message lists the real engines only
  const Invocation bad = physbench({"run", "-e", "havok", "--out", (dir / "x").string()}, dir);
  EXPECT_EQ(bad.outcome.exit_code, 2);
  EXPECT_EQ(bad.output.find("test-fault"), std::string::npos) << bad.output;
}

TEST(Runner, EnergyGrowthOverAHundredPercentReadsDivergedNotOk) {
  // a spring at ω dt = 5/6: the midpoint method gains (ω dt)⁴/4 = 12 % of its energy a step and
  // ends finite (some 30 m out) but 10³ times higher; symplectic Euler's energy stays bounded
  const fs::path dir = fresh_dir("diverged");
  std::ofstream(dir / "spring.json")
      << R"({"name": "spring", "dt": 0.03333333333333333, "duration": 2, "collisions": false,
    "gravity": [0, 0, 0],
    "bodies": [{"shape": {"type": "sphere", "radius": 0.1}, "mass": 1, "position": [1, 0, 0]}],
    "springs": [{"body_a": 0, "body_b": -1, "point_b": [0, 0, 0], "stiffness": 625}],
    "probe": {"metrics": ["energy"]}})";
  const Invocation inv =
      physbench({"run", "--scene", (dir / "spring.json").string(), "-e", "rtp", "--variant",
                 "midpoint,symplectic", "--budget", "0", "--out", (dir / "r").string()},
                dir);
  ASSERT_EQ(inv.outcome.exit_code, 0) << inv.output;
  const auto rows = read_rows(dir / "r" / "results.csv");
  const auto* euler = find_row(rows, "rtp", "midpoint");
  const auto* symplectic = find_row(rows, "rtp", "symplectic");
  ASSERT_TRUE(euler && symplectic);
  EXPECT_EQ(euler->at("status"), "diverged") << euler->at("message");
  EXPECT_GT(std::stod(euler->at("energy_drift_max")), 1.0);
  EXPECT_NE(euler->at("message").find("energy grew to"), std::string::npos) << euler->at("message");
  EXPECT_FALSE(euler->at("steps_per_s").empty()) << "it finished: its speed is a measurement";
  EXPECT_EQ(symplectic->at("status"), "ok") << symplectic->at("message");
}

TEST(Runner, ContactSceneThatCreatesEnergyReadsDivergedNotOk) {
  // a struck row of elastic balls: nothing in it can add energy. The seed's lab 5 reverses every
  // relative velocity a contact sees in each of its iterations, and the row ends with 40 % more
  // energy than the strike's: diverged, with the joules named; the soft step keeps it and is ok
  const fs::path dir = fresh_dir("contact-diverged");
  const Invocation inv =
      physbench({"run", "-s", "cradle-5", "-e", "rtp", "--variant", "seed,soft-step", "--budget",
                 "0", "--no-sweep", "--out", (dir / "r").string()},
                dir);
  ASSERT_EQ(inv.outcome.exit_code, 0) << inv.output;
  const auto rows = read_rows(dir / "r" / "results.csv");
  const auto* seed = find_row(rows, "rtp", "seed");
  const auto* soft = find_row(rows, "rtp", "soft-step");
  ASSERT_TRUE(seed && soft);
  EXPECT_EQ(seed->at("status"), "diverged") << seed->at("message");
  EXPECT_NE(seed->at("message").find("energy grew by"), std::string::npos) << seed->at("message");
  EXPECT_GT(std::stod(seed->at("energy_added_max")), 0.05 * 2.0);  // of the strike's 2 J
  EXPECT_EQ(soft->at("status"), "ok") << soft->at("message");
  EXPECT_EQ(soft->at("cradle_answer"), "simultaneous");
}

// a body on a spring compared with the converged reference (rtp RK4 at dt / divisor)
std::string converged_spring_scene(const std::string& name, double dt, double duration,
                                   int divisor) {
  std::ostringstream scene;
  scene << std::setprecision(17) << R"({"name": ")" << name << R"(", "dt": )" << dt
        << R"(, "duration": )" << duration << R"(, "collisions": false, "gravity": [0, 0, 0],
    "bodies": [{"shape": {"type": "box", "half_extents": [0.1, 0.2, 0.3]}, "mass": 1,
                "position": [1, 0, 0], "angular_velocity": [0, 1, 0]}],
    "springs": [{"body_a": 0, "body_b": -1, "local_point_a": [0.1, 0, 0], "stiffness": 100}],
    "probe": {"metrics": ["position", "orientation", "energy"]},
    "reference": {"kind": "converged", "dt_divisor": )"
        << divisor << "}}";
  return scene.str();
}

TEST(Runner, ConvergedReferenceThatFailsOrTimesOutIsNamedOnEveryRowThatNeededIt) {
  // the reference is SciPy's, run by the project's Python: one run where it works, one where its
  // interpreter is missing (an error) and one where it hangs (a timeout)
  const fs::path dir = fresh_dir("reference_failure");
  std::ofstream(dir / "spring.json") << converged_spring_scene("spring", 1e-3, 1.0, 4);
  const fs::path hang = dir / "hang.sh";
  std::ofstream(hang) << "#!/bin/sh\nsleep 60\n";
  fs::permissions(hang, fs::perms::owner_all);
  const std::map<std::string, std::string> cases = {
      {"ok", ""}, {"error", (dir / "no-python").string()}, {"timeout", hang.string()}};
  for (const auto& [want, python] : cases) {
    if (python.empty())
      ::unsetenv("PHYSBENCH_REFERENCE_PYTHON");
    else
      ::setenv("PHYSBENCH_REFERENCE_PYTHON", python.c_str(), 1);
    const fs::path out = dir / ("r-" + want);
    const Invocation inv =
        physbench({"run", "--scene", (dir / "spring.json").string(), "-e", "rtp", "--variant",
                   "euler,symplectic", "--budget", "0", "--timeout",
                   // the hanging one is cut at 3 s; SciPy's start on a busy machine may take that
                   want == "timeout" ? "3" : "60", "--out", out.string()},
                  dir);
    ::unsetenv("PHYSBENCH_REFERENCE_PYTHON");
    ASSERT_EQ(inv.outcome.exit_code, 0) << inv.output;
    const auto rows = read_rows(out / "results.csv");
    ASSERT_EQ(rows.size(), 2u) << inv.output;
    for (const auto& row : rows) {
      const std::string what = want + " " + row.at("variant");
      // the engine's own run was fine; the reference's fate is a column of its own
      EXPECT_EQ(row.at("status"), "ok") << what << ": " << row.at("message");
      EXPECT_EQ(row.at("reference"), "converged") << what;
      EXPECT_EQ(row.at("reference_status"), want) << what << ": " << row.at("message");
      EXPECT_FALSE(row.at("energy_drift_max").empty()) << what << ": invariants need no reference";
      if (want == "ok") {
        EXPECT_FALSE(row.at("position_err_max").empty()) << what;
        EXPECT_FALSE(row.at("orientation_err_max").empty()) << what;
        EXPECT_FALSE(row.at("reference_self_error").empty()) << what;
        EXPECT_EQ(row.at("message").find("reference"), std::string::npos) << row.at("message");
        continue;
      }
      EXPECT_TRUE(row.at("position_err_max").empty()) << what;
      EXPECT_TRUE(row.at("orientation_err_max").empty()) << what;
      EXPECT_TRUE(row.at("reference_self_error").empty()) << what;
      EXPECT_NE(row.at("message").find("no position or orientation error: reference run (SciPy "
                                       "dop853) " + want),
                std::string::npos)
          << what << ": " << row.at("message");
    }
    // the reason is in the metadata too, per step, for the report's section
    std::ifstream in(out / "metadata.json");
    const nlohmann::json meta = nlohmann::json::parse(in);
    EXPECT_EQ(meta.at("scenarios").at("spring").contains("reference_failure"), want != "ok")
        << meta.at("scenarios").at("spring").dump();
  }
}

// The SciPy reference against the closed forms it is not built from: a torque-free symmetric top
// (Goldstein §5.6) and a damped oscillator, to 1e-9 in position and orientation over the run
TEST(Runner, ScipyReferenceAgreesWithTheClosedForms) {
  const fs::path dir = fresh_dir("scipy_reference");
  for (const physbench::Scene& scene : {physbench::symmetric_top_scene(), physbench::spring_oscillator_scene(0.1)}) {
    const fs::path file = dir / (scene.name + ".json");
    std::ofstream(file) << physbench::to_json(scene).dump();
    const physbench::RunResult r = physbench::run_worker_job(physbench::scipy_reference("dop853"), file, dir / "r.json",
                                       dir / "r.log", scene.probe_every_steps(), 0.0, 120.0);
    ASSERT_EQ(r.status, physbench::Status::Ok) << scene.name << ": " << r.message;
    ASSERT_EQ(r.trajectory.samples.size(), std::size_t(scene.step_count() /
                                                       scene.probe_every_steps() + 1))
        << scene.name;
    const physbench::Trajectory closed = physbench::analytic_reference(scene, r.trajectory);
    physbench::Scene check = scene;
    check.probe.metrics = {physbench::Metric::Position, physbench::Metric::Orientation};
    const physbench::ErrorSummary e = physbench::summarise(physbench::compare(check, r.trajectory, &closed));
    ASSERT_TRUE(e.position && e.orientation) << scene.name;
    EXPECT_LT(e.position->max, 1e-9) << scene.name;
    EXPECT_LT(e.orientation->max, 1e-9) << scene.name;
  }
}

// rtp's determinism across processes (in-process repeats and threads: validation's Determinism
// tests): the worker's result holds every sample at full precision, so equal files are equal bits
TEST(Runner, RtpStackGivesTheSameBitsInSeparateProcessesAtOneAndTwoThreads) {
  const fs::path dir = fresh_dir("determinism");
  ASSERT_EQ(physbench({"export-scenes", (dir / "scenes").string()}, dir).outcome.exit_code, 0);
  // tower-10 for 1 s of its 10
  std::ifstream in(dir / "scenes" / "tower-10.0.json");
  nlohmann::json scene = nlohmann::json::parse(in);
  scene["duration"] = 1.0;
  std::ofstream(dir / "tower.json") << scene.dump();
  std::vector<nlohmann::json> samples;
  for (const char* variant : {"soft-step", "soft-step", "soft-step-2t", "soft-step-2t"}) {
    const fs::path out = dir / (std::string(variant) + std::to_string(samples.size()) + ".json");
    const Invocation inv = physbench({"worker", "--scene", (dir / "tower.json").string(),
                                      "--engine", "rtp", "--variant", variant, "--budget", "0",
                                      "--out", out.string()},
                                     dir);
    ASSERT_EQ(inv.outcome.exit_code, 0) << inv.output;
    std::ifstream result(out);
    const nlohmann::json doc = nlohmann::json::parse(result);
    ASSERT_EQ(doc.at("status"), "ok") << doc.at("message");
    samples.push_back(doc.at("samples"));
  }
  ASSERT_GT(samples[0].size(), 10u);
  for (std::size_t i = 1; i < samples.size(); ++i) EXPECT_EQ(samples[i], samples[0]) << "run " << i;
}

// each peer adapter gives the same results twice: two worker processes on the same scene, every
// sample compared as the worker writes it (shortest round-trip text of each double, so equal text
// is equal bits); a free scene with springs and a contact scene where every box starts in contact
TEST(Runner, EveryEngineGivesTheSameBitsTwiceInSeparateProcesses) {
  const fs::path dir = fresh_dir("repeatability");
  ASSERT_EQ(physbench({"export-scenes", (dir / "scenes").string()}, dir).outcome.exit_code, 0);
  struct Job {
    std::string engine, variant;
    fs::path host;
    bool contacts_only = false;  // a variant that only applies where bodies touch
  };
  const fs::path bullet64 = fs::path(PHYSBENCH_EXE).parent_path() / "physbench-bullet64";
  const fs::path mujoco4 = fs::path(PHYSBENCH_EXE).parent_path() / "physbench-mujoco4";
  const std::vector<Job> peers = {
#ifdef PHYSBENCH_HAVE_BULLET
      {"bullet", "float", PHYSBENCH_EXE},
      {"bullet", "double", bullet64},
#endif
#ifdef PHYSBENCH_HAVE_ODE
      {"ode", "quickstep", PHYSBENCH_EXE},  // shuffles its rows with ODE's global generator
      {"ode", "step", PHYSBENCH_EXE},
#endif
#ifdef PHYSBENCH_HAVE_BOX2D
      {"box2d", "default", PHYSBENCH_EXE},
#endif
#ifdef PHYSBENCH_HAVE_MUJOCO
      {kMujoco, "euler", PHYSBENCH_EXE},
      {kMujoco, "pgs-10", PHYSBENCH_EXE, true},
#endif
#ifdef PHYSBENCH_MUJOCO4_VERSION
      {"mujoco", "euler", mujoco4},
      {"mujoco", "pgs-10", mujoco4, true},
#endif
  };
  // (scene, seconds of it, rtp's variant for it)
  const std::vector<std::tuple<std::string, double, std::string>> scenes = {
      {"spring-chain", 2.0, "rk4"}, {"overlap-recovery", 1.0, "soft-step"}};
  for (const auto& [name, seconds, rtp_variant] : scenes) {
    std::ifstream in(dir / "scenes" / (name + ".0.json"));
    ASSERT_TRUE(in) << "export-scenes wrote no " << name << ".0.json";
    nlohmann::json scene = nlohmann::json::parse(in);
    scene["duration"] = seconds;
    const fs::path file = dir / (name + ".json");
    std::ofstream(file) << scene.dump();
    std::vector<Job> jobs = {{"rtp", rtp_variant, PHYSBENCH_EXE}};
    jobs.insert(jobs.end(), peers.begin(), peers.end());
    for (const Job& job : jobs) {
      if (job.contacts_only && !scene.value("collisions", true)) continue;
      const std::string what = name + " " + job.engine + "/" + job.variant;
      std::vector<nlohmann::json> docs;
      for (int run = 0; run < 2; ++run) {
        const fs::path out = dir / (name + "." + job.engine + "." + job.variant + "." +
                                    std::to_string(run) + ".json");
        std::vector<std::string> argv = {job.host.string(), "worker", "--scene", file.string(),
                                         "--engine", job.engine, "--variant", job.variant,
                                         "--budget", "0", "--out", out.string()};
        const ChildOutcome outcome = run_child(argv, (dir / "worker.log").string(), 300.0);
        ASSERT_EQ(outcome.kind, ChildOutcome::Kind::Exited) << what << ": " << outcome.describe();
        ASSERT_EQ(outcome.exit_code, 0)
            << what << ": " << tail_of_file((dir / "worker.log").string(), 3);
        std::ifstream result(out);
        docs.push_back(nlohmann::json::parse(result));
      }
      EXPECT_NE(docs[0].at("status"), "unsupported") << what << ": " << docs[0].at("message");
      EXPECT_EQ(docs[0].at("status"), docs[1].at("status")) << what;
      EXPECT_EQ(docs[0].at("message"), docs[1].at("message")) << what;
      ASSERT_GT(docs[0].at("samples").size(), 10u) << what << ": " << docs[0].at("message");
      // text, not values: -0 and 0 differ here as they do in bits
      const std::string first = docs[0].at("samples").dump(), second = docs[1].at("samples").dump();
      EXPECT_TRUE(first == second) << what << ": the two runs differ, first at sample "
                                   << [&] {
                                        const auto& a = docs[0].at("samples");
                                        const auto& b = docs[1].at("samples");
                                        std::size_t k = 0;
                                        while (k < a.size() && k < b.size() &&
                                               a[k].dump() == b[k].dump())
                                          ++k;
                                        return k;
                                      }();
    }
  }
}

// the ';'-separated parts of a numbers cell
std::vector<double> parts_of(const std::string& cell) {
  std::vector<double> parts;
  std::stringstream in(cell);
  for (std::string part; std::getline(in, part, ';');) parts.push_back(std::stod(part));
  return parts;
}

#ifdef PHYSBENCH_HAVE_BULLET
TEST(Runner, RtpContactStepTimesItsStagesWithinItsStepAndAPeerLeavesThemEmpty) {
  const fs::path dir = fresh_dir("stages");
  const Invocation inv =
      physbench({"run", "-s", "tower-10", "-e", "rtp,bullet", "--variant", "soft-step,float",
                 "--duration", "2", "--budget", "0.05", "--out", (dir / "r").string()},
                dir);
  ASSERT_EQ(inv.outcome.exit_code, 0) << inv.output;
  const auto rows = read_rows(dir / "r" / "results.csv");
  const auto* rtp = find_row(rows, "rtp", "soft-step");
  const auto* bullet = find_row(rows, "bullet", "float");
  ASSERT_TRUE(rtp && bullet);
  ASSERT_EQ(rtp->at("status"), "ok") << rtp->at("message");
  std::ifstream meta_file(dir / "r" / "metadata.json");
  const nlohmann::json meta = nlohmann::json::parse(meta_file);
  const auto names = meta["engines"]["rtp"]["stages"].get<std::vector<std::string>>();
  const std::vector<double> stage_ms = parts_of(rtp->at("stage_ms"));
  ASSERT_EQ(stage_ms.size(), names.size()) << rtp->at("stage_ms");
  ASSERT_GE(names.size(), 5u);
  EXPECT_NE(std::find(names.begin(), names.end(), "narrow_phase"), names.end());
  double sum = 0.0;
  for (std::size_t i = 0; i < names.size(); ++i) {
    EXPECT_GE(stage_ms[i], 0.0) << names[i];
    sum += stage_ms[i];
  }
  // the stages come from the same timed repeats as steps/s: together they are most of a step's
  // wall time and never more (plus the 4-digit rounding of both)
  double mean_ms = 0.0;
  const std::vector<double> repeats = parts_of(rtp->at("steps_per_s_repeats"));
  for (double steps_per_s : repeats) mean_ms += 1e3 / steps_per_s / double(repeats.size());
  EXPECT_LE(sum, mean_ms * 1.01 + 1e-4) << rtp->at("stage_ms");
  EXPECT_GE(sum, mean_ms * 0.5) << rtp->at("stage_ms");
  // a peer that does not time its stages has none: empty, never an estimate
  EXPECT_EQ(bullet->at("status"), "ok");
  EXPECT_TRUE(bullet->at("stage_ms").empty()) << bullet->at("stage_ms");
  EXPECT_FALSE(meta["engines"]["bullet"].contains("stages"));
  // contact points per step, by each engine's own count, through the worker: rtp keeps each of
  // the ten resting faces' four corners; Bullet at least a point a face, at most four
  ASSERT_FALSE(rtp->at("contact_points").empty());
  EXPECT_EQ(std::stod(rtp->at("contact_points")), 40.0);
  ASSERT_FALSE(bullet->at("contact_points").empty());
  EXPECT_GE(std::stod(bullet->at("contact_points")), 10.0);
  EXPECT_LE(std::stod(bullet->at("contact_points")), 40.0);
}
#endif

std::string file_text(const fs::path& file) {
  std::ifstream in(file);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

TEST(Runner, IterationSweepIsARowPerValueWithTheSolverSetAndSaysWhereAVariantHasNone) {
  const fs::path dir = fresh_dir("sweep_iterations");
  const Invocation inv = physbench(
      {"run", "-s", "tower-10", "-e", "rtp", "--variant", "sequential-impulse,soft-step",
       "--sweep-iterations", "1,16", "--duration", "2", "--budget", "0", "--all-trajectories", "--out",
       (dir / "r").string()},
      dir);
  ASSERT_EQ(inv.outcome.exit_code, 0) << inv.output;
  const auto rows = read_rows(dir / "r" / "results.csv");
  ASSERT_EQ(rows.size(), 6u) << "two variants, each at its own settings and at 1 and 16";
  std::map<std::string, const std::map<std::string, std::string>*> si, soft;
  for (const auto& r : rows) {
    EXPECT_TRUE(r.at("substeps").empty());
    (r.at("variant") == "soft-step" ? soft : si)[r.at("iterations")] = &r;
  }
  ASSERT_EQ(si.size(), 3u);
  ASSERT_TRUE(si.count("") && si.count("1") && si.count("16"));
  for (const auto& [iterations, r] : si) EXPECT_EQ(r->at("status"), "ok") << iterations;
  // one iteration against sixteen: a different solve, so a different trajectory, in files of
  // their own
  const std::string one = si["1"]->at("trajectory"), sixteen = si["16"]->at("trajectory");
  EXPECT_NE(one, sixteen);
  EXPECT_NE(file_text(dir / "r" / one), file_text(dir / "r" / sixteen));
  EXPECT_GT(std::stod(si["1"]->at("stack_drift_max")), std::stod(si["16"]->at("stack_drift_max")));
  // the soft step has no iteration count: its swept rows say so, and are not faked
  ASSERT_EQ(soft.size(), 3u);
  EXPECT_EQ(soft[""]->at("status"), "ok");
  for (const char* n : {"1", "16"}) {
    EXPECT_EQ(soft[n]->at("status"), "unsupported");
    EXPECT_NE(soft[n]->at("message").find("no iteration count"), std::string::npos);
    EXPECT_TRUE(soft[n]->at("stack_drift_max").empty());
  }
  // the settings table says what the knob maps to, beside the variant's own table
  std::ifstream meta_file(dir / "r" / "metadata.json");
  const nlohmann::json rtp = nlohmann::json::parse(meta_file)["engines"]["rtp"];
  bool stated = false;
  for (const auto& s : rtp["sweeps"]["sequential-impulse"]["iterations-16"])
    stated |= s["name"] == "velocity iterations" && s["value"] == "16";
  EXPECT_TRUE(stated) << rtp.dump(1);
  for (const auto& s : rtp["variants"]["sequential-impulse"])
    if (s["name"] == "velocity iterations") {
      EXPECT_EQ(s["value"], "10");
    }
}

#ifdef PHYSBENCH_HAVE_RTP_BASELINE
TEST(Runner, RtpAtTheBaselineInstructionSetRunsBesideTheBuildsOwn) {
  // physbench-rtp-baseline: the same engine compiled without -march, its default contact variant
  // listed as soft-step-x86-64 (soft-step-baseline off x86). It must load the scene as the main build
  // does (its scene library is compiled again too: Eigen's alignment follows the instruction
  // set), take the swept knobs, and say its instruction set in its settings table
  const fs::path dir = fresh_dir("baseline-isa");
  const std::string baseline = std::string("soft-step") + PHYSBENCH_RTP_ISA_SUFFIX;
  const Invocation inv = physbench({"run", "-s", "tower-10", "-e", "rtp", "--variant",
                                    "soft-step," + baseline, "--duration",
                                    "1", "--budget", "0", "--sweep-substeps", "4", "--out",
                                    (dir / "r").string()},
                                   dir);
  ASSERT_EQ(inv.outcome.exit_code, 0) << inv.output;
  const auto rows = read_rows(dir / "r" / "results.csv");
  std::map<std::string, const std::map<std::string, std::string>*> by;  // variant.substeps
  for (const auto& row : rows) by[row.at("variant") + "." + row.at("substeps")] = &row;
  for (const std::string substeps : {"", "4"}) {
    const auto* own = by[std::string("soft-step.") + substeps];
    const auto* base = by[baseline + "." + substeps];
    ASSERT_TRUE(own && base) << "substeps " << substeps << "\n" << inv.output;
    EXPECT_EQ(base->at("status"), "ok") << base->at("message");
    EXPECT_EQ(base->at("contact_verdict"), own->at("contact_verdict"));
    // the same arithmetic up to fused multiply-adds: the same tower to a millimetre
    EXPECT_NEAR(std::stod(base->at("stack_drift_max")), std::stod(own->at("stack_drift_max")), 1e-3);
  }
  std::ifstream meta_file(dir / "r" / "metadata.json");
  const nlohmann::json rtp = nlohmann::json::parse(meta_file)["engines"]["rtp"];
  ASSERT_TRUE(rtp["variants"].contains(baseline)) << rtp.dump(1);
  const auto& first = rtp["variants"][baseline][0];
  EXPECT_EQ(first["name"], "instruction set");
  EXPECT_NE(first["value"].get<std::string>().find("baseline"), std::string::npos) << first.dump();
}

TEST(Runner, RtpAtBox2dsSettingsRunsAtTheBaselineInstructionSetToo) {
  // soft-step-4 at the baseline instruction set: rtp at Box3D's rules and Box3D's instruction
  // set, the ratio at equal settings and equal ISA. The host must map the name to Box2D v3's
  // settings (4 substeps, one relax pass), not to the default's 8
  const fs::path dir = fresh_dir("baseline-isa-4");
  const std::string baseline = std::string("soft-step-4") + PHYSBENCH_RTP_ISA_SUFFIX;
  const Invocation inv = physbench({"run", "-s", "tower-10", "-e", "rtp", "--variant",
                                    "soft-step-4," + baseline, "--duration", "1", "--budget", "0",
                                    "--no-sweep", "--out", (dir / "r").string()},
                                   dir);
  ASSERT_EQ(inv.outcome.exit_code, 0) << inv.output;
  std::map<std::string, std::map<std::string, std::string>> by;
  for (const auto& row : read_rows(dir / "r" / "results.csv")) by[row.at("variant")] = row;
  ASSERT_TRUE(by.count("soft-step-4") && by.count(baseline)) << inv.output;
  EXPECT_EQ(by[baseline].at("status"), "ok") << by[baseline].at("message");
  EXPECT_EQ(by[baseline].at("contact_verdict"), by["soft-step-4"].at("contact_verdict"));
  EXPECT_NEAR(std::stod(by[baseline].at("stack_drift_max")),
              std::stod(by["soft-step-4"].at("stack_drift_max")), 1e-3);
  std::ifstream meta_file(dir / "r" / "metadata.json");
  const nlohmann::json variants = nlohmann::json::parse(meta_file)["engines"]["rtp"]["variants"];
  ASSERT_TRUE(variants.contains(baseline)) << variants.dump(1);
  auto setting = [&](const std::string& variant, const std::string& name) {
    for (const auto& s : variants[variant])
      if (s["name"] == name) return s["value"].get<std::string>();
    return std::string("(none)");
  };
  EXPECT_EQ(setting(baseline, "substeps"), "4");
  EXPECT_EQ(setting(baseline, "relax iterations"), "1");
  EXPECT_NE(setting(baseline, "instruction set").find("baseline"), std::string::npos);
}
#endif

#ifdef PHYSBENCH_WORKERS_BUILT
// the peers that compile from source here run a native-instruction-set build beside their generic
// one (workers/catalog.tsv): Rapier for this machine's CPU, Box2D v3 with its AVX2 path. Each is the
// same engine at the same settings, so it holds the tower as the generic build does, and its
// settings table says which instruction set it was compiled for
TEST(Runner, ThePeersNativeBuildsRunBesideTheirGenericOnes) {
  const fs::path dir = fresh_dir("peers-native");
  const Invocation inv = physbench({"run", "-s", "tower-10", "-e", "rapier,box2d-v3", "--variant",
                                    "default,default-native,default-avx2", "--duration", "1",
                                    "--budget", "0", "--no-sweep", "--out", (dir / "r").string()},
                                   dir);
  ASSERT_EQ(inv.outcome.exit_code, 0) << inv.output;
  std::map<std::string, std::map<std::string, std::string>> by;  // engine/variant
  for (const auto& row : read_rows(dir / "r" / "results.csv"))
    by[row.at("engine") + "/" + row.at("variant")] = row;
  std::ifstream meta_file(dir / "r" / "metadata.json");
  const nlohmann::json engines = nlohmann::json::parse(meta_file)["engines"];
  for (const auto& [engine, native, says] :
       {std::tuple{"rapier", "default-native", "target-cpu=native"},
        std::tuple{"box2d-v3", "default-avx2", "AVX2"}}) {
    const std::string generic = std::string(engine) + "/default", built = std::string(engine) + "/" + native;
    ASSERT_TRUE(by.count(generic) && by.count(built)) << inv.output;
    EXPECT_EQ(by[built].at("status"), "ok") << by[built].at("message");
    EXPECT_EQ(by[built].at("contact_verdict"), by[generic].at("contact_verdict"));
    EXPECT_NEAR(std::stod(by[built].at("stack_drift_max")), std::stod(by[generic].at("stack_drift_max")), 1e-3);
    const auto instruction_set = [&](const char* variant) {
      for (const auto& row : engines[engine]["variants"][variant])
        if (row["name"] == "instruction set") return row["value"].get<std::string>();
      return std::string("(no instruction set row)");
    };
    EXPECT_NE(instruction_set(native).find(says), std::string::npos) << instruction_set(native);
    EXPECT_EQ(instruction_set("default").find(says), std::string::npos) << instruction_set("default");
  }
}
#endif

#ifdef PHYSBENCH_HAVE_BULLET
// a swept substep count reaches a peer: Bullet at four steps of dt/4 a frame holds the 10-box
// tower its single step lets drift half a metre, and its settings table says what ran; an
// external worker (Jolt, where cargo built it) is given the knob too and answers with its own
TEST(Runner, SubstepSweepReachesThePeersAndTheirSettingsSayHow) {
  const fs::path dir = fresh_dir("sweep_substeps");
  const Invocation inv = physbench(
      {"run", "-s", "tower-10", "-e", "bullet,jolt", "--variant", "float,default",
       "--sweep-substeps", "1,4", "--no-sweep", "--budget", "0", "--out", (dir / "r").string()},
      dir);
  ASSERT_EQ(inv.outcome.exit_code, 0) << inv.output;
  const auto rows = read_rows(dir / "r" / "results.csv");
  auto row = [&](const std::string& engine, const std::string& substeps) {
    for (const auto& r : rows)
      if (r.at("engine") == engine && r.at("substeps") == substeps) return &r;
    return static_cast<const std::map<std::string, std::string>*>(nullptr);
  };
  const auto *one = row("bullet", "1"), *four = row("bullet", "4");
  ASSERT_TRUE(one && four);
  ASSERT_EQ(one->at("status"), "ok") << one->at("message");
  ASSERT_EQ(four->at("status"), "ok") << four->at("message");
  EXPECT_GT(std::stod(one->at("stack_drift_max")), 0.1);
  EXPECT_LT(std::stod(four->at("stack_drift_max")), 0.5 * std::stod(one->at("stack_drift_max")));
  // a solve a substep: the engine's own count of points a solve stays a tower's, not four times it
  EXPECT_LT(std::stod(four->at("contact_points")), 1.5 * std::stod(one->at("contact_points")));
  std::ifstream meta_file(dir / "r" / "metadata.json");
  const nlohmann::json meta = nlohmann::json::parse(meta_file);
  bool stated = false;
  for (const auto& s : meta["engines"]["bullet"]["sweeps"]["float"]["substeps-4"])
    stated |= s["name"] == "substeps" &&
              s["why"].get<std::string>().find("stepSimulation(dt/N, 0)") != std::string::npos;
  EXPECT_TRUE(stated) << meta["engines"]["bullet"].dump(1);
  // Jolt, when its worker was built: the knob runs (a row of its own, not `unsupported`) and holds
  // the tower closer than one collision step does
  const auto *jolt_one = row("jolt", "1"), *jolt_four = row("jolt", "4");
  if (jolt_one && jolt_four && jolt_one->at("status") == "ok") {
    ASSERT_EQ(jolt_four->at("status"), "ok") << jolt_four->at("message");
    EXPECT_LT(std::stod(jolt_four->at("stack_drift_max")),
              std::stod(jolt_one->at("stack_drift_max")));
  }
}
#endif

TEST(Runner, BadSweepValueIsRefusedNamingTheOptionAndWritesNothing) {
  const fs::path dir = fresh_dir("bad_sweep");
  for (const auto& [option, value] : std::vector<std::pair<std::string, std::string>>{
           {"--sweep-iterations", "0"},
           {"--sweep-iterations", "-4"},
           {"--sweep-iterations", "many"},
           {"--sweep-iterations", "4,,8"},
           {"--sweep-substeps", "2.5"},
           {"--sweep-substeps", "0"}}) {
    const Invocation inv = physbench({"run", "-s", "tower-10", "-e", "rtp", option, value,
                                      "--out", (dir / "r").string()},
                                     dir);
    EXPECT_EQ(inv.outcome.exit_code, 2) << option << " " << value << ": " << inv.output;
    EXPECT_NE(inv.output.find(option + " " + value + ":"), std::string::npos) << inv.output;
    EXPECT_FALSE(fs::exists(dir / "r")) << option << " " << value;
  }
}

TEST(Runner, UnknownEngineIsAClearErrorAndWritesNothing) {
  const fs::path dir = fresh_dir("unknown_engine");
  const Invocation inv = physbench({"run", "-e", "havok", "--out", (dir / "r").string()}, dir);
  EXPECT_EQ(inv.outcome.exit_code, 2);
  EXPECT_NE(inv.output.find("unknown engine 'havok'"), std::string::npos) << inv.output;
  EXPECT_NE(inv.output.find("rtp"), std::string::npos) << "the error lists the engines there are";
  EXPECT_FALSE(fs::exists(dir / "r"));
}

TEST(Runner, MalformedSceneFileNamesTheFieldAndWritesNothing) {
  const fs::path dir = fresh_dir("malformed");
  std::ofstream(dir / "bad.json") << R"({"name": "bad", "dt": 0.01, "duration": 1,
    "bodies": [{"shape": {"type": "box", "half_extents": [1, 1, 1]}, "mass": "heavy"}]})";
  const Invocation inv = physbench(
      {"run", "--scene", (dir / "bad.json").string(), "--out", (dir / "r").string()}, dir);
  EXPECT_EQ(inv.outcome.exit_code, 2);
  EXPECT_NE(inv.output.find("bad.json: bodies[0].mass: expected a number"), std::string::npos)
      << inv.output;
  EXPECT_FALSE(fs::exists(dir / "r" / "results.csv"));
}

TEST(Runner, SceneFileRunsTheSameAsTheBuiltInScenario) {
  // a scene written out by one run and read back by another gives the same trajectory
  const fs::path dir = fresh_dir("scene_file");
  ASSERT_EQ(physbench({"run", "-s", "tumbling-box", "--no-sweep", "-e", "rtp", "--variant", "rk4",
                       "--budget", "0", "--out", (dir / "a").string()},
                      dir)
                .outcome.exit_code,
            0);
  ASSERT_EQ(
      physbench({"run", "--scene", (dir / "a" / "scenes" / "tumbling-box.json").string(), "-e",
                 "rtp", "--variant", "rk4", "--budget", "0", "--out", (dir / "b").string()},
                dir)
          .outcome.exit_code,
      0);
  const auto a = read_rows(dir / "a" / "results.csv"), b = read_rows(dir / "b" / "results.csv");
  ASSERT_EQ(a.size(), 1u);
  ASSERT_EQ(b.size(), 1u);
  EXPECT_EQ(a[0].at("orientation_err_max"), b[0].at("orientation_err_max"));
  EXPECT_EQ(a[0].at("energy_drift_max"), b[0].at("energy_drift_max"));
}

TEST(Runner, DtSweepGivesARowPerStepAndRk4ConvergesAtFourthOrder) {
  const fs::path dir = fresh_dir("sweep");
  const Invocation inv =
      physbench({"run", "-s", "spring-oscillator", "-e", "rtp", "--variant", "rk4", "--sweep-hz",
                 "60,120,240", "--budget", "0", "--out", (dir / "r").string()},
                dir);
  ASSERT_EQ(inv.outcome.exit_code, 0) << inv.output;
  auto rows = read_rows(dir / "r" / "results.csv");
  ASSERT_EQ(rows.size(), 3u);
  std::sort(rows.begin(), rows.end(), [](const auto& a, const auto& b) {
    return std::stod(a.at("dt")) > std::stod(b.at("dt"));
  });
  // each halving of dt divides RK4's error by about 2⁴
  for (std::size_t i = 0; i + 1 < rows.size(); ++i) {
    const double ratio =
        std::stod(rows[i].at("position_err_max")) / std::stod(rows[i + 1].at("position_err_max"));
    EXPECT_GT(ratio, 12.0) << "dt " << rows[i].at("dt");
    EXPECT_LT(ratio, 20.0) << "dt " << rows[i].at("dt");
  }
  for (const char* tag : {"60hz", "120hz", "240hz"})
    EXPECT_TRUE(
        fs::exists(dir / "r" / "scenes" / ("spring-oscillator.dt-" + std::string(tag) + ".json")));
}

}  // namespace
