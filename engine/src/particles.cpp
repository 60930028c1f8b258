#include "rtp/particles.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rtp {

namespace {

// a counter-based random number in [0, 1) (splitmix64): the same particle index and generation
// give the same number on any thread, so emission needs no shared generator
double unit_random(std::uint64_t seed, std::uint64_t index, std::uint64_t salt) {
  std::uint64_t z = seed + 0x9E3779B97F4A7C15ull * (index + 1) + 0xBF58476D1CE4E5B9ull * (salt + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  return static_cast<double>(z >> 11) * (1.0 / 9007199254740992.0);
}

struct Float3 {
  float x, y, z;
};

}  // namespace

ParticleSystem::ParticleSystem(const ParticleSystemDef& def) : def_(def) {
  for (const ParticlePlane& p : def_.planes)
    if (std::abs(p.normal.norm() - 1.0) > 1e-6) throw std::invalid_argument("rtp: particle plane normal must be unit");
  if (def_.softening <= 0.0) throw std::invalid_argument("rtp: particle softening must be > 0");
  const std::size_t n = def_.count;
  for (auto* v : {&px_, &py_, &pz_, &vx_, &vy_, &vz_}) v->resize(n);
  if (def_.drag > 0.0)
    for (auto* v : {&wx_, &wy_, &wz_}) v->resize(n);
  if (def_.lifetime > 0.0) age_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    emit(i);
    // stagger the first generation's ages so the emitter runs steadily instead of in one burst
    if (!age_.empty()) age_[i] = static_cast<float>(def_.lifetime * unit_random(def_.seed, i, 7));
  }
}

void ParticleSystem::emit(std::size_t i) {
  // the generation: a re-emitted particle gets new numbers
  const std::uint64_t generation = recycled_;
  auto uniform = [&](double lo, double hi, std::uint64_t salt) {
    return lo + (hi - lo) * unit_random(def_.seed, i, generation * 16 + salt);
  };
  px_[i] = static_cast<float>(uniform(def_.spawn_min.x(), def_.spawn_max.x(), 0));
  py_[i] = static_cast<float>(uniform(def_.spawn_min.y(), def_.spawn_max.y(), 1));
  pz_[i] = static_cast<float>(uniform(def_.spawn_min.z(), def_.spawn_max.z(), 2));
  vx_[i] = static_cast<float>(uniform(def_.velocity_min.x(), def_.velocity_max.x(), 3));
  vy_[i] = static_cast<float>(uniform(def_.velocity_min.y(), def_.velocity_max.y(), 4));
  vz_[i] = static_cast<float>(uniform(def_.velocity_min.z(), def_.velocity_max.z(), 5));
  if (!wx_.empty()) {
    const double j = def_.wind_jitter;
    wx_[i] = static_cast<float>(def_.wind.x() + uniform(-j, j, 6));
    wy_[i] = static_cast<float>(def_.wind.y() + uniform(-j, j, 7));
    wz_[i] = static_cast<float>(def_.wind.z() + uniform(-j, j, 8));
  }
  if (!age_.empty()) age_[i] = 0.0f;
}

std::size_t ParticleSystem::bytes_per_particle_step() const {
  // read and written once each: position and velocity, plus wind (read) and age (read+write)
  std::size_t bytes = 2 * 6 * sizeof(float);
  if (!wx_.empty()) bytes += 3 * sizeof(float);
  if (!age_.empty()) bytes += 2 * sizeof(float);
  return bytes;
}

void ParticleSystem::update_range(std::size_t begin, std::size_t end, float dt) {
  const Float3 gravity{float(def_.gravity.x()), float(def_.gravity.y()), float(def_.gravity.z())};
  const float drag = static_cast<float>(def_.drag);
  const float eps2 = static_cast<float>(def_.softening * def_.softening);
  const float restitution = static_cast<float>(def_.restitution);
  const float keep_tangential = static_cast<float>(1.0 - def_.friction);
  const bool windy = !wx_.empty();

  // acceleration at (p, v) for particle i
  auto acceleration = [&](std::size_t i, Float3 p, Float3 v) {
    Float3 a = gravity;
    if (windy) {
      a.x += drag * (wx_[i] - v.x);
      a.y += drag * (wy_[i] - v.y);
      a.z += drag * (wz_[i] - v.z);
    } else if (drag > 0.0f) {
      a.x -= drag * v.x;
      a.y -= drag * v.y;
      a.z -= drag * v.z;
    }
    for (const Attractor& attractor : def_.attractors) {
      const float rx = float(attractor.position.x()) - p.x, ry = float(attractor.position.y()) - p.y,
                  rz = float(attractor.position.z()) - p.z;
      const float r2 = rx * rx + ry * ry + rz * rz + eps2;
      const float scale = float(attractor.strength) / (r2 * std::sqrt(r2));
      a.x += scale * rx;
      a.y += scale * ry;
      a.z += scale * rz;
    }
    return a;
  };

  for (std::size_t i = begin; i < end; ++i) {
    Float3 p{px_[i], py_[i], pz_[i]}, v{vx_[i], vy_[i], vz_[i]};
    // integrate
    switch (def_.integrator) {
      case ParticleIntegrator::ExplicitEuler: {
        const Float3 a = acceleration(i, p, v);
        p = {p.x + dt * v.x, p.y + dt * v.y, p.z + dt * v.z};
        v = {v.x + dt * a.x, v.y + dt * a.y, v.z + dt * a.z};
        break;
      }
      case ParticleIntegrator::SemiImplicitEuler: {
        const Float3 a = acceleration(i, p, v);
        v = {v.x + dt * a.x, v.y + dt * a.y, v.z + dt * a.z};
        p = {p.x + dt * v.x, p.y + dt * v.y, p.z + dt * v.z};
        break;
      }
      case ParticleIntegrator::Midpoint: {
        const float h = 0.5f * dt;
        const Float3 a1 = acceleration(i, p, v);
        const Float3 pm{p.x + h * v.x, p.y + h * v.y, p.z + h * v.z};
        const Float3 vm{v.x + h * a1.x, v.y + h * a1.y, v.z + h * a1.z};
        const Float3 a2 = acceleration(i, pm, vm);
        p = {p.x + dt * vm.x, p.y + dt * vm.y, p.z + dt * vm.z};
        v = {v.x + dt * a2.x, v.y + dt * a2.y, v.z + dt * a2.z};
        break;
      }
    }
    // planes: a particle that crossed is reflected out, its penetration scaled by the restitution
    // (exact for straight-line motion near the plane, and no sinking), its normal velocity
    // reversed and scaled by the restitution, its tangential velocity reduced by the friction
    for (const ParticlePlane& plane : def_.planes) {
      const float nx = float(plane.normal.x()), ny = float(plane.normal.y()), nz = float(plane.normal.z());
      const float depth = (p.x - float(plane.point.x())) * nx + (p.y - float(plane.point.y())) * ny +
                          (p.z - float(plane.point.z())) * nz;
      if (depth >= 0.0f) continue;
      const float out = -(1.0f + restitution) * depth;
      p = {p.x + out * nx, p.y + out * ny, p.z + out * nz};
      const float vn = v.x * nx + v.y * ny + v.z * nz;
      if (vn < 0.0f) {
        const Float3 tangential{v.x - vn * nx, v.y - vn * ny, v.z - vn * nz};
        v = {keep_tangential * tangential.x - restitution * vn * nx, keep_tangential * tangential.y - restitution * vn * ny,
             keep_tangential * tangential.z - restitution * vn * nz};
      }
    }
    px_[i] = p.x, py_[i] = p.y, pz_[i] = p.z;
    vx_[i] = v.x, vy_[i] = v.y, vz_[i] = v.z;
  }
}

void ParticleSystem::step(double dt) {
  const std::size_t n = px_.size();
  const float h = static_cast<float>(dt);
  // both cores for large counts: fixed chunks, no allocation
  const long blocks = static_cast<long>((n + 4095) / 4096);
#pragma omp parallel for num_threads(def_.threads) schedule(static) if (def_.threads > 1 && n >= 16384)
  for (long b = 0; b < blocks; ++b) {
    const std::size_t begin = static_cast<std::size_t>(b) * 4096;
    update_range(begin, std::min(n, begin + 4096), h);
  }
  // age and recycle: serial, so a re-emission's numbers do not depend on the thread count
  if (!age_.empty()) {
    const float lifetime = static_cast<float>(def_.lifetime);
    for (std::size_t i = 0; i < n; ++i) {
      age_[i] += h;
      if (age_[i] >= lifetime) {
        ++recycled_;
        emit(i);
      }
    }
  }
}

}  // namespace rtp
