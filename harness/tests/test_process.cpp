// Job isolation: a child that crashes, hangs or fails is described, never fatal to the runner.
#include <gtest/gtest.h>

#include <filesystem>
#include <unistd.h>

#include "physbench/process.h"
#include "physbench/worker.h"

namespace {

using namespace physbench;

// one log per test: CTest runs tests in parallel
std::string log_file() {
  const std::string name = ::testing::UnitTest::GetInstance()->current_test_info()->name();
  const auto path = std::filesystem::temp_directory_path() /
                    ("physbench_process_" + name + "_" + std::to_string(getpid()) + ".log");
  std::filesystem::remove(path);
  return path.string();
}

TEST(Process, ReportsExitCode) {
  const ChildOutcome o = run_child({"/bin/sh", "-c", "exit 3"}, log_file(), 10.0);
  EXPECT_EQ(o.kind, ChildOutcome::Kind::Exited);
  EXPECT_EQ(o.exit_code, 3);
}

TEST(Process, ReportsACrashBySignal) {
  const ChildOutcome o = run_child({"/bin/sh", "-c", "kill -SEGV $$"}, log_file(), 10.0);
  EXPECT_EQ(o.kind, ChildOutcome::Kind::Signalled);
  EXPECT_EQ(o.signal, SIGSEGV);
  EXPECT_NE(o.describe().find("killed by signal"), std::string::npos);
}

TEST(Process, KillsAHangAtTheTimeout) {
  const ChildOutcome o = run_child({"/bin/sh", "-c", "sleep 30"}, log_file(), 0.3);
  EXPECT_EQ(o.kind, ChildOutcome::Kind::TimedOut);
  EXPECT_LT(o.wall_seconds, 5.0);
}

TEST(Process, ReportsAMissingProgram) {
  const std::string log = log_file();
  const ChildOutcome o = run_child({"/nonexistent/physbench-worker"}, log, 10.0);
  EXPECT_EQ(o.kind, ChildOutcome::Kind::FailedToStart);
  EXPECT_NE(tail_of_file(log, 1).find("cannot run /nonexistent/physbench-worker"),
            std::string::npos);
}

TEST(WorkerResult, JsonRoundTripKeepsStatesAndNan) {
  RunResult r;
  r.status = Status::Exploded;
  r.message = "non-finite";
  r.engine_version = "x";
  r.settings = {{"a", "b", "c"}};
  r.steps = 12;
  r.wall_seconds = {0.5, 0.25};
  r.trajectory.bodies = {0};
  Sample s;
  s.time = 0.125;
  SampledState b;
  b.position = Vec3(1.0 / 3.0, 2, 3);
  b.orientation = Quat(0.5, 0.5, 0.5, 0.5);
  b.linear_velocity = Vec3(std::nan(""), 0, 0);
  b.angular_velocity = Vec3(0, 0, 7);
  s.bodies = {b};
  r.trajectory.samples = {s};
  const RunResult back = result_from_json(nlohmann::json::parse(result_to_json(r).dump()));
  EXPECT_EQ(back.status, Status::Exploded);
  EXPECT_EQ(back.wall_seconds, r.wall_seconds);
  EXPECT_EQ(back.settings[0].why, "c");
  const SampledState& bb = back.trajectory.samples[0].bodies[0];
  EXPECT_EQ(bb.position.x(), 1.0 / 3.0);
  EXPECT_EQ(bb.orientation.coeffs(), b.orientation.coeffs());
  EXPECT_TRUE(std::isnan(bb.linear_velocity.x()));
  EXPECT_EQ(bb.angular_velocity.z(), 7.0);
  // no contact count: none comes back; a count comes back as it went, and a malformed one is
  // refused
  EXPECT_EQ(back.contacts.steps, 0);
  r.contacts = {46.0, 12};
  nlohmann::json doc = result_to_json(r);
  const RunResult counted = result_from_json(nlohmann::json::parse(doc.dump()));
  EXPECT_EQ(counted.contacts.points, 46.0);
  EXPECT_EQ(counted.contacts.steps, 12);
  doc["contacts"]["steps"] = 0;
  EXPECT_THROW(result_from_json(doc), std::runtime_error);
  doc["contacts"] = {{"points", -1.0}, {"steps", 12}};
  EXPECT_THROW(result_from_json(doc), std::runtime_error);
}

}  // namespace
