#include "physbench/particle_driver.h"

namespace physbench {

std::optional<std::string> peer_particles_unsupported(const Scene& scene,
                                                      const std::string& engine) {
  if (!scene.particles) return std::nullopt;
  if (scene.particles->count > kMaxPeerParticles)
    return "over " + std::to_string(kMaxPeerParticles) + " particles a run of " + engine +
           " outlasts the harness's time budget: rtp alone runs larger sets";
  if (!scene.bodies.empty())
    return "particles beside rigid bodies are not mapped onto " + engine + " yet";
  return std::nullopt;
}

rtp::ParticleSystemDef particle_system_def(const Scene& scene) {
  const ParticleSetSpec& p = *scene.particles;
  rtp::ParticleSystemDef def;
  def.count = static_cast<std::size_t>(p.count);
  def.spawn_min = p.spawn_min;
  def.spawn_max = p.spawn_max;
  def.velocity_min = p.velocity_min;
  def.velocity_max = p.velocity_max;
  def.gravity = scene.gravity;
  def.drag = p.drag;
  def.wind = p.wind;
  def.wind_jitter = p.wind_jitter;
  for (const ParticleAttractor& a : p.attractors)
    def.attractors.push_back({a.position, a.strength});
  def.softening = p.softening;
  for (const ParticlePlaneSpec& plane : p.planes) def.planes.push_back({plane.point, plane.normal});
  def.restitution = p.restitution;
  def.friction = p.friction;
  def.lifetime = p.lifetime;
  def.seed = p.seed;
  return def;
}

ParticleDriver::ParticleDriver(const Scene& scene)
    : def_(particle_system_def(scene)), mass_(scene.particles->mass) {
  wind_.resize(def_.count);
  for (std::size_t i = 0; i < def_.count; ++i) wind_[i] = rtp::particle_spawn(def_, i, 0).wind;
  if (def_.lifetime > 0.0) {
    age_.resize(def_.count);
    for (std::size_t i = 0; i < def_.count; ++i) age_[i] = rtp::particle_initial_age(def_, i);
  }
}

void ParticleDriver::age(double dt,
                         const std::function<void(long, const rtp::ParticleSpawn&)>& respawn) {
  for (std::size_t i = 0; i < age_.size(); ++i) {
    age_[i] += dt;
    if (age_[i] >= def_.lifetime) {
      ++recycled_;
      const rtp::ParticleSpawn spawn = rtp::particle_spawn(def_, i, recycled_);
      wind_[i] = spawn.wind;
      age_[i] = 0.0;
      respawn(static_cast<long>(i), spawn);
    }
  }
}

}  // namespace physbench
