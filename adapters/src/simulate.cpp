#include "physbench/simulate.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>

namespace physbench {

namespace {

using Clock = std::chrono::steady_clock;

Sample sample_of(const Engine& engine, const std::vector<int>& bodies, double time) {
  Sample s;
  s.time = time;
  s.bodies.reserve(bodies.size());
  for (int b : bodies) s.bodies.push_back(engine.body_state(b));
  return s;
}

bool finite(const Vec3& v) {
  return std::isfinite(v.x()) && std::isfinite(v.y()) && std::isfinite(v.z());
}

struct Pass {
  double stepping_seconds = 0.0;
  bool exploded = false;
  double explosion_time = 0.0;
  long capped_at = 0;  // steps taken when the run cap stopped the run; 0: it ran to the end
  std::string reason;  // the engine's own, when it reported the explosion itself
};

// one run of the whole scene; the trajectory is kept when asked
// busy-waits until the time since start is (1 + share) times what it was on entry
void stretch(Clock::time_point start, double share) {
  if (share <= 0.0) return;
  const auto until = start + (Clock::now() - start) * (1.0 + share);
  while (Clock::now() < until) {
  }
}

Pass run_once(Engine& engine, const Scene& scene, const std::vector<int>& bodies, int every_steps,
              double explosion_distance, double slowdown, Trajectory* keep, double cap = 0.0) {
  Pass pass;
  const long steps = scene.step_count();
  Sample first = sample_of(engine, bodies, 0.0);
  if (keep) keep->samples.push_back(std::move(first));
  // scheduled impulses by the step they precede
  std::vector<std::pair<long, const ImpulseSpec*>> due;
  for (const ImpulseSpec& p : scene.impulses) due.emplace_back(std::lround(p.time / scene.dt), &p);
  std::stable_sort(due.begin(), due.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  std::size_t next = 0;
  // with a run cap, a run whose first step forecasts over a quarter of the cap is watched step by
  // step (one step of a heavy scene can take seconds); any other at each sample, so a clock read
  // never weighs on a cheap step's timing
  bool watch = cap > 0.0;
  const auto seconds_since = [](Clock::time_point t) {
    return std::chrono::duration<double>(Clock::now() - t).count();
  };
  for (long done = 0; done < steps;) {
    const long chunk = std::min<long>(every_steps, steps - done);
    const auto start = Clock::now();
    long i = 0;  // steps of this chunk taken
    bool over = false;
    try {
      if (next == due.size() && !watch) {
        for (; i < chunk; ++i) engine.step();
      } else {
        for (; i < chunk && !over; ++i) {
          for (; next < due.size() && due[next].first == done + i; ++next)
            engine.apply_impulse(due[next].second->body, due[next].second->impulse,
                                 due[next].second->point);
          engine.step();
          if (watch) {
            const double so_far = pass.stepping_seconds + seconds_since(start);
            if (done == 0 && i == 0) watch = so_far * static_cast<double>(steps) > 0.25 * cap;
            over = so_far >= cap;
          }
        }
      }
    } catch (const EngineExploded& e) {
      // the engine overwrote its own state: nothing sampled after this is the scene's motion
      pass.stepping_seconds += seconds_since(start);
      pass.exploded = true;
      pass.explosion_time = static_cast<double>(done + i + 1) * scene.dt;
      pass.reason = e.what();
      return pass;
    }
    stretch(start, slowdown);
    pass.stepping_seconds += seconds_since(start);
    done += i;
    Sample s = sample_of(engine, bodies, static_cast<double>(done) * scene.dt);
    const bool sane = is_sane(s, explosion_distance);
    if (keep) keep->samples.push_back(std::move(s));
    if (!sane) {
      pass.exploded = true;
      pass.explosion_time = static_cast<double>(done) * scene.dt;
      return pass;
    }
    if (cap > 0.0 && (over || pass.stepping_seconds >= cap) && done < steps) {
      pass.capped_at = done;
      return pass;
    }
  }
  return pass;
}

// adds the engine's stage times of a timed pass to the run's
void add_stages(const Engine& engine, StageTimes& sum) {
  const std::optional<StageTimes> pass = engine.stage_times();
  if (!pass) return;
  if (sum.names.empty()) {
    sum.names = pass->names;
    sum.seconds.assign(pass->names.size(), 0.0);
  }
  for (std::size_t i = 0; i < sum.seconds.size() && i < pass->seconds.size(); ++i)
    sum.seconds[i] += pass->seconds[i];
  sum.steps += pass->steps;
}

}  // namespace

const char* to_string(Status status) {
  switch (status) {
    case Status::Ok:
      return "ok";
    case Status::Unsupported:
      return "unsupported";
    case Status::Exploded:
      return "exploded";
    case Status::Crashed:
      return "crashed";
    case Status::Timeout:
      return "timeout";
    case Status::Error:
      return "error";
    case Status::NotApplicable:
      return "not-applicable";
    case Status::Diverged:
      return "diverged";
  }
  return "?";
}

Status status_from_string(const std::string& name) {
  for (Status s : {Status::Ok, Status::Unsupported, Status::Exploded, Status::Crashed,
                   Status::Timeout, Status::Error, Status::NotApplicable, Status::Diverged})
    if (name == to_string(s)) return s;
  return Status::Error;
}

bool is_sane(const Sample& sample, double explosion_distance) {
  for (const SampledState& b : sample.bodies) {
    if (!finite(b.position) || !finite(b.linear_velocity) || !finite(b.angular_velocity))
      return false;
    if (!std::isfinite(b.orientation.w()) || !finite(b.orientation.vec())) return false;
    if (b.position.norm() > explosion_distance) return false;
  }
  return true;
}

RunResult simulate(const EngineInfo& info, const std::string& variant, const Scene& scene,
                   const SimulateOptions& options) {
  RunResult result;
  result.engine_version = info.version;
  result.settings = info.settings(variant);
  result.steps = scene.step_count();
  result.trajectory.bodies = scene.probed_bodies();
  if (std::find(info.variants.begin(), info.variants.end(), variant) == info.variants.end()) {
    result.status = Status::Error;
    result.message = "engine " + info.name + " has no variant '" + variant + "'";
    return result;
  }
  if (info.applies && !info.applies(scene, variant)) {
    result.status = Status::NotApplicable;
    result.message = "variant " + variant + " does not apply to this scene";
    return result;
  }
  if (auto why = info.unsupported(scene, variant)) {
    result.status = Status::Unsupported;
    result.message = *why;
    return result;
  }
  const int every = options.every_steps > 0 ? options.every_steps : scene.probe_every_steps();
  // every world of the run is built with the sweep's knobs, when there are any
  const auto create = [&] {
    std::unique_ptr<Engine> engine = info.create(variant);
    if (options.knobs.any()) engine->tune(options.knobs);
    return engine;
  };
  if (options.knobs.any()) {
    const Tuning tuning = info.create(variant)->tune(options.knobs);
    if (!tuning.unsupported.empty()) {
      result.status = Status::Unsupported;
      result.message = tuning.unsupported;
      return result;
    }
    // the knobs' rows replace the variant's rows of the same name
    for (const Setting& knob : tuning.settings) {
      auto same = std::find_if(result.settings.begin(), result.settings.end(),
                               [&](const Setting& s) { return s.name == knob.name; });
      if (same != result.settings.end())
        *same = knob;
      else
        result.settings.push_back(knob);
    }
  }

  // first run: the trajectory, and a warm-up for the timed repeats (a timing round has neither)
  if (!options.timing_only) {
    auto engine = create();
    engine->load(scene);
    const Pass pass = run_once(*engine, scene, result.trajectory.bodies, every,
                               options.explosion_distance, options.slowdown, &result.trajectory,
                               options.run_cap_seconds);
    if (const std::optional<ContactCount> contacts = engine->contact_count())
      result.contacts = *contacts;
    if (pass.capped_at > 0) {
      // too slow to finish: its speed from the steps it took, no verdict on a part of the run
      std::ostringstream why;
      why << "too slow: stopped at the run cap after " << pass.capped_at << " of "
          << result.steps << " steps (" << pass.stepping_seconds << " s of stepping, --run-cap "
          << options.run_cap_seconds << " s); its speed is from those steps";
      result.status = Status::Timeout;
      result.message = why.str();
      result.steps = pass.capped_at;
      result.wall_seconds.push_back(pass.stepping_seconds);
      return result;
    }
    if (pass.exploded) {
      std::ostringstream why;
      if (!pass.reason.empty())
        why << pass.reason;
      else
        why << "non-finite or runaway state at t = " << pass.explosion_time << " s";
      result.status = Status::Exploded;
      result.message = why.str();
      result.wall_seconds.push_back(pass.stepping_seconds);
      return result;
    }
    if (pass.stepping_seconds >= options.timing_budget) {
      result.wall_seconds.push_back(pass.stepping_seconds);
      add_stages(*engine, result.stages);
      return result;
    }
  }

  // timed repeats, each on a freshly built world
  double measured = 0.0;
  const int min_repeats = options.timing_only ? 1 : options.min_timed_repeats;
  while (static_cast<int>(result.wall_seconds.size()) < options.max_timed_repeats &&
         (static_cast<int>(result.wall_seconds.size()) < min_repeats ||
          measured < options.timing_budget)) {
    auto engine = create();
    engine->load(scene);
    const Pass pass = run_once(*engine, scene, result.trajectory.bodies, every,
                               options.explosion_distance, options.slowdown, nullptr);
    result.wall_seconds.push_back(pass.stepping_seconds);
    add_stages(*engine, result.stages);
    measured += pass.stepping_seconds;
  }
  return result;
}

}  // namespace physbench
