// rtp adapter: the scene maps one to one onto rtp's own conventions (y up, world-frame
// angular velocity), so nothing is converted.
#include <rtp/world.h>

#include "physbench/registry.h"

namespace physbench {

namespace {

rtp::Integrator integrator_for(const std::string& variant) {
  if (variant == "euler") return rtp::Integrator::SemiImplicitEuler;
  if (variant == "midpoint") return rtp::Integrator::Midpoint;
  if (variant == "symplectic") return rtp::Integrator::Symplectic;
  return rtp::Integrator::RungeKutta4;
}

class RtpEngine final : public Engine {
 public:
  explicit RtpEngine(rtp::Integrator integrator) : integrator_(integrator) {}

  void load(const Scene& scene) override {
    dt_ = scene.dt;
    world_ = std::make_unique<rtp::World>(scene.gravity, integrator_);
    for (const BodySpec& b : scene.bodies) {
      rtp::BodyDef def;
      def.position = b.position;
      def.orientation = b.orientation;
      def.linear_velocity = b.linear_velocity;
      def.angular_velocity = b.angular_velocity;
      def.mass = b.mass;
      if (b.mass > 0.0) def.principal_inertia = principal_inertia(b.shape, b.mass);
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
  }

  void step() override { world_->step(dt_); }

  void apply_impulse(int body, const Vec3& impulse, const Vec3& point) override {
    world_->apply_impulse(static_cast<rtp::BodyId>(body), impulse, point);
  }

  BodyState body_state(int body) const override {
    const auto id = static_cast<rtp::BodyId>(body);
    const rtp::BodyState& s = world_->state(id);
    return {s.position, s.orientation, world_->velocity(id), world_->angular_velocity(id)};
  }

 private:
  rtp::Integrator integrator_;
  double dt_ = 0.0;
  std::unique_ptr<rtp::World> world_;
};

}  // namespace

EngineInfo rtp_engine_info() {
  EngineInfo info;
  info.name = "rtp";
  info.variants = {"rk4", "midpoint", "euler", "symplectic"};
  info.version = "0.1.0";
  info.unsupported = [](const Scene& scene, const std::string&) -> std::optional<std::string> {
    // rtp has no contact pipeline yet: a scene where two bodies may touch cannot be modelled
    if (scene.has_contacts())
      return "contacts are not implemented in rtp yet (no broad or narrow phase)";
    return std::nullopt;
  };
  info.create = [](const std::string& variant) -> std::unique_ptr<Engine> {
    return std::make_unique<RtpEngine>(integrator_for(variant));
  };
  info.settings = [](const std::string& variant) {
    std::vector<Setting> s;
    const char* integrator =
        variant == "euler"      ? "semi-implicit Euler, exponential-map rotation"
        : variant == "midpoint" ? "midpoint"
        : variant == "symplectic"
            ? "symplectic: kick + principal-axis splitting of the free rotation"
            : "RK4";
    s.push_back({"integrator", integrator,
                 "the variant; momentum form, forces re-evaluated at every stage"});
    s.push_back({"precision", "double", "rtp computes in double throughout"});
    return s;
  };
  return info;
}

}  // namespace physbench
