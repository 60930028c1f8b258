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
  // substep counts the default suite runs every engine variant at besides its own settings (the
  // contact stacks: each engine's best knobs, not only its defaults); `--sweep-substeps` or
  // `--sweep-iterations` replace it, `--no-sweep` drops it
  std::vector<int> sweep_substeps = {};
  std::vector<int> sweep_iterations = {};  // iteration counts, likewise
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

// contact scenes (validation/src/contact_scenarios.cpp): unit boxes (1 m, 1 kg), y up, a static
// ground plane, dt = 1/60, every scene planar (all motion in XY) but rain
Scene tower_scene(int boxes);                 // "tower-N": μ = 0.6, exactly touching, 10 s
Scene pyramid_scene(int base);                // "pyramid-B": B (B + 1) / 2 boxes, μ = 0.6, 10 s
Scene many_pyramids_scene(int per_side, int base);  // Box3D's many_pyramids: per_side² walls of base B
Scene bounce_scene(double restitution);       // "bounce-eE": dropped flat from 1 m, e^(2n) apexes
// "bounce-e1-box", "bounce-e1-sphere": bounce_scene at e = 1 for 20 bounces (18.5 s)
Scene elastic_bounce_scene(ShapeKind shape);
Scene rolling_scene(bool sliding);  // "roll-slide" (5 m/s, no spin), "roll-keep" (rolling 3 m/s)
Scene cradle_scene(int balls);      // "cradle-N": N − 1 touching spheres struck by one, e = 1
Scene offcentre_impact_scene();     // "impact-offcentre": two boxes, an edge on a face, e = 1
Scene incline_scene(double degrees);          // "incline-D": μ = 0.5 on a slope of D degrees
Scene mass_ratio_scene(double ratio);         // "mass-ratio-R": R kg on 1 kg on the ground
Scene overlap_recovery_scene();               // "overlap-recovery": a stack started 5 cm deep
Scene tunnelling_scene(double hz);            // "tunnelling-H": 0.1 m box at 50 m/s, dt = 1/H
Scene head_on_scene();                        // "head-on": e = 1, μ = 0, no gravity
// "rain": 200 tilted 0.5 m boxes falling into a box of four static walls 4 m high, 8 s (3D, not
// planar); planar: "rain-planar", 96 boxes into a trough of two walls 6 m high
Scene rain_scene(bool planar = false);
// the contact scenarios in the default suite, in the order above
std::vector<Scenario> contact_scenarios();

}  // namespace physbench
