// The run's last stage: one writer that owns the results folder — results.csv's rows, the
// trajectories, the replay viewer's poses, the scene files and metadata.json — and the rename
// that makes results.csv appear only when the run is complete (docs/architecture.md, "A run").
#pragma once

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "physbench/evaluate.h"
#include "physbench/plan.h"

namespace physbench {

class ResultsFolder {
 public:
  // RunError when the folder exists and holds files: an earlier run is never written into
  static void refuse_used(const std::filesystem::path& out);

  // makes the folder with results.csv.partial (its header) and the metadata known before any
  // job: machine, build, timing, the plan and this shard's share of it
  ResultsFolder(const std::filesystem::path& out, const Plan& plan, const RunOptions& options,
                std::size_t jobs_in_shard);

  const std::filesystem::path& root() const { return out_; }
  // the jobs' scratch (their result files and logs), removed when the run ends
  const std::filesystem::path& work() const { return work_; }

  // scenes/<stem>.json: the exact scene a job (or a reference run) reads
  std::filesystem::path write_scene(const std::string& stem, const Scene& scene);
  // metadata.json's scenarios.<name>: what the scene asks and the steps it runs at
  void describe_scenario(const PlannedScene& planned);
  // the scene step's file and reference, under its scenario
  void record_step(const PlannedScene& planned, double dt, const std::filesystem::path& scene_file,
                   const ReferenceRun& reference);

  // the engine's version and settings table, the trajectory and (at the scene's own step) poses
  // under the job's file stem, then the row, checked against the schema (RunError names the
  // column) and flushed, so an interrupted run keeps every finished row
  void add(EvaluatedJob& job, const std::string& stem, bool own_step, std::size_t job_number);
  std::size_t rows_written() const { return rows_written_; }

  // one timing round of one job (docs/metrics.md, "Interleaved timing"): timing_rounds.csv's row
  // of the scene step, the job's engine, variant and knobs, the round (from 1), the job's place
  // in that round's order (from 1), its timed repeats and their median's seconds per step
  struct Round {
    std::string scenario, engine, variant;
    double dt = 0.0;
    SolverKnobs knobs;
    int round = 0, order = 0, repeats = 0;
    double seconds_per_step = 0.0;
  };
  void add_round(const Round& round);

  // results.csv and metadata.json (with wall_time, where the run's time went) renamed into
  // place: the run is complete
  void finish(const nlohmann::json& wall_time = nullptr);
  // the run stops at job `done` of `total`: results.csv.partial keeps the rows so far, an
  // INCOMPLETE file says why, and no results.csv appears
  void mark_interrupted(int signal, std::size_t done, std::size_t total);
  void mark_stopped(const std::string& why, std::size_t done, std::size_t total);

 private:
  void write_poses(const EvaluatedJob& job, const std::string& stem);

  std::filesystem::path out_, work_;
  std::ofstream csv_, rounds_;
  nlohmann::json metadata_;
  std::uint64_t pose_bytes_ = 0;
  bool all_trajectories_ = false;  // --all-trajectories: every row's, every probed body's
  std::size_t rows_written_ = 0;
};

}  // namespace physbench
