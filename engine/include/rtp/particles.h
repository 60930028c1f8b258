// rtp particles (the seed's lab 1): many point masses under gravity, point attractors, drag and
// wind, bouncing off oriented planes, optionally ageing and recycled through an emitter.
//
// State is structure-of-arrays, hot data only in the update loop: position and velocity
// (6 floats = 24 bytes per particle); age only when particles age. The per-particle wind
// offset is drawn once at emission, so a step draws no random numbers and allocates nothing.
#pragma once

#include <array>
#include <bit>
#include <cstdint>
#include <vector>

#include "rtp/math.h"

namespace rtp {

enum class ParticleIntegrator : std::uint8_t {
  ExplicitEuler,      // x += v dt with the old v
  SemiImplicitEuler,  // v first, then x with the new v
  Midpoint,           // forces at the half step (the seed's choice)
};

// a point that pulls (strength > 0) or pushes (< 0) with Plummer-softened inverse-square
// acceleration a = s r / (|r|² + ε²)^{3/2}: 1/r² far away, finite at r = 0, and conservative
// (potential −s / √(|r|² + ε²))
struct Attractor {
  Vec3 position = Vec3::Zero();  // m
  double strength = 0.0;         // m³/s²; negative repels
};

// particles stay on the side the normal points to
struct ParticlePlane {
  Vec3 point = Vec3::Zero();
  Vec3 normal = Vec3::UnitY();  // unit
};

// which code updates the particles: the best the core runs (AVX-512 kernels written by hand where
// the core has AVX-512F, chosen at run time), or the portable loops the compiler vectorises for
// the instruction set it was told (tests compare the two)
enum class ParticleKernels : std::uint8_t { Best, Portable };

struct ParticleSystemDef {
  std::size_t count = 0;
  Vec3 spawn_min = Vec3::Zero(), spawn_max = Vec3::Zero();  // uniform initial positions (m)
  Vec3 velocity_min = Vec3::Zero(),
       velocity_max = Vec3::Zero();  // uniform initial velocities (m/s)
  Vec3 gravity = Vec3(0.0, -9.81, 0.0);
  double drag = 0.0;         // 1/s: a += drag (wind + offset − v)
  Vec3 wind = Vec3::Zero();  // m/s
  double wind_jitter = 0.0;  // m/s: each particle's wind differs by a uniform offset of this size
  std::vector<Attractor> attractors;
  double softening = 0.05;  // ε (m)
  std::vector<ParticlePlane> planes;
  double restitution = 0.5;  // normal velocity kept on a bounce
  double friction = 0.0;     // fraction of tangential velocity lost on a bounce, 0..1
  double lifetime = 0.0;     // s; > 0: particles age and are re-emitted from the spawn box
  std::uint64_t seed = 1;
  ParticleIntegrator integrator = ParticleIntegrator::Midpoint;
  int threads = 1;  // OpenMP threads for the update
  ParticleKernels kernels = ParticleKernels::Best;
};

// 1/√x for x > 0 without the divider: a first guess from the float's bits (the exponent halved
// and negated, Lomont 2003), within 3.4 %, refined by three Newton steps y ← y (3/2 − x y²/2),
// each of which squares the relative error (1.8e-3, 4.7e-6, then float rounding: 1.5e-7 at worst
// over 1e-30 … 1e30). Only multiplies and adds, so it vectorises on every instruction set and
// pipelines, where a square root and a divide per attractor and particle queue on the one divider
// (what limited the particle update in cache on an Intel core).
inline float reciprocal_sqrt(float x) {
  float y = std::bit_cast<float>(0x5f375a86u - (std::bit_cast<std::uint32_t>(x) >> 1));
  const float half_x = 0.5f * x;
  y *= 1.5f - half_x * y * y;
  y *= 1.5f - half_x * y * y;
  y *= 1.5f - half_x * y * y;
  return y;
}

// Where particle i of a generation appears: uniform in the spawn box and velocity range, its wind
// offset uniform in ±jitter. A pure function of (seed, i, generation) — a counter-based
// generator, so any thread, and any other engine driven by the harness, emits the same particles.
struct ParticleSpawn {
  Vec3 position, velocity, wind;
};
ParticleSpawn particle_spawn(const ParticleSystemDef& def, std::size_t i, std::uint64_t generation);
// the first generation's ages are staggered over the lifetime so the emitter runs steadily
double particle_initial_age(const ParticleSystemDef& def, std::size_t i);
// the acceleration of the definition's forces other than gravity (drag toward the particle's wind,
// attractors) at position p and velocity v, in double: the law the float update implements
Vec3 particle_acceleration(const ParticleSystemDef& def, const Vec3& p, const Vec3& v,
                           const Vec3& wind);

class ParticleSystem {
 public:
  explicit ParticleSystem(const ParticleSystemDef& def);

  void step(double dt);

  std::size_t size() const { return px_.size(); }
  Vec3 position(std::size_t i) const { return Vec3(px_[i], py_[i], pz_[i]); }
  Vec3 velocity(std::size_t i) const { return Vec3(vx_[i], vy_[i], vz_[i]); }
  float age(std::size_t i) const { return age_.empty() ? 0.0f : age_[i]; }
  std::size_t recycled() const { return recycled_; }
  // the structure-of-arrays x positions, for drawing and for checking that buffers stay put
  const float* x_data() const { return px_.data(); }
  const ParticleSystemDef& def() const { return def_; }
  // bytes of particle state one step reads and writes, for the roofline
  std::size_t bytes_per_particle_step() const;
  // the kernels in use: "avx512" or "portable"
  const char* kernels() const { return avx512_ ? "avx512" : "portable"; }

 private:
  void emit(std::size_t i);
  void update_range(std::size_t begin, std::size_t end, float dt);
  void accelerate(std::size_t first, std::size_t n, const float* px, const float* py,
                  const float* pz, const float* vx, const float* vy, const float* vz, float* ax,
                  float* ay, float* az) const;

  ParticleSystemDef def_;
  bool avx512_ = false;  // the hand-written AVX-512 kernels run
  // the attractors in float: x, y, z, strength
  std::vector<std::array<float, 4>> attractors_;
  // hot: positions and velocities (m, m/s)
  std::vector<float> px_, py_, pz_, vx_, vy_, vz_;
  // per-particle wind (m/s), only when the scene has drag
  std::vector<float> wx_, wy_, wz_;
  // ages (s), only when particles age
  std::vector<float> age_;
  std::size_t recycled_ = 0;
};

}  // namespace rtp
