// Run a scene on a linked engine in this process and measure it against its reference.
#pragma once

#include <gtest/gtest.h>

#include "physbench/metrics.h"
#include "physbench/registry.h"

namespace physbench::testing {

struct Measured {
  RunResult run;
  ErrorSummary summary;
};

inline const EngineInfo& engine(const std::string& name) {
  const EngineInfo* info = find_linked_engine(name);
  if (!info) throw std::runtime_error("engine not linked: " + name);
  return *info;
}

// converged: rtp RK4 at dt / divisor, sampled at the run's sample times
inline Trajectory converged_reference(const Scene& scene, int divisor) {
  SimulateOptions options;
  options.every_steps = scene.probe_every_steps() * divisor;
  options.timing_budget = 0.0;
  return simulate(rtp_engine_info(), "rk4", refined(scene, divisor), options).trajectory;
}

// the scene's probed bodies held at their starting poses for the given number of samples, one a
// step: a run that does not move, for testing metrics and verdicts
inline Trajectory held_still(const Scene& scene, int samples) {
  Trajectory t;
  t.bodies = scene.probed_bodies();
  for (int k = 0; k < samples; ++k) {
    Sample s;
    s.time = k * scene.dt;
    for (int b : t.bodies) s.bodies.push_back({scene.bodies[b].position, scene.bodies[b].orientation});
    t.samples.push_back(s);
  }
  return t;
}

inline Measured measure(const std::string& engine_name, const std::string& variant,
                        const Scene& scene) {
  SimulateOptions options;
  options.timing_budget = 0.0;  // tests measure accuracy, never speed
  Measured m;
  m.run = simulate(engine(engine_name), variant, scene, options);
  if (m.run.status != Status::Ok) {
    ADD_FAILURE() << engine_name << "/" << variant << " on " << scene.name << ": "
                  << to_string(m.run.status) << " " << m.run.message;
    return m;
  }
  Trajectory reference;
  if (has_analytic_reference(scene)) reference = analytic_reference(scene, m.run.trajectory);
  if (scene.reference.kind == ReferenceKind::Converged)
    reference = converged_reference(scene, scene.reference.dt_divisor);
  m.summary = summarise(compare(scene, m.run.trajectory, &reference));
  return m;
}

}  // namespace physbench::testing
