// Run a job in a child process so that a crash or a hang in an engine is a row, not the end.
#pragma once

#include <string>
#include <vector>

namespace physbench {

struct ChildOutcome {
  // Interrupted: the runner itself got SIGINT or SIGTERM, and killed the child's group
  enum class Kind { Exited, Signalled, TimedOut, FailedToStart, Interrupted } kind = Kind::Exited;
  int exit_code = 0;  // Exited
  int signal = 0;     // Signalled
  double wall_seconds = 0.0;
  std::string describe() const;  // "exit code 3", "killed by SIGSEGV", "timed out after 12 s"
};

// Runs argv[0] with argv, its stdout and stderr appended to log_path; kills it (SIGKILL, whole
// process group) once timeout_seconds have passed, or as soon as this process is interrupted
// (install_interrupt_handlers). The child also gets SIGKILL should this process die first.
ChildOutcome run_child(const std::vector<std::string>& argv, const std::string& log_path,
                       double timeout_seconds);

// SIGINT and SIGTERM set a flag instead of ending this process, so that run_child can kill the
// running child's process group (it does not share the terminal's group, so Ctrl-C never reaches
// it) and the caller can leave its output marked incomplete. interrupt_signal() is the signal
// received, 0 while none has been.
void install_interrupt_handlers();
int interrupt_signal();

// the last lines of a text file, for error messages
std::string tail_of_file(const std::string& path, int lines);

}  // namespace physbench
