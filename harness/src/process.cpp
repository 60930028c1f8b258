#include "physbench/process.h"

#include <fcntl.h>
#include <sys/prctl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstring>
#include <deque>
#include <fstream>
#include <sstream>
#include <thread>

namespace physbench {

namespace {
volatile std::sig_atomic_t g_interrupt = 0;
extern "C" void on_interrupt(int signal) { g_interrupt = signal; }
}  // namespace

void install_interrupt_handlers() {
  struct sigaction action {};
  action.sa_handler = on_interrupt;
  sigemptyset(&action.sa_mask);
  action.sa_flags = 0;  // no SA_RESTART: the poll loop's sleep returns early
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

int interrupt_signal() { return g_interrupt; }

std::string ChildOutcome::describe() const {
  std::ostringstream out;
  switch (kind) {
    case Kind::Exited:
      out << "exit code " << exit_code;
      break;
    case Kind::Signalled:
      out << "killed by signal " << signal << " (" << strsignal(signal) << ")";
      break;
    case Kind::TimedOut:
      out << "timed out after " << wall_seconds << " s";
      break;
    case Kind::FailedToStart:
      out << "could not start";
      break;
    case Kind::Interrupted:
      out << "stopped: the runner was interrupted by signal " << signal << " ("
          << strsignal(signal) << ")";
      break;
  }
  return out.str();
}

ChildOutcome run_child(const std::vector<std::string>& argv, const std::string& log_path,
                       double timeout_seconds) {
  using Clock = std::chrono::steady_clock;
  ChildOutcome outcome;
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);

  const auto start = Clock::now();
  if (g_interrupt) {
    outcome.kind = ChildOutcome::Kind::Interrupted;
    outcome.signal = g_interrupt;
    return outcome;
  }
  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid < 0) {
    outcome.kind = ChildOutcome::Kind::FailedToStart;
    return outcome;
  }
  if (pid == 0) {
    // child: own process group (so a timeout kills everything it started), output to the log
    setpgid(0, 0);
    // should the runner die without killing us (SIGKILL, a crash), die with it
    prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (getppid() != parent) _exit(126);
    const int fd = open(log_path.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    if (fd >= 0) {
      dup2(fd, STDOUT_FILENO);
      dup2(fd, STDERR_FILENO);
      close(fd);
    }
    execv(args[0], args.data());
    std::fprintf(stderr, "cannot run %s: %s\n", args[0], std::strerror(errno));
    _exit(127);
  }
  setpgid(pid, pid);

  // poll: a millisecond's sleep is far below any job's length
  int status = 0;
  for (;;) {
    const pid_t done = waitpid(pid, &status, WNOHANG);
    outcome.wall_seconds = std::chrono::duration<double>(Clock::now() - start).count();
    if (done == pid) break;
    if (g_interrupt) {
      kill(-pid, SIGKILL);
      waitpid(pid, &status, 0);
      outcome.kind = ChildOutcome::Kind::Interrupted;
      outcome.signal = g_interrupt;
      return outcome;
    }
    if (outcome.wall_seconds > timeout_seconds) {
      kill(-pid, SIGKILL);
      waitpid(pid, &status, 0);
      outcome.kind = ChildOutcome::Kind::TimedOut;
      return outcome;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(outcome.wall_seconds < 0.1 ? 1 : 10));
  }
  if (WIFSIGNALED(status)) {
    outcome.kind = ChildOutcome::Kind::Signalled;
    outcome.signal = WTERMSIG(status);
  } else {
    outcome.kind =
        WEXITSTATUS(status) == 127 ? ChildOutcome::Kind::FailedToStart : ChildOutcome::Kind::Exited;
    outcome.exit_code = WEXITSTATUS(status);
  }
  return outcome;
}

std::string tail_of_file(const std::string& path, int lines) {
  std::ifstream in(path);
  std::deque<std::string> last;
  for (std::string line; std::getline(in, line);) {
    if (line.empty()) continue;
    last.push_back(line);
    if (static_cast<int>(last.size()) > lines) last.pop_front();
  }
  std::string text;
  for (const std::string& l : last) text += (text.empty() ? "" : " | ") + l;
  return text;
}

}  // namespace physbench
