// Run a job in a child process so that a crash or a hang in an engine is a row, not the end.
#pragma once

#include <string>
#include <vector>

namespace physbench {

struct ChildOutcome {
  enum class Kind { Exited, Signalled, TimedOut, FailedToStart } kind = Kind::Exited;
  int exit_code = 0;  // Exited
  int signal = 0;     // Signalled
  double wall_seconds = 0.0;
  std::string describe() const;  // "exit code 3", "killed by SIGSEGV", "timed out after 12 s"
};

// Runs argv[0] with argv, its stdout and stderr appended to log_path; kills it (SIGKILL, whole
// process group) once timeout_seconds have passed.
ChildOutcome run_child(const std::vector<std::string>& argv, const std::string& log_path,
                       double timeout_seconds);

// the last lines of a text file, for error messages
std::string tail_of_file(const std::string& path, int lines);

}  // namespace physbench
