// rtp adapter: the scene maps one to one onto rtp's own conventions (y up, world-frame
// angular velocity, a plane as the body's local y = 0 surface, the pair rules √(μa μb) and
// max(ea, eb)), so nothing is converted.
#include <rtp/particles.h>
#include <rtp/world.h>

#include <array>
#include <iterator>
#include <optional>
#include <sstream>

#include "physbench/particle_driver.h"
#include "physbench/registry.h"
#include "physbench/rtp_world.h"

namespace physbench {

namespace {

rtp::Integrator integrator_for(const std::string& variant) {
  if (variant == "euler") return rtp::Integrator::SemiImplicitEuler;
  if (variant == "midpoint") return rtp::Integrator::Midpoint;
  if (variant == "symplectic") return rtp::Integrator::Symplectic;
  return rtp::Integrator::RungeKutta4;
}

rtp::ParticleIntegrator particle_integrator_for(const std::string& variant) {
  if (variant == "euler") return rtp::ParticleIntegrator::SemiImplicitEuler;
  if (variant == "explicit-euler") return rtp::ParticleIntegrator::ExplicitEuler;
  return rtp::ParticleIntegrator::Midpoint;
}

// particle variants run the particle update on this many threads
int threads_for(const std::string& variant) { return variant.ends_with("-2t") ? 2 : 1; }

std::string base_variant(const std::string& variant) {
  return variant.ends_with("-2t") ? variant.substr(0, variant.size() - 3) : variant;
}

// The contact variants: rtp's default soft step, Box2D v3's own soft-step settings (4 substeps,
// 30 Hz, damping ratio 10, one relax pass, 3 m/s push-out), sequential impulses, and the seed's
// lab 5; "soft-step-fresh" is the default with the pair cache, the manifolds' reuse and held
// contacts off (every candidate through the narrow phase, every contact built, every step); "-2t" runs the narrow phase and each colour of
// the solve on two threads
std::optional<rtp::ContactSettings> contact_settings_for(const std::string& variant) {
  const std::string base = base_variant(variant);
  rtp::ContactSettings settings;
  if (base == "soft-step") {
    settings.solver = rtp::ContactSolver::SoftStep;
  } else if (base == "soft-step-fresh") {
    settings.solver = rtp::ContactSolver::SoftStep;
    settings.pair_cache_distance = 0.0;
    settings.manifold_reuse_distance = 0.0;
    settings.contact_hold_distance = 0.0;
    settings.bounds_margin = 0.0;
  } else if (base == "soft-step-4") {
    settings.solver = rtp::ContactSolver::SoftStep;
    settings.substeps = 4;
    settings.contact_hertz = 30.0;
    settings.damping_ratio = 10.0;
    settings.relax_iterations = 1;
    settings.max_relax_iterations = 1;  // Box2D's one pass, never more
    settings.recovery_relax_iterations = 1;
    settings.recovery_position_iterations = 0;  // Box2D pushes out by velocity alone
    settings.max_push_speed = 3.0;
  } else if (base == "sequential-impulse") {
    settings.solver = rtp::ContactSolver::SequentialImpulse;
  } else if (base == "seed") {
    settings.solver = rtp::ContactSolver::Seed;
  } else {
    return std::nullopt;
  }
  settings.threads = threads_for(variant);
  // the scene's meaning: impacts slower than this are inelastic (docs/scene-format.md)
  settings.restitution_threshold = kRestitutionThreshold;
  return settings;
}

bool is_contact_variant(const std::string& variant) {
  return contact_settings_for(variant).has_value();
}

// the stages of rtp's contact step as StepProfile times them (docs/architecture.md, "rtp's step"),
// in the step's order
constexpr const auto& kContactStages = rtp::StepProfile::kStageNames;
constexpr std::size_t kContactStageCount = kContactStages.size();

class RtpEngine final : public Engine {
 public:
  explicit RtpEngine(const std::string& variant)
      : variant_(variant),
        integrator_(integrator_for(base_variant(variant))),
        contacts_(contact_settings_for(variant).value_or(rtp::ContactSettings{})),
        particle_integrator_(particle_integrator_for(base_variant(variant))),
        threads_(threads_for(variant)) {}

  void load(const Scene& scene) override {
    dt_ = scene.dt;
    world_ = std::make_unique<rtp::World>(
        make_rtp_world(scene, integrator_, contacts_));
    body_count_ = static_cast<int>(scene.bodies.size());
    // a world without contacts is one stage (integrate) and a particle system is timed by
    // nobody: only the contact step's profile says where a step's time goes
    profiled_ = world_->has_contacts() && !scene.particles;
    stage_seconds_.fill(0.0);
    profiled_steps_ = 0;
    contact_points_ = 0.0;
    if (scene.particles) {
      rtp::ParticleSystemDef def = particle_system_def(scene);
      def.integrator = particle_integrator_;
      def.threads = threads_;
      particles_ = std::make_unique<rtp::ParticleSystem>(def);
    }
  }

  void step() override {
    if (body_count_ > 0) world_->step(dt_);
    if (particles_) particles_->step(dt_);
    if (profiled_) add_profile(world_->profile());
  }

  // iterations: the sequential-impulse and seed solvers' velocity iterations; substeps: the soft
  // step's. The other way round each has none, nor has an integrator variant
  Tuning tune(const SolverKnobs& knobs) override {
    if (!is_contact_variant(variant_))
      return {{}, "rtp's " + variant_ +
                      " is an integrator without a constraint solver: no iterations or substeps"};
    Tuning tuning;
    const bool soft = contacts_.solver == rtp::ContactSolver::SoftStep;
    if (knobs.iterations > 0) {
      if (soft)
        return {{}, "rtp's soft step solves once per substep (then its relax passes): it has no "
                    "iteration count to sweep; sweep its substeps"};
      contacts_.velocity_iterations = knobs.iterations;
      tuning.settings.push_back(
          {"velocity iterations", std::to_string(knobs.iterations),
           "the sweep's value (--sweep-iterations): ContactSettings::velocity_iterations"});
    }
    if (knobs.substeps > 0) {
      if (!soft)
        return {{}, "rtp's " + variant_ + " solves once per step: it has no substeps"};
      contacts_.substeps = knobs.substeps;
      tuning.settings.push_back({"substeps", std::to_string(knobs.substeps),
                                 "the sweep's value (--sweep-substeps): ContactSettings::substeps"});
    }
    return tuning;
  }

  std::optional<ContactCount> contact_count() const override {
    if (!profiled_) return std::nullopt;
    return ContactCount{contact_points_, profiled_steps_};
  }

  std::optional<StageTimes> stage_times() const override {
    if (!profiled_) return std::nullopt;
    StageTimes times;
    times.names.assign(std::begin(kContactStages), std::end(kContactStages));
    times.seconds.assign(stage_seconds_.begin(), stage_seconds_.end());
    times.steps = profiled_steps_;
    return times;
  }

  void apply_impulse(int body, const Vec3& impulse, const Vec3& point) override {
    world_->apply_impulse(static_cast<rtp::BodyId>(body), impulse, point);
  }

  SampledState body_state(int body) const override {
    if (body >= body_count_) {
      const std::size_t i = static_cast<std::size_t>(body - body_count_);
      return {particles_->position(i), Quat::Identity(), particles_->velocity(i), Vec3::Zero()};
    }
    const auto id = static_cast<rtp::BodyId>(body);
    const rtp::BodyState& s = world_->state(id);
    return {s.position, s.orientation, world_->velocity(id), world_->angular_velocity(id)};
  }

 private:
  std::string variant_;
  rtp::Integrator integrator_;
  rtp::ContactSettings contacts_;
  rtp::ParticleIntegrator particle_integrator_;
  int threads_;
  int body_count_ = 0;
  std::unique_ptr<rtp::ParticleSystem> particles_;
  double dt_ = 0.0;
  std::unique_ptr<rtp::World> world_;
  // the contact step's stage times summed since load(), in kContactStages' order (s)
  bool profiled_ = false;
  std::array<double, kContactStageCount> stage_seconds_{};
  long profiled_steps_ = 0;
  double contact_points_ = 0.0;  // the manifolds' points, summed since load()

  void add_profile(const rtp::StepProfile& p) {
    contact_points_ += static_cast<double>(p.contact_points);
    const std::array<double, kContactStageCount> stages = p.stage_seconds();
    for (std::size_t i = 0; i < kContactStageCount; ++i) stage_seconds_[i] += stages[i];
    ++profiled_steps_;
  }
};

}  // namespace

EngineInfo rtp_engine_info() {
  EngineInfo info;
  info.name = "rtp";
  info.variants = {"rk4",       "midpoint",     "euler",        "symplectic",
                   "explicit-euler", "midpoint-2t", "soft-step",  "soft-step-2t",
                   "soft-step-4", "soft-step-fresh", "sequential-impulse", "seed"};
  // particles integrate by explicit Euler, semi-implicit Euler or midpoint (the seed's three);
  // the rigid-body-only integrators do not apply to a particle scene, nor the particle-only ones
  // to a scene without particles. A scene with contacts steps by a contact solver (the three
  // contact variants), every other scene by an integrator.
  info.applies = [](const Scene& scene, const std::string& variant) {
    if (scene.has_contacts()) return is_contact_variant(variant);
    if (is_contact_variant(variant)) return false;
    const bool particle_only = variant == "explicit-euler" || variant == "midpoint-2t";
    const bool bodies_only = variant == "rk4" || variant == "symplectic";
    return scene.particles ? !bodies_only : !particle_only;
  };
  info.version = "0.2.0";
  info.unsupported = [](const Scene& scene, const std::string&) -> std::optional<std::string> {
    // particles collide with planes only: particles beside bodies that touch are not modelled
    if (scene.has_contacts() && scene.particles)
      return "particles in a scene with body contacts (rtp's particles meet planes only)";
    return std::nullopt;
  };
  info.create = [](const std::string& variant) -> std::unique_ptr<Engine> {
    return std::make_unique<RtpEngine>(variant);
  };
  info.settings = [](const std::string& variant) {
    if (auto contacts = contact_settings_for(variant)) {
      const rtp::ContactSettings& c = *contacts;
      const std::string base = base_variant(variant);
      auto number = [](double value) {
        std::ostringstream out;
        out << value;
        return out.str();
      };
      std::vector<Setting> table = {
          {"contact solver", base,
           c.solver == rtp::ContactSolver::SoftStep
               ? "substeps, each a soft biased solve and relax solves, restitution last "
                 "(docs/solver.md)"
           : c.solver == rtp::ContactSolver::SequentialImpulse
               ? "one step of accumulated impulses, warm start, Baumgarte past the slop"
               : "the seed's lab 5: impulse magnitudes with a penalty term, no warm start"},
          {"integration", "semi-implicit Euler, exponential-map rotation",
           "contact scenes step at the velocity level; RK4's stages do not fit a contact solve"},
          {"speculative distance", number(c.speculative_distance) + " m",
           c.solver == rtp::ContactSolver::Seed
               ? "points found apart are ignored (the seed's contacts touch)"
               : "contacts made this far apart, plus each body's motion in the step"},
          {"threads", std::to_string(c.threads), "narrow phase and each colour of the solve"},
          {"sleeping", "none", "rtp has no sleeping"},
          {"broad-phase margin",
           c.bounds_margin > 0.0 ? number(c.bounds_margin) + " m" : "off",
           "each body's box in the broad phase is its bounds grown this much more; pairs are "
           "looked for again only in a step where some body's bounds leave its box"},
          {"pair cache",
           c.pair_cache_distance > 0.0 ? number(c.pair_cache_distance) + " m" : "off",
           "a pair found apart is not tested again while neither shape has moved this far in "
           "the other's frame since"},
          {"manifold reuse",
           c.manifold_reuse_distance > 0.0 ? number(c.manifold_reuse_distance) + " m" : "off",
           "a box pair's face contact is moved with the boxes, its depths measured again, not "
           "computed, while neither box has moved this far in the other's frame since"},
          {"contacts held",
           c.contact_hold_distance > 0.0 && c.manifold_reuse_distance > 0.0
               ? number(c.contact_hold_distance) + " m"
               : "off",
           "a step whose pairs are last step's keeps the solver's contacts as packed, each "
           "point's separation carried on, while no touching pair has moved this far in its "
           "bodies' frames since"},
      };
      if (c.solver != rtp::ContactSolver::Seed)
        table.push_back({"solver precision", "single, " + std::to_string(rtp::contact_block_lanes()) +
                                                 " manifolds a block",
                         "a colour's contacts solved in SIMD lanes (docs/solver.md)"});
      if (c.solver == rtp::ContactSolver::SoftStep) {
        table.push_back({"substeps", std::to_string(c.substeps),
                         base == "soft-step-4" ? "Box2D v3's default"
                                               : "the stiffness a 20-box tower needs"});
        if (c.max_relax_iterations > c.relax_iterations && c.relax_tolerance > 0.0)
          table.push_back({"relax iterations",
                           std::to_string(c.relax_iterations) + " to " +
                               std::to_string(c.max_relax_iterations),
                           "per substep: more while the last pass changed a contact's normal "
                           "velocity by over " + number(c.relax_tolerance * 1e3) + " mm/s"});
        else
          table.push_back({"relax iterations", std::to_string(c.relax_iterations), "per substep"});
        if (c.recovery_relax_iterations != c.relax_iterations)
          table.push_back({"relax iterations recovering",
                           std::to_string(c.recovery_relax_iterations),
                           "per substep of a step whose deepest overlap is more than the push-out "
                           "removes in it (boxes spawned into each other)"});
        table.push_back({"position passes recovering",
                         std::to_string(c.recovery_position_iterations),
                         c.recovery_position_iterations > 0
                             ? "a step recovering from an overlap first moves the poses apart "
                               "where they overlap deeper than the push-out removes in the step"
                             : "none: overlaps are pushed out by velocity alone, as Box2D v3's"});
        table.push_back({"push-out speed", number(c.max_push_speed) + " m/s",
                         "the fastest a contact pushes penetrating bodies apart"});
        table.push_back({"contact stiffness",
                         number(c.contact_hertz) + " Hz, damping ratio " + number(c.damping_ratio),
                         "capped at a quarter of the substep rate"});
      } else {
        table.push_back({"velocity iterations", std::to_string(c.velocity_iterations),
                         "as the peers' equal-iterations variants"});
        table.push_back({"Baumgarte",
                         number(c.baumgarte) + ", slop " + number(c.linear_slop) + " m",
                         "fraction of the penetration past the slop removed per step"});
      }
      if (c.solver != rtp::ContactSolver::Seed)
        table.push_back({"restitution threshold", number(c.restitution_threshold) + " m/s",
                         "the scene's: slower impacts are inelastic (rtp's own default 1 m/s)"});
      return table;
    }
    const std::string base = base_variant(variant);
    const char* integrator =
        base == "euler"            ? "semi-implicit Euler, exponential-map rotation"
        : base == "midpoint"       ? "midpoint"
        : base == "explicit-euler" ? "explicit Euler (particles only)"
        : base == "symplectic" ? "symplectic: kick + principal-axis splitting of the free rotation"
                               : "RK4";
    return std::vector<Setting>{
        {"integrator", integrator,
         "the variant; momentum form for bodies, forces re-evaluated at every stage"},
        {"precision", "double for bodies, float for particles",
         "particles are bandwidth-bound: 24 bytes of state each"},
        {"particle threads", std::to_string(threads_for(variant)),
         "OpenMP threads of the particle update (-2t: two)"},
    };
  };
  state_instruction_set(info, rtp::instruction_set(),
                        "as compiled: physbench's bench preset -march=native; its release preset "
                        "the baseline, the contact passes the widest the CPU runs; the -x86-64 "
                        "variants the baseline throughout");
  return info;
}

}  // namespace physbench
