// The run's third stage: a finished job (its RunResult) judged against its scene's reference
// into one results row, typed against harness/results-schema.json as it is filled.
#pragma once

#include <cmath>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "physbench/metrics.h"
#include "physbench/plan.h"
#include "physbench/simulate.h"

namespace physbench {

// One row of results.csv. Each setter names a column of the schema and writes it the way its
// type is written (a setter of the wrong kind, or a column the schema lacks, is a RunError at
// once: a defect of physbench, found where it is made).
class ResultRow {
 public:
  void text(std::string_view column, std::string value);  // a string or status column
  void number(std::string_view column, double value);     // 9 digits; NaN: empty
  void exact(std::string_view column, double value);      // every bit (dt: rows are matched by it)
  void integer(std::string_view column, long long value);
  // ';'-separated, each to `digits` significant digits; a NaN part is empty
  void numbers(std::string_view column, const std::vector<double>& values, int digits = 9);

  // the cell as written, empty when unset
  const std::string& operator[](std::string_view column) const;
  const std::map<std::string, std::string>& cells() const { return cells_; }

 private:
  void set(std::string_view column, std::string_view kinds, std::string value);
  std::map<std::string, std::string> cells_;
};

// the reference a scene step's rows compare with (a converged one is two jobs of its own)
struct ReferenceRun {
  bool available = false;
  // converged, not available: the failed run's status ("timeout", "error", …) and why
  std::string failed_status;
  std::string failure;
  Trajectory trajectory;             // converged: the dt/divisor run
  double self_error = std::nan("");  // converged: difference to the dt/(2·divisor) run
};

// a finished job, evaluated: its row, and what the folder writes beside it
struct EvaluatedJob {
  ResultRow row;
  Status status = Status::Ok;
  std::string engine_version;
  std::vector<Setting> settings;
  std::vector<std::string> stage_names;  // the engine's timed stages, in stage_ms's order
  SolverKnobs knobs;                      // a sweep's; none: the variant's own settings
  // the metrics were computed: the trajectory (and at the scene's own step the poses) are written
  bool measured = false;
  const Scene* scene = nullptr;  // as it ran (outlives the job)
  Trajectory trajectory;
  ErrorSeries series;
  Trajectory closed_form;                   // the analytic reference, when the scene has one
  bool against_closed_form = false;
  const Trajectory* against_run = nullptr;  // else the converged reference, when it ran
  const Trajectory* against() const {
    return against_closed_form ? &closed_form : against_run;
  }
};

// The row of a job that ran (any status but not-applicable): what the scene is, the speed of its
// timed repeats, and the error metrics its scene asks for against the reference (the analytic
// one, or the converged run when it is available). A finished run whose energy more than doubled
// becomes `diverged`. Metrics that fail to compute leave their columns empty and say why in the
// message. Writes no file.
EvaluatedJob evaluate_job(const PlannedScene& planned, const Scene& scene, const EngineVariant& ev,
                          const SolverKnobs& knobs, RunResult result,
                          const ReferenceRun& reference);

}  // namespace physbench
