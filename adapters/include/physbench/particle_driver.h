// Drives a scene's particles in an engine without a particle system of its own: the same starts,
// forces, ageing and re-emission as rtp's (rtp/particles.h), so every engine runs the same
// particles. Gravity is left to the engine; collisions with the planes are the engine's own.
#pragma once

#include <rtp/particles.h>

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "physbench/scene.h"

namespace physbench {

// peers run particle sets up to this size: beyond it a rigid-body engine's run of a seed scene
// takes minutes (Bullet float steps 6.0e4 particle-steps/s at 1e5 particles: docs/particles.md)
inline constexpr long kMaxPeerParticles = 100000;

// why a rigid-body engine cannot run this scene's particles, or nullopt when it can
std::optional<std::string> peer_particles_unsupported(const Scene& scene,
                                                      const std::string& engine);

// the scene's particle set as rtp's definition (integrator and threads left at their defaults)
rtp::ParticleSystemDef particle_system_def(const Scene& scene);

class ParticleDriver {
 public:
  explicit ParticleDriver(const Scene& scene);

  long count() const { return static_cast<long>(wind_.size()); }
  // where particle i starts
  rtp::ParticleSpawn start(long i) const {
    return rtp::particle_spawn(def_, static_cast<std::size_t>(i), 0);
  }
  // drag toward the particle's wind and the attractors, as a force on a particle of the scene's
  // mass (N)
  Vec3 force(long i, const Vec3& position, const Vec3& velocity) const {
    return mass_ * rtp::particle_acceleration(def_, position, velocity, wind_[i]);
  }
  // ages every particle by dt and re-emits, in index order as rtp does, those past their lifetime
  void age(double dt, const std::function<void(long, const rtp::ParticleSpawn&)>& respawn);

 private:
  rtp::ParticleSystemDef def_;
  double mass_;
  std::vector<Vec3> wind_;   // each particle's wind, this generation (m/s)
  std::vector<double> age_;  // s; empty when particles do not age
  std::uint64_t recycled_ = 0;
};

}  // namespace physbench
