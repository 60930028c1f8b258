// Ctrl-C and SIGTERM on `physbench run`: the running worker (in its own process group, so the
// terminal's signal never reaches it) is killed, the partial folder is marked incomplete, and an
// earlier run's folder is never written into.
#include <gtest/gtest.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>
#include <vector>

namespace {

namespace fs = std::filesystem;

std::string read_text(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// pids whose parent is `parent`, from /proc
std::vector<pid_t> children_of(pid_t parent) {
  std::vector<pid_t> found;
  for (const auto& entry : fs::directory_iterator("/proc")) {
    const std::string name = entry.path().filename();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::istringstream stat(read_text(entry.path() / "stat"));
    std::string pid, comm, state;
    long ppid = 0;
    // comm is in parentheses and may hold spaces; ours does not
    stat >> pid >> comm >> state >> ppid;
    if (ppid == parent) found.push_back(static_cast<pid_t>(std::stol(pid)));
  }
  return found;
}

// alive means running or sleeping: a zombie (exited, not yet reaped) holds no memory
bool alive(pid_t pid) {
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  if (!stat) return false;
  std::string p, comm, state;
  stat >> p >> comm >> state;
  return state != "Z" && state != "X";
}

pid_t spawn(const std::vector<std::string>& args, const fs::path& log) {
  const pid_t pid = fork();
  if (pid == 0) {
    std::vector<char*> argv;
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(fd, 1);
    dup2(fd, 2);
    execv(argv[0], argv.data());
    _exit(127);
  }
  return pid;
}

class Interrupt : public ::testing::TestWithParam<int> {};

TEST_P(Interrupt, KillsTheWorkerAndMarksTheRunIncomplete) {
  const int signal = GetParam();
  // orphans come to this process, so a worker left behind is seen (and reaped) here
  ASSERT_EQ(prctl(PR_SET_CHILD_SUBREAPER, 1), 0);
  const std::string name = std::to_string(signal) + "_" + std::to_string(getpid());
  const fs::path dir = fs::temp_directory_path() / ("physbench_test_interrupt_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);

  // an earlier, complete run
  const pid_t earlier = spawn({PHYSBENCH_EXE, "run", "-s", "projectile", "-e", "rtp", "--variant",
                               "euler", "--no-sweep", "--budget", "0", "--out",
                               (dir / "earlier").string()},
                              dir / "earlier.log");
  int status = 0;
  ASSERT_EQ(waitpid(earlier, &status, 0), earlier);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << read_text(dir / "earlier.log");
  const std::string earlier_csv = read_text(dir / "earlier" / "results.csv");
  ASSERT_FALSE(earlier_csv.empty());

  // one free box for 10^8 steps: minutes of work for the worker
  std::ofstream(dir / "long.json") << R"({"version": 1, "name": "long-free-box", "dt": 1e-6,
    "duration": 100, "collisions": false, "gravity": [0, 0, 0],
    "bodies": [{"shape": {"type": "box", "half_extents": [0.5, 0.5, 0.5]}, "mass": 1,
                "angular_velocity": [0.1, 1, 0]}],
    "probe": {"interval": 1, "metrics": ["energy"]}})";
  const pid_t runner =
      spawn({PHYSBENCH_EXE, "run", "--scene", (dir / "long.json").string(), "-e", "rtp",
             "--variant", "euler,rk4", "--budget", "0", "--timeout", "600", "--out",
             (dir / "r").string()},
            dir / "run.log");
  // the worker, not the runner's other short-lived children (git through popen)
  std::vector<pid_t> workers;
  for (int i = 0; i < 3000 && workers.empty(); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
    for (pid_t p : children_of(runner))
      if (read_text("/proc/" + std::to_string(p) + "/cmdline").find("worker") != std::string::npos)
        workers.push_back(p);
  }
  ASSERT_FALSE(workers.empty()) << "no worker started: " << read_text(dir / "run.log");
  std::this_thread::sleep_for(std::chrono::milliseconds(200));  // well inside the job
  ASSERT_TRUE(alive(workers[0]));
  ASSERT_EQ(kill(runner, signal), 0);
  ASSERT_EQ(waitpid(runner, &status, 0), runner);
  // the runner ends as the signal would have ended it
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == signal) << read_text(dir / "run.log");

  for (pid_t w : workers) {
    // an orphaned worker would have come to us: reap it if it is a zombie, fail if it runs
    waitpid(w, nullptr, WNOHANG);
    EXPECT_FALSE(alive(w)) << "worker " << w << " survived the runner";
    if (alive(w)) kill(-w, SIGKILL), waitpid(w, nullptr, 0);
  }
  for (pid_t p : children_of(getpid())) EXPECT_FALSE(alive(p)) << "process " << p << " left behind";

  EXPECT_FALSE(fs::exists(dir / "r" / "results.csv"));
  EXPECT_FALSE(fs::exists(dir / "r" / "metadata.json"));
  EXPECT_TRUE(fs::exists(dir / "r" / "results.csv.partial"));
  const std::string note = read_text(dir / "r" / "INCOMPLETE");
  EXPECT_NE(note.find("interrupted by signal " + std::to_string(signal)), std::string::npos)
      << note;
  EXPECT_NE(read_text(dir / "r" / "metadata.json.partial").find("\"interrupted\""),
            std::string::npos);
  EXPECT_EQ(read_text(dir / "earlier" / "results.csv"), earlier_csv);

  // and a run pointed at the earlier folder refuses it, leaving it as it was
  const pid_t reuse = spawn({PHYSBENCH_EXE, "run", "-s", "projectile", "-e", "rtp", "--variant",
                             "euler", "--no-sweep", "--budget", "0", "--out",
                             (dir / "earlier").string()},
                            dir / "reuse.log");
  ASSERT_EQ(waitpid(reuse, &status, 0), reuse);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 2);
  EXPECT_NE(read_text(dir / "reuse.log").find("already holds files"), std::string::npos)
      << read_text(dir / "reuse.log");
  EXPECT_EQ(read_text(dir / "earlier" / "results.csv"), earlier_csv);
  prctl(PR_SET_CHILD_SUBREAPER, 0);
}

// an external worker (a catalog line, docs/worker-protocol.md) runs through the same process
// machinery: the runner's signal kills its whole group, grandchildren too
TEST(Signals, InterruptKillsAnExternalWorkersGroup) {
  ASSERT_EQ(prctl(PR_SET_CHILD_SUBREAPER, 1), 0);
  const fs::path dir = fs::temp_directory_path() /
                       ("physbench_test_interrupt_external_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path script = dir / "stand-in-worker.sh";
  std::ofstream(script) << "#!/bin/sh\nsleep 600\n";
  fs::permissions(script, fs::perms::owner_all);
  std::ofstream(dir / "catalog.tsv") << "stand-in\tdefault\t" << script.string() << "\n";
  setenv("PHYSBENCH_WORKER_CATALOG", (dir / "catalog.tsv").c_str(), 1);
  const pid_t runner = spawn({PHYSBENCH_EXE, "run", "-s", "projectile", "-e", "stand-in",
                              "--no-sweep", "--budget", "0", "--timeout", "600", "--out",
                              (dir / "r").string()},
                             dir / "run.log");
  unsetenv("PHYSBENCH_WORKER_CATALOG");
  std::vector<pid_t> workers;
  for (int i = 0; i < 3000 && workers.empty(); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
    for (pid_t p : children_of(runner))
      if (read_text("/proc/" + std::to_string(p) + "/cmdline").find("stand-in-worker") !=
          std::string::npos)
        workers.push_back(p);
  }
  ASSERT_FALSE(workers.empty()) << "no worker started: " << read_text(dir / "run.log");
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  ASSERT_EQ(kill(runner, SIGINT), 0);
  int status = 0;
  ASSERT_EQ(waitpid(runner, &status, 0), runner);
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGINT) << read_text(dir / "run.log");
  // the worker and its sleep (a grandchild, which would come to this subreaper) are gone
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  for (pid_t w : workers) waitpid(w, nullptr, WNOHANG);
  for (pid_t p : children_of(getpid())) {
    waitpid(p, nullptr, WNOHANG);
    EXPECT_FALSE(alive(p)) << "process " << p << " left behind";
    if (alive(p)) kill(p, SIGKILL), waitpid(p, nullptr, 0);
  }
  EXPECT_TRUE(fs::exists(dir / "r" / "INCOMPLETE"));
  EXPECT_FALSE(fs::exists(dir / "r" / "results.csv"));
  prctl(PR_SET_CHILD_SUBREAPER, 0);
}

INSTANTIATE_TEST_SUITE_P(Signals, Interrupt, ::testing::Values(SIGINT, SIGTERM),
                         [](const auto& info) { return info.param == SIGINT ? "SIGINT" : "SIGTERM"; });

}  // namespace
