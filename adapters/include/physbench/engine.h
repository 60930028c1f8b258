// The one adapter interface every engine implements.
//
// An adapter maps the scene's physical meaning onto its engine's conventions (up axis,
// friction and restitution combining, margins, contact buffers) so that the *physical*
// scene is the same everywhere, and states every setting it changes from its engine's
// defaults in settings(): that table is written into the results and shown in the report.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "physbench/scene.h"

namespace physbench {

// a body's state as read back from an engine, in the scene's conventions (velocity form:
// rtp::BodyState, the engine's own, is momentum form)
struct SampledState {
  Vec3 position = Vec3::Zero();          // centre of mass, world (m)
  Quat orientation = Quat::Identity();   // body to world
  Vec3 linear_velocity = Vec3::Zero();   // world (m/s)
  Vec3 angular_velocity = Vec3::Zero();  // world (rad/s)
};

// one non-default engine setting: what, the value, and why the adapter sets it
struct Setting {
  std::string name;
  std::string value;
  std::string why;
};

// a sweep's substeps (--sweep-substeps) as a settings-table line: N steps of dt/N a step, by the
// engine's own knob
inline Setting swept_substeps(int substeps, const std::string& knob) {
  const std::string n = std::to_string(substeps);
  return {"substeps", n + " steps of dt/" + n + " a step",
          "the sweep's value (--sweep-substeps): " + knob};
}

// where the steps' time went, by the engine's own named stages (rtp's StepProfile), summed over
// the steps since load()
struct StageTimes {
  std::vector<std::string> names;
  std::vector<double> seconds;  // per stage, in names' order, summed over `steps` steps (s)
  long steps = 0;
};

// the contact points the engine solved, summed over the steps since load() (each engine's own
// count of the points its contact solver held that step: a manifold's points, ODE's contact joints,
// MuJoCo's contacts)
struct ContactCount {
  double points = 0.0;
  long steps = 0;
};

// an adapter's running sum for Engine::contact_count: started at load() (it counts only a scene
// with contacts and no particles, decided once), points added as the step finds them, a step
// closed after each
class ContactTally {
 public:
  void start(const Scene& scene) {
    counting_ = scene.has_contacts() && !scene.particles;
    sum_ = ContactCount{};
  }
  bool counting() const { return counting_; }
  void add(double points) { sum_.points += points; }
  void end_step() { ++sum_.steps; }
  std::optional<ContactCount> count() const {
    if (!counting_) return std::nullopt;
    return sum_;
  }

 private:
  bool counting_ = false;
  ContactCount sum_;
};

// a sweep's solver knobs (docs/regression.md, "Sweeps over iterations and substeps"); 0 leaves the
// variant's own
struct SolverKnobs {
  int iterations = 0;  // the constraint solver's iterations per step, as the engine counts them
  int substeps = 0;    // substeps per step
  bool any() const { return iterations > 0 || substeps > 0; }
};

// what an engine made of the knobs: the settings rows that say what each maps to (each replaces
// the variant's row of the same name), or why the variant has no such knob
struct Tuning {
  std::vector<Setting> settings;
  std::string unsupported;  // not empty: nothing is set, and the row says this
};

// Thrown by an adapter's step() when its engine reset or overwrote its state on its own (MuJoCo's
// reset after a bad-acceleration warning): the trajectory up to the last sample before it is kept,
// and the row reads `exploded` with this reason. Dropped contacts and clamped motion, which leave
// a trajectory that is not the scene's, are std::runtime_error: an `error` row.
struct EngineExploded : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class Engine {
 public:
  virtual ~Engine() = default;
  // build the world for the scene (already checked with EngineInfo::unsupported)
  virtual void load(const Scene& scene) = 0;
  // advance one fixed step of scene.dt
  virtual void step() = 0;
  virtual SampledState body_state(int body) const = 0;
  // an instantaneous impulse (N s) at a world point on a dynamic body, before the next step
  virtual void apply_impulse(int body, const Vec3& impulse, const Vec3& world_point) = 0;
  // the engine's own timing of its step's stages since load(), for an engine that times them;
  // nothing for one that does not (its results column stays empty: never an estimate)
  virtual std::optional<StageTimes> stage_times() const { return std::nullopt; }
  // the contact points of the steps since load(), for an engine that reports them; nothing for
  // one that does not (its results column stays empty)
  virtual std::optional<ContactCount> contact_count() const { return std::nullopt; }
  // a sweep's knobs, set before load() on the engine's nearest native ones; an adapter without
  // them says so
  virtual Tuning tune(const SolverKnobs&) {
    return {{}, "this adapter maps no solver iterations or substeps"};
  }
};

struct EngineInfo {
  std::string name;                   // "rtp", "bullet", …
  std::vector<std::string> variants;  // the engine's own knobs as names; the first is the default
  std::string version;
  // why the engine cannot model this scene in this variant, or nullopt when it can
  std::function<std::optional<std::string>(const Scene&, const std::string& variant)> unsupported;
  std::function<std::unique_ptr<Engine>(const std::string& variant)> create;
  // false when a variant would not differ from another on this scene (a native-spring variant on
  // a scene without springs): the run makes no row for it. Unset: every variant applies.
  std::function<bool(const Scene&, const std::string& variant)> applies;
  std::function<std::vector<Setting>(const std::string& variant)> settings;
  // an engine for the harness's own tests (test-fault): not listed, and run only when named
  bool test_only = false;
};

// every settings table of info opens with how the engine was built ("instruction set"): the
// instruction set is half of any speed ratio, so each table states it (docs/engines.md, "Equal
// instruction set")
inline void state_instruction_set(EngineInfo& info, std::string value, std::string why) {
  info.settings = [table_of = info.settings, row = Setting{"instruction set", std::move(value),
                                                           std::move(why)}](const std::string& v) {
    std::vector<Setting> table = table_of ? table_of(v) : std::vector<Setting>{};
    table.insert(table.begin(), row);
    return table;
  };
}

}  // namespace physbench
