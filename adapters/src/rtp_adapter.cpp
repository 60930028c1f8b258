// rtp adapter: the scene maps one to one onto rtp's own conventions (y up, world-frame
// angular velocity, a plane as the body's local y = 0 surface, the pair rules √(μa μb) and
// max(ea, eb)), so nothing is converted.
#include <rtp/particles.h>
#include <rtp/world.h>

#include <optional>

#include "physbench/particle_driver.h"
#include "physbench/registry.h"

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

// the contact solver a contact variant names
std::optional<rtp::ContactSolver> contact_solver_for(const std::string& variant) {
  if (variant == "soft-step") return rtp::ContactSolver::SoftStep;
  if (variant == "sequential-impulse") return rtp::ContactSolver::SequentialImpulse;
  if (variant == "seed") return rtp::ContactSolver::Seed;
  return std::nullopt;
}

bool is_contact_variant(const std::string& variant) {
  return contact_solver_for(variant).has_value();
}

rtp::ShapeDef shape_def(const Shape& shape) {
  rtp::ShapeDef def;
  switch (shape.kind) {
    case ShapeKind::Box:
      def.kind = rtp::BodyShape::Box;
      def.half_extents = shape.half_extents;
      break;
    case ShapeKind::Sphere:
      def.kind = rtp::BodyShape::Sphere;
      def.radius = shape.radius;
      break;
    case ShapeKind::Plane:
      def.kind = rtp::BodyShape::Plane;
      break;
  }
  return def;
}

// particle variants run the particle update on this many threads
int threads_for(const std::string& variant) { return variant.ends_with("-2t") ? 2 : 1; }

std::string base_variant(const std::string& variant) {
  return variant.ends_with("-2t") ? variant.substr(0, variant.size() - 3) : variant;
}

class RtpEngine final : public Engine {
 public:
  explicit RtpEngine(const std::string& variant)
      : integrator_(integrator_for(base_variant(variant))),
        contact_solver_(contact_solver_for(variant)),
        particle_integrator_(particle_integrator_for(base_variant(variant))),
        threads_(threads_for(variant)) {}

  void load(const Scene& scene) override {
    dt_ = scene.dt;
    rtp::ContactSettings contacts;
    if (contact_solver_) contacts.solver = *contact_solver_;
    world_ = std::make_unique<rtp::World>(scene.gravity, integrator_, contacts);
    // shapes only where bodies can touch: a scene without contacts keeps its integrator
    const bool shaped = scene.has_contacts();
    for (const BodySpec& b : scene.bodies) {
      rtp::BodyDef def;
      def.position = b.position;
      def.orientation = b.orientation;
      def.linear_velocity = b.linear_velocity;
      def.angular_velocity = b.angular_velocity;
      def.mass = b.mass;
      if (b.mass > 0.0) def.principal_inertia = principal_inertia(b.shape, b.mass);
      if (shaped) def.shape = shape_def(b.shape);
      def.friction = b.friction;
      def.restitution = b.restitution;
      world_->add_body(def);
    }
    for (const SpringSpec& s : scene.springs) {
      rtp::SpringDef def;
      def.body_a = static_cast<rtp::BodyId>(s.body_a);
      def.local_point_a = s.local_point_a;
      def.body_b = s.body_b < 0 ? rtp::kWorldAnchor : static_cast<rtp::BodyId>(s.body_b);
      def.point_b = s.point_b;
      def.stiffness = s.stiffness;
      def.damping = s.damping;
      def.rest_length = s.rest_length;
      world_->add_spring(def);
    }
    body_count_ = static_cast<int>(scene.bodies.size());
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
  }

  void apply_impulse(int body, const Vec3& impulse, const Vec3& point) override {
    world_->apply_impulse(static_cast<rtp::BodyId>(body), impulse, point);
  }

  BodyState body_state(int body) const override {
    if (body >= body_count_) {
      const std::size_t i = static_cast<std::size_t>(body - body_count_);
      return {particles_->position(i), Quat::Identity(), particles_->velocity(i), Vec3::Zero()};
    }
    const auto id = static_cast<rtp::BodyId>(body);
    const rtp::BodyState& s = world_->state(id);
    return {s.position, s.orientation, world_->velocity(id), world_->angular_velocity(id)};
  }

 private:
  rtp::Integrator integrator_;
  std::optional<rtp::ContactSolver> contact_solver_;
  rtp::ParticleIntegrator particle_integrator_;
  int threads_;
  int body_count_ = 0;
  std::unique_ptr<rtp::ParticleSystem> particles_;
  double dt_ = 0.0;
  std::unique_ptr<rtp::World> world_;
};

}  // namespace

EngineInfo rtp_engine_info() {
  EngineInfo info;
  info.name = "rtp";
  info.variants = {"rk4",       "midpoint",           "euler", "symplectic", "explicit-euler",
                   "midpoint-2t", "soft-step", "sequential-impulse", "seed"};
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
    if (auto solver = contact_solver_for(variant)) {
      rtp::ContactSettings c;
      c.solver = *solver;
      std::vector<Setting> table = {
          {"contact solver", variant,
           *solver == rtp::ContactSolver::SoftStep
               ? "substeps, soft biased solve + relax, restitution last (docs/solver.md)"
           : *solver == rtp::ContactSolver::SequentialImpulse
               ? "one step of accumulated impulses, warm start, Baumgarte past the slop"
               : "the seed's lab 5: impulse magnitudes with a penalty term, no warm start"},
          {"integration", "semi-implicit Euler, exponential-map rotation",
           "contact scenes step at the velocity level; RK4's stages do not fit a contact solve"},
          {"speculative distance", std::to_string(c.speculative_distance) + " m",
           *solver == rtp::ContactSolver::Seed ? "points found this far apart are ignored"
                                               : "contacts made before bodies touch"},
          {"sleeping", "none", "rtp has no sleeping"},
      };
      if (*solver == rtp::ContactSolver::SoftStep) {
        table.push_back({"substeps", std::to_string(c.substeps), "Box2D v3's default"});
        table.push_back({"relax iterations", std::to_string(c.relax_iterations), "per substep"});
        table.push_back({"contact stiffness", std::to_string(c.contact_hertz) + " Hz, damping ratio " +
                                                  std::to_string(c.damping_ratio),
                         "twice as stiff against static bodies"});
      } else {
        table.push_back({"velocity iterations", std::to_string(c.velocity_iterations),
                         "equal to the peers' equal-iterations setting"});
        table.push_back({"Baumgarte", std::to_string(c.baumgarte) + ", slop " +
                                          std::to_string(c.linear_slop) + " m",
                         "fraction of the penetration past the slop removed per step"});
      }
      table.push_back({"restitution threshold", std::to_string(c.restitution_threshold) + " m/s",
                       "slower approaches do not bounce"});
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
  return info;
}

}  // namespace physbench
