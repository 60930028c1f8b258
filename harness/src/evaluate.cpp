#include "physbench/evaluate.h"

#include <algorithm>
#include <iomanip>
#include <optional>
#include <sstream>

#include "text.h"

namespace physbench {

namespace {

// a finished run whose energy in play grew by more than this fraction reads `diverged`
constexpr double kDivergedEnergyGrowth = 1.0;


// the speed columns from the timed repeats
void put_speed(ResultRow& row, const Scene& scene, const RunResult& r, int dynamic_bodies) {
  const double wall = median(r.wall_seconds);
  const double steps = static_cast<double>(r.steps);
  const auto [lo, hi] = std::minmax_element(r.wall_seconds.begin(), r.wall_seconds.end());
  row.integer("repeats", static_cast<long long>(r.wall_seconds.size()));
  row.number("wall_s_median", wall);
  if (r.status == Status::Exploded) return;  // the run stopped early: its speed is not comparable
  row.number("steps_per_s", steps / wall);
  row.number("steps_per_s_min", steps / *hi);
  row.number("steps_per_s_max", steps / *lo);
  // every repeat, for `physbench compare`'s rank test (docs/regression.md), to four digits: a
  // nightly history keeps them for years
  std::vector<double> repeats;
  for (double seconds : r.wall_seconds) repeats.push_back(steps / seconds);
  row.numbers("steps_per_s_repeats", repeats, 4);
  row.number("body_steps_per_s", steps * dynamic_bodies / wall);
  // simulated time over wall time (a run stopped at the run cap simulated only its steps)
  row.number("realtime_factor",
             (r.status == Status::Timeout ? steps * scene.dt : scene.duration) / wall);
  // where a step's time went, by the engine's own stages, averaged over the same repeats
  if (!r.stages.names.empty() && r.stages.steps > 0) {
    std::vector<double> ms_per_step;
    for (double seconds : r.stages.seconds)
      ms_per_step.push_back(1e3 * seconds / static_cast<double>(r.stages.steps));
    row.numbers("stage_ms", ms_per_step, 4);
  }
  // the engine's own count of the contact points it solved, per step of the first run
  if (r.contacts.steps > 0)
    row.number("contact_points", r.contacts.points / static_cast<double>(r.contacts.steps));
}

// the error metrics the scene asks for; the job's status becomes diverged when its energy more
// than doubled
void put_metrics(EvaluatedJob& job, const Scene& scene, const ReferenceRun& reference,
                 std::string& message) {
  ResultRow& row = job.row;
  if (has_analytic_reference(scene)) {
    job.closed_form = analytic_reference(scene, job.trajectory);
    job.against_closed_form = true;
  } else if (scene.reference.kind == ReferenceKind::Converged) {
    if (reference.available)
      job.against_run = &reference.trajectory;
    else
      append(message, "no position or orientation error: " + reference.failure);
  }
  Scene measured = scene;
  if (!job.against()) {
    // without a reference only the invariants can be judged
    std::erase_if(measured.probe.metrics,
                  [](Metric m) { return m == Metric::Position || m == Metric::Orientation; });
  }
  job.series = compare(measured, job.trajectory, job.against());
  const ErrorSeries& series = job.series;
  const ErrorSummary summary = summarise(series);
  auto put = [&](const std::string& prefix, const std::optional<SeriesSummary>& s,
                 bool with_rms) {
    if (!s) return;
    if (with_rms) row.number(prefix + "_rms", s->rms);
    row.number(prefix + "_max", s->max);
    row.number(prefix + "_final", s->final);
  };
  put("position_err", summary.position, true);
  put("orientation_err", summary.orientation, true);
  put("energy_drift", summary.energy, false);
  if (summary.energy_change_final) row.number("energy_change_final", *summary.energy_change_final);
  row.text("stability", job.status == Status::Exploded ? "exploded" : stability_of(scene, series));
  // a finished run whose energy more than doubled is not a success to skim past; contact scenes
  // are left out: their energy at rest is in joules, not relative
  if (job.status == Status::Ok && !scene.has_contacts() && !series.energy_change.empty()) {
    const double grew = *std::max_element(series.energy_change.begin(), series.energy_change.end());
    if (!(grew <= kDivergedEnergyGrowth)) {
      job.status = Status::Diverged;
      std::ostringstream why;
      why << "energy grew to " << std::setprecision(3) << 1.0 + grew
          << " times the energy in play (over +100 %)";
      message = why.str() + (message.empty() ? "" : "; " + message);
    }
  }
  put("linear_momentum_drift", summary.linear_momentum, false);
  put("angular_momentum_drift", summary.angular_momentum, false);
  put("stack_drift", summary.stack_drift, false);
  put("penetration", summary.penetration, false);
  // the contact scene's own question; an empty value could not be computed
  const ContactSummary contact = contact_summary(scene, job.trajectory, series);
  auto put_value = [&](const char* key, const std::optional<double>& v) {
    if (v) row.number(key, *v);
  };
  put_value("top_height_change", contact.top_height_change);
  put_value("drift_in_plane_max", contact.drift_in_plane);
  put_value("drift_out_of_plane_max", contact.drift_out_of_plane);
  put_value("energy_added_max", contact.energy_added_max);
  put_value("speed_max", contact.speed_max);
  put_value("rest_speed_rms", contact.rest_speed_rms);
  row.numbers("apex_rel_err", contact.apex_relative_errors);
  put_value("apex_rel_err_max", contact.apex_relative_error_max);
  put_value("slide_distance", contact.slide_distance);
  put_value("slide_accel", contact.slide_acceleration);
  put_value("slide_accel_expected", contact.slide_acceleration_expected);
  put_value("slide_accel_rel_err", contact.slide_acceleration_error);
  put_value("exchange_err", contact.exchange_error);
  put_value("roll_speed_rel_err", contact.roll_speed_error);
  put_value("roll_time_rel_err", contact.roll_time_error);
  row.text("cradle_answer", contact.cradle_answer);
  if (contact.tunnelled) row.integer("tunnelled", *contact.tunnelled ? 1 : 0);
  if (contact.escaped) row.integer("escaped", *contact.escaped);
  row.text("contact_verdict", contact.verdict);
  if (job.status == Status::Exploded && scene.has_contacts())
    row.text("contact_verdict", "exploded");
  else if (!contact.message.empty())
    append(message, contact.message);
  // a contact scene whose energy can only fall, and rose by more than a share of its energy
  // scale, created energy: diverged on any engine (absolute joules, where the relative change
  // above divides by a resting stack's zero kinetic energy)
  if (job.status == Status::Ok && scene.has_contacts() && contact.energy_added_max &&
      energy_can_only_fall(scene, series)) {
    const double scale = energy_scale(scene);
    if (*contact.energy_added_max > kEnergyGainTolerance * scale) {
      job.status = Status::Diverged;
      std::ostringstream why;
      why << std::setprecision(3) << "energy grew by " << *contact.energy_added_max
          << " J, over " << 100.0 * kEnergyGainTolerance << " % of the scene's energy scale ("
          << scale << " J), where nothing can add energy";
      message = why.str() + (message.empty() ? "" : "; " + message);
    }
  }
}

}  // namespace

EvaluatedJob evaluate_job(const PlannedScene& p, const Scene& scene, const EngineVariant& ev,
                          const SolverKnobs& knobs, RunResult r, const ReferenceRun& reference) {
  EvaluatedJob job;
  job.status = r.status;
  job.engine_version = r.engine_version;
  job.settings = std::move(r.settings);
  job.stage_names = r.stages.names;
  job.scene = &scene;

  int dynamic_bodies = 0;
  for (const BodySpec& b : scene.bodies) dynamic_bodies += b.mass > 0.0;
  // particles count as bodies here: body_steps_per_s is particle-steps/s in a particle scene
  if (scene.particles) dynamic_bodies += static_cast<int>(scene.particles->count);

  ResultRow& row = job.row;
  row.text("scenario", scene.name);
  row.text("engine", ev.engine);
  row.text("variant", ev.variant);
  row.text("engine_version", r.engine_version);
  row.text("family", p.family);
  row.number("parameter", p.parameter);
  row.exact("dt", scene.dt);  // full precision: rows are matched to their scenario's step
  // a swept knob is part of the row's identity, whatever became of the job
  job.knobs = knobs;
  if (knobs.iterations > 0) row.integer("iterations", knobs.iterations);
  if (knobs.substeps > 0) row.integer("substeps", knobs.substeps);
  row.number("duration", scene.duration);
  row.integer("steps", scene.step_count());
  row.integer("bodies", dynamic_bodies);
  row.text("reference", to_string(scene.reference.kind));
  // a converged reference is a job of its own: whether it ran is on every row that needs it
  if (scene.reference.kind == ReferenceKind::Converged)
    row.text("reference_status", reference.available ? "ok" : reference.failed_status);
  row.number("reference_self_error", reference.self_error);
  std::string message = r.message;

  if (r.status == Status::Ok || r.status == Status::Exploded) {
    if (!r.wall_seconds.empty()) put_speed(row, scene, r, dynamic_bodies);
    job.trajectory = std::move(r.trajectory);
    try {
      put_metrics(job, scene, reference, message);
      job.measured = true;
    } catch (const RunError&) {
      throw;
    } catch (const std::exception& e) {
      append(message, std::string("metrics failed: ") + e.what());
    }
  }
  // a run stopped at the run cap (--run-cap): too slow, its speed from the steps it took, no
  // metric from part of a run
  if (r.status == Status::Timeout && !r.wall_seconds.empty()) put_speed(row, scene, r, dynamic_bodies);
  row.text("status", to_string(job.status));
  row.text("message", message);
  return job;
}

}  // namespace physbench
