// Built-in scenarios: parameterised scene generators and the question each answers.
// Tests, benchmarks and reports build their scenes from here, and only from here.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "physbench/scene.h"

namespace physbench {

struct Scenario {
  std::string name;
  std::string question;  // what the scenario answers, for `physbench list` and the report
  std::function<Scene()> build;
  // time steps the default suite sweeps for the speed-against-error picture; empty: only the
  // scene's own
  std::vector<double> sweep_dt = {};
  // scenarios that map one parameter share a family (a stability map's rows)
  std::string family = {};
  std::string parameter_name = {};
  double parameter = 0.0;
};

// 1/30 … 1/960 s: the sweep of the integrator scenarios
std::vector<double> standard_dt_sweep();

const std::vector<Scenario>& scenarios();
const Scenario* find_scenario(const std::string& name);

// the scenes themselves, for callers that want to change a parameter
Scene projectile_scene();
Scene projectile_planar_scene();
Scene tumbling_box_scene();
Scene symmetric_top_scene();
Scene spring_oscillator_scene(double damping = 0.0);
Scene spring_cube_scene();
Scene spring_chain_scene(int links = 8);
Scene stiff_spring_scene(double stiffness);
Scene pushed_box_scene(bool planar = false);
Scene particles_bounce_scene();
Scene particles_orbit_scene();
Scene particles_attractors_scene(long count = 100000);
Scene particles_snow_scene(long count = 100000);
Scene particles_plume_scene(long count = 100000);
// a particle scene in the XY plane (z of every position, velocity and direction dropped, plane
// normals renormalised), marked planar so Box2D can run it; the scene must have no wind jitter
Scene planar_particles(Scene scene);

}  // namespace physbench
