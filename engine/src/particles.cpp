#include "rtp/particles.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define RTP_PARTICLES_AVX512 1
#endif

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

#ifdef RTP_PARTICLES_AVX512
bool core_has_avx512() { return __builtin_cpu_supports("avx512f"); }
#else
bool core_has_avx512() { return false; }
#endif

}  // namespace

ParticleSpawn particle_spawn(const ParticleSystemDef& def, std::size_t i,
                             std::uint64_t generation) {
  auto uniform = [&](double lo, double hi, std::uint64_t salt) {
    return lo + (hi - lo) * unit_random(def.seed, i, generation * 16 + salt);
  };
  ParticleSpawn s;
  s.position = Vec3(uniform(def.spawn_min.x(), def.spawn_max.x(), 0),
                    uniform(def.spawn_min.y(), def.spawn_max.y(), 1),
                    uniform(def.spawn_min.z(), def.spawn_max.z(), 2));
  s.velocity = Vec3(uniform(def.velocity_min.x(), def.velocity_max.x(), 3),
                    uniform(def.velocity_min.y(), def.velocity_max.y(), 4),
                    uniform(def.velocity_min.z(), def.velocity_max.z(), 5));
  const double j = def.wind_jitter;
  s.wind = def.wind + Vec3(uniform(-j, j, 6), uniform(-j, j, 7), uniform(-j, j, 8));
  return s;
}

double particle_initial_age(const ParticleSystemDef& def, std::size_t i) {
  return def.lifetime * unit_random(def.seed, i, 7);
}

Vec3 particle_acceleration(const ParticleSystemDef& def, const Vec3& p, const Vec3& v,
                           const Vec3& wind) {
  Vec3 a = def.drag * (wind - v);
  const double eps2 = def.softening * def.softening;
  for (const Attractor& attractor : def.attractors) {
    const Vec3 r = attractor.position - p;
    const double r2 = r.squaredNorm() + eps2;
    a += attractor.strength / (r2 * std::sqrt(r2)) * r;
  }
  return a;
}

ParticleSystem::ParticleSystem(const ParticleSystemDef& def) : def_(def) {
  for (const ParticlePlane& p : def_.planes)
    if (std::abs(p.normal.norm() - 1.0) > 1e-6)
      throw std::invalid_argument("rtp: particle plane normal must be unit");
  if (def_.softening <= 0.0) throw std::invalid_argument("rtp: particle softening must be > 0");
  avx512_ = def_.kernels == ParticleKernels::Best && core_has_avx512();
  for (const Attractor& a : def_.attractors)
    attractors_.push_back({float(a.position.x()), float(a.position.y()), float(a.position.z()),
                           float(a.strength)});
  const std::size_t n = def_.count;
  for (auto* v : {&px_, &py_, &pz_, &vx_, &vy_, &vz_}) v->resize(n);
  if (def_.drag > 0.0)
    for (auto* v : {&wx_, &wy_, &wz_}) v->resize(n);
  if (def_.lifetime > 0.0) age_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    emit(i);
    // stagger the first generation's ages so the emitter runs steadily instead of in one burst
    if (!age_.empty()) age_[i] = static_cast<float>(particle_initial_age(def_, i));
  }
}

void ParticleSystem::emit(std::size_t i) {
  // the generation: a re-emitted particle gets new numbers
  const ParticleSpawn spawn = particle_spawn(def_, i, recycled_);
  px_[i] = static_cast<float>(spawn.position.x());
  py_[i] = static_cast<float>(spawn.position.y());
  pz_[i] = static_cast<float>(spawn.position.z());
  vx_[i] = static_cast<float>(spawn.velocity.x());
  vy_[i] = static_cast<float>(spawn.velocity.y());
  vz_[i] = static_cast<float>(spawn.velocity.z());
  if (!wx_.empty()) {
    wx_[i] = static_cast<float>(spawn.wind.x());
    wy_[i] = static_cast<float>(spawn.wind.y());
    wz_[i] = static_cast<float>(spawn.wind.z());
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

namespace {

// Particles are updated in blocks small enough for their temporaries to stay in L1. Every loop
// below is branch-free over a block, so the compiler vectorises it (with -fno-trapping-math for
// the selects: engine/CMakeLists.txt); the per-attractor and per-plane loops sit outside the
// particle loop.
constexpr std::size_t kBlock = 256;

struct Block {
  alignas(64) float x[kBlock], y[kBlock], z[kBlock];
};

#ifdef RTP_PARTICLES_AVX512
// The AVX-512 kernels, for cores that have it (chosen at run time, so a portable build uses them
// too): 16 particles per register, and 1/√r² at each attractor and the bounce's 1/vₙ by the
// core's 14-bit estimates and one Newton step each (relative error ≤ 1.5 (2⁻¹⁴)² and (2⁻¹⁴)²,
// under float rounding): five operations for 1/√r² where the portable reciprocal_sqrt takes
// fourteen, and three multiply-adds for 1/vₙ where the portable loop divides. In cache, the update
// is bound by the number of vector operations (docs/particles.md).
//
// The unmasked forms of these four fill a register from an "undefined" one, which GCC 12 reports
// as maybe uninitialised at every use (GCC bug 105593); the zero-masked forms under a full mask
// compile to the same instructions.
constexpr __mmask16 kAll = 0xFFFF;
__attribute__((target("avx512f"))) inline __m512 min16(__m512 a, __m512 b) {
  return _mm512_maskz_min_ps(kAll, a, b);
}
__attribute__((target("avx512f"))) inline __m512 max16(__m512 a, __m512 b) {
  return _mm512_maskz_max_ps(kAll, a, b);
}
__attribute__((target("avx512f"))) inline __m512 rsqrt16(__m512 a) {
  return _mm512_maskz_rsqrt14_ps(kAll, a);
}
__attribute__((target("avx512f"))) inline __m512 rcp16(__m512 a) {
  return _mm512_maskz_rcp14_ps(kAll, a);
}
// the lanes of a 16-particle group that exist: all but in a block's last, partial group
inline __mmask16 lanes(std::size_t n, std::size_t j) {
  return static_cast<__mmask16>(n - j >= 16 ? 0xFFFFu : (1u << (n - j)) - 1u);
}

// a = g + drag (wind − v) + Σ attractors for n particles; wx is null when the scene has no drag
// (no wind is kept then). The attractors are summed in registers.
__attribute__((target("avx512f"))) void accelerate_avx512(
    std::size_t n, const float* px, const float* py, const float* pz, const float* vx,
    const float* vy, const float* vz, const float* wx, const float* wy, const float* wz,
    const std::array<float, 3>& gravity, float drag, const std::array<float, 4>* attractors,
    std::size_t count, float eps2, float* ax, float* ay, float* az) {
  const __m512 half = _mm512_set1_ps(0.5f), three_halves = _mm512_set1_ps(1.5f),
               softening = _mm512_set1_ps(eps2), k = _mm512_set1_ps(drag),
               gx = _mm512_set1_ps(gravity[0]), gy = _mm512_set1_ps(gravity[1]),
               gz = _mm512_set1_ps(gravity[2]);
  for (std::size_t j = 0; j < n; j += 16) {
    const __mmask16 m = lanes(n, j);
    const __m512 x = _mm512_maskz_loadu_ps(m, px + j), y = _mm512_maskz_loadu_ps(m, py + j),
                 z = _mm512_maskz_loadu_ps(m, pz + j);
    __m512 sx = _mm512_maskz_loadu_ps(m, vx + j), sy = _mm512_maskz_loadu_ps(m, vy + j),
           sz = _mm512_maskz_loadu_ps(m, vz + j);
    if (wx) {
      sx = _mm512_sub_ps(_mm512_maskz_loadu_ps(m, wx + j), sx);
      sy = _mm512_sub_ps(_mm512_maskz_loadu_ps(m, wy + j), sy);
      sz = _mm512_sub_ps(_mm512_maskz_loadu_ps(m, wz + j), sz);
      sx = _mm512_fmadd_ps(k, sx, gx);
      sy = _mm512_fmadd_ps(k, sy, gy);
      sz = _mm512_fmadd_ps(k, sz, gz);
    } else {
      sx = _mm512_fnmadd_ps(k, sx, gx);
      sy = _mm512_fnmadd_ps(k, sy, gy);
      sz = _mm512_fnmadd_ps(k, sz, gz);
    }
    for (std::size_t i = 0; i < count; ++i) {
      const std::array<float, 4>& a = attractors[i];
      const __m512 rx = _mm512_sub_ps(_mm512_set1_ps(a[0]), x);
      const __m512 ry = _mm512_sub_ps(_mm512_set1_ps(a[1]), y);
      const __m512 rz = _mm512_sub_ps(_mm512_set1_ps(a[2]), z);
      const __m512 r2 =
          _mm512_fmadd_ps(rx, rx, _mm512_fmadd_ps(ry, ry, _mm512_fmadd_ps(rz, rz, softening)));
      // y ← y (3/2 − r² y²/2) from the estimate
      const __m512 guess = rsqrt16(r2);
      const __m512 half_r2_guess = _mm512_mul_ps(_mm512_mul_ps(half, r2), guess);
      const __m512 inverse =
          _mm512_mul_ps(guess, _mm512_fnmadd_ps(half_r2_guess, guess, three_halves));
      const __m512 scale = _mm512_mul_ps(_mm512_mul_ps(_mm512_set1_ps(a[3]), inverse),
                                         _mm512_mul_ps(inverse, inverse));
      sx = _mm512_fmadd_ps(scale, rx, sx);
      sy = _mm512_fmadd_ps(scale, ry, sy);
      sz = _mm512_fmadd_ps(scale, rz, sz);
    }
    _mm512_mask_storeu_ps(ax + j, m, sx);
    _mm512_mask_storeu_ps(ay + j, m, sy);
    _mm512_mask_storeu_ps(az + j, m, sz);
  }
}
#endif

}  // namespace

// a = g + drag (wind − v) + Σ attractors, for n particles of one block
void ParticleSystem::accelerate(std::size_t first, std::size_t n, const float* __restrict px,
                                const float* __restrict py, const float* __restrict pz,
                                const float* __restrict vx, const float* __restrict vy,
                                const float* __restrict vz, float* __restrict ax,
                                float* __restrict ay, float* __restrict az) const {
  const float gx = float(def_.gravity.x()), gy = float(def_.gravity.y()),
              gz = float(def_.gravity.z());
  const float drag = static_cast<float>(def_.drag);
  const float eps2 = static_cast<float>(def_.softening * def_.softening);
#ifdef RTP_PARTICLES_AVX512
  if (avx512_) {
    const bool wind = !wx_.empty();
    accelerate_avx512(n, px, py, pz, vx, vy, vz, wind ? wx_.data() + first : nullptr,
                      wind ? wy_.data() + first : nullptr, wind ? wz_.data() + first : nullptr,
                      {gx, gy, gz}, drag, attractors_.data(), attractors_.size(), eps2, ax, ay,
                      az);
    return;
  }
#endif
  if (!wx_.empty()) {
    const float* __restrict wx = wx_.data() + first;
    const float* __restrict wy = wy_.data() + first;
    const float* __restrict wz = wz_.data() + first;
    for (std::size_t j = 0; j < n; ++j) {
      ax[j] = gx + drag * (wx[j] - vx[j]);
      ay[j] = gy + drag * (wy[j] - vy[j]);
      az[j] = gz + drag * (wz[j] - vz[j]);
    }
  } else {
    for (std::size_t j = 0; j < n; ++j) {
      ax[j] = gx - drag * vx[j];
      ay[j] = gy - drag * vy[j];
      az[j] = gz - drag * vz[j];
    }
  }
  for (const std::array<float, 4>& attractor : attractors_) {
    const float cx = attractor[0], cy = attractor[1], cz = attractor[2], strength = attractor[3];
    for (std::size_t j = 0; j < n; ++j) {
      const float rx = cx - px[j], ry = cy - py[j], rz = cz - pz[j];
      const float r2 = rx * rx + ry * ry + rz * rz + eps2;
      const float inverse = reciprocal_sqrt(r2);
      const float scale = strength * (inverse * inverse * inverse);
      ax[j] += scale * rx;
      ay[j] += scale * ry;
      az[j] += scale * rz;
    }
  }
}

namespace {

// one block's position and velocity update from its accelerations; restrict-qualified
// parameters tell the compiler the six arrays never overlap, so each loop vectorises
void kick_drift(ParticleIntegrator integrator, std::size_t n, float dt, float* __restrict x,
                float* __restrict y, float* __restrict z, float* __restrict vx,
                float* __restrict vy, float* __restrict vz, const float* __restrict ax,
                const float* __restrict ay, const float* __restrict az) {
  if (integrator == ParticleIntegrator::ExplicitEuler) {
    for (std::size_t j = 0; j < n; ++j) {
      x[j] += dt * vx[j];
      y[j] += dt * vy[j];
      z[j] += dt * vz[j];
      vx[j] += dt * ax[j];
      vy[j] += dt * ay[j];
      vz[j] += dt * az[j];
    }
  } else {
    for (std::size_t j = 0; j < n; ++j) {
      vx[j] += dt * ax[j];
      vy[j] += dt * ay[j];
      vz[j] += dt * az[j];
      x[j] += dt * vx[j];
      y[j] += dt * vy[j];
      z[j] += dt * vz[j];
    }
  }
}

// midpoint's half step: the state h = dt/2 ahead, by the step's first accelerations
void midpoint_stage(std::size_t n, float h, const float* __restrict x, const float* __restrict y,
                    const float* __restrict z, const float* __restrict vx,
                    const float* __restrict vy, const float* __restrict vz,
                    const float* __restrict ax, const float* __restrict ay,
                    const float* __restrict az, float* __restrict sx, float* __restrict sy,
                    float* __restrict sz, float* __restrict svx, float* __restrict svy,
                    float* __restrict svz) {
  for (std::size_t j = 0; j < n; ++j) {
    sx[j] = x[j] + h * vx[j];
    sy[j] = y[j] + h * vy[j];
    sz[j] = z[j] + h * vz[j];
    svx[j] = vx[j] + h * ax[j];
    svy[j] = vy[j] + h * ay[j];
    svz[j] = vz[j] + h * az[j];
  }
}

// midpoint's last stage: positions by the half-step velocities, velocities by the half-step
// accelerations
void midpoint_finish(std::size_t n, float dt, float* __restrict x, float* __restrict y,
                     float* __restrict z, float* __restrict vx, float* __restrict vy,
                     float* __restrict vz, const float* __restrict hx, const float* __restrict hy,
                     const float* __restrict hz, const float* __restrict ax,
                     const float* __restrict ay, const float* __restrict az) {
  for (std::size_t j = 0; j < n; ++j) {
    x[j] += dt * hx[j];
    y[j] += dt * hy[j];
    z[j] += dt * hz[j];
    vx[j] += dt * ax[j];
    vy[j] += dt * ay[j];
    vz[j] += dt * az[j];
  }
}

// One plane against one block. A particle found below the plane at the end of a step crossed it
// τ = depth / vₙ ago (straight-line estimate). It is bounced as if at the crossing: its normal
// speed at impact, vₙ + gₙτ with gₙ the pull of gravity into the plane, is reversed and scaled by
// the restitution, then it climbs against gravity for τ. Reflecting the end-of-step speed instead
// hands every bounce the (1 + e) gₙ τ it gained below the plane: apexes came out 7 % high at
// dt = 1/120. Its tangential velocity loses the friction fraction; it never ends below the plane.
// Written as selects, not branches, so it vectorises.
void collide(std::size_t n, float nx, float ny, float nz, float offset, float gravity_into_plane,
             float restitution, float keep_tangential, float* __restrict x, float* __restrict y,
             float* __restrict z, float* __restrict vx, float* __restrict vy,
             float* __restrict vz) {
  const float gn = gravity_into_plane;
  for (std::size_t j = 0; j < n; ++j) {
    const float depth = x[j] * nx + y[j] * ny + z[j] * nz - offset;
    const float vn = vx[j] * nx + vy[j] * ny + vz[j] * nz;
    const bool hit = (depth < 0.0f) & (vn < 0.0f);
    const float tau = hit ? depth / vn : 0.0f;           // s since the crossing
    const float impact = std::min(vn + gn * tau, 0.0f);  // normal velocity at the crossing
    const float rise = -restitution * impact;            // normal speed off the plane
    const float height = std::max(rise * tau - 0.5f * gn * tau * tau, 0.0f);
    const float after = height > 0.0f ? rise - gn * tau : std::max(rise - gn * tau, 0.0f);
    // a particle below the plane but moving out of it is only lifted back to the surface
    const float lift = hit ? height - depth : std::max(-depth, 0.0f);
    x[j] += lift * nx;
    y[j] += lift * ny;
    z[j] += lift * nz;
    const float keep = hit ? keep_tangential : 1.0f;
    const float normal =
        hit ? after - keep_tangential * vn : 0.0f;  // v = keep (v − vn n) + after n
    vx[j] = keep * vx[j] + normal * nx;
    vy[j] = keep * vy[j] + normal * ny;
    vz[j] = keep * vz[j] + normal * nz;
  }
}

#ifdef RTP_PARTICLES_AVX512
// collide() with AVX-512: the same arithmetic, 1/vₙ from the estimate and r ← r (2 − vₙ r)
__attribute__((target("avx512f"))) void collide_avx512(
    std::size_t n, float nx, float ny, float nz, float offset, float gravity_into_plane,
    float restitution, float keep_tangential, float* x, float* y, float* z, float* vx, float* vy,
    float* vz) {
  const __m512 n_x = _mm512_set1_ps(nx), n_y = _mm512_set1_ps(ny), n_z = _mm512_set1_ps(nz),
               plane = _mm512_set1_ps(offset), gn = _mm512_set1_ps(gravity_into_plane),
               half_gn = _mm512_set1_ps(0.5f * gravity_into_plane),
               minus_e = _mm512_set1_ps(-restitution), keep_t = _mm512_set1_ps(keep_tangential),
               zero = _mm512_setzero_ps(), one = _mm512_set1_ps(1.0f), two = _mm512_set1_ps(2.0f);
  for (std::size_t j = 0; j < n; j += 16) {
    const __mmask16 m = lanes(n, j);
    const __m512 px = _mm512_maskz_loadu_ps(m, x + j), py = _mm512_maskz_loadu_ps(m, y + j),
                 pz = _mm512_maskz_loadu_ps(m, z + j), ux = _mm512_maskz_loadu_ps(m, vx + j),
                 uy = _mm512_maskz_loadu_ps(m, vy + j), uz = _mm512_maskz_loadu_ps(m, vz + j);
    const __m512 depth =
        _mm512_fmadd_ps(px, n_x, _mm512_fmadd_ps(py, n_y, _mm512_fmsub_ps(pz, n_z, plane)));
    const __m512 vn = _mm512_fmadd_ps(ux, n_x, _mm512_fmadd_ps(uy, n_y, _mm512_mul_ps(uz, n_z)));
    const __mmask16 hit = _mm512_mask_cmp_ps_mask(_mm512_cmp_ps_mask(depth, zero, _CMP_LT_OQ),
                                                  vn, zero, _CMP_LT_OQ);
    const __m512 guess = rcp16(vn);
    const __m512 reciprocal = _mm512_mul_ps(guess, _mm512_fnmadd_ps(vn, guess, two));
    const __m512 tau = _mm512_maskz_mul_ps(hit, depth, reciprocal);
    const __m512 impact = min16(_mm512_fmadd_ps(gn, tau, vn), zero);
    const __m512 rise = _mm512_mul_ps(minus_e, impact);
    const __m512 height = max16(_mm512_mul_ps(tau, _mm512_fnmadd_ps(half_gn, tau, rise)), zero);
    const __m512 climb = _mm512_fnmadd_ps(gn, tau, rise);
    const __m512 after = _mm512_mask_mov_ps(max16(climb, zero),
                                            _mm512_cmp_ps_mask(height, zero, _CMP_GT_OQ), climb);
    const __m512 lift = _mm512_mask_sub_ps(max16(_mm512_sub_ps(zero, depth), zero), hit,
                                           height, depth);
    const __m512 keep = _mm512_mask_mov_ps(one, hit, keep_t);
    const __m512 normal = _mm512_maskz_mov_ps(hit, _mm512_fnmadd_ps(keep_t, vn, after));
    _mm512_mask_storeu_ps(x + j, m, _mm512_fmadd_ps(lift, n_x, px));
    _mm512_mask_storeu_ps(y + j, m, _mm512_fmadd_ps(lift, n_y, py));
    _mm512_mask_storeu_ps(z + j, m, _mm512_fmadd_ps(lift, n_z, pz));
    _mm512_mask_storeu_ps(vx + j, m, _mm512_fmadd_ps(normal, n_x, _mm512_mul_ps(keep, ux)));
    _mm512_mask_storeu_ps(vy + j, m, _mm512_fmadd_ps(normal, n_y, _mm512_mul_ps(keep, uy)));
    _mm512_mask_storeu_ps(vz + j, m, _mm512_fmadd_ps(normal, n_z, _mm512_mul_ps(keep, uz)));
  }
}
#endif

}  // namespace

void ParticleSystem::update_range(std::size_t begin, std::size_t end, float dt) {
  const float restitution = static_cast<float>(def_.restitution);
  const float keep_tangential = static_cast<float>(1.0 - def_.friction);
#ifdef RTP_PARTICLES_AVX512
  const auto collide_block = avx512_ ? collide_avx512 : collide;
#else
  const auto collide_block = collide;
#endif
  Block a, stage_p, stage_v;
  for (std::size_t first = begin; first < end; first += kBlock) {
    const std::size_t n = std::min(kBlock, end - first);
    float* x = px_.data() + first;
    float* y = py_.data() + first;
    float* z = pz_.data() + first;
    float* vx = vx_.data() + first;
    float* vy = vy_.data() + first;
    float* vz = vz_.data() + first;

    // integrate
    accelerate(first, n, x, y, z, vx, vy, vz, a.x, a.y, a.z);
    if (def_.integrator == ParticleIntegrator::Midpoint) {
      midpoint_stage(n, 0.5f * dt, x, y, z, vx, vy, vz, a.x, a.y, a.z, stage_p.x, stage_p.y,
                     stage_p.z, stage_v.x, stage_v.y, stage_v.z);
      accelerate(first, n, stage_p.x, stage_p.y, stage_p.z, stage_v.x, stage_v.y, stage_v.z, a.x,
                 a.y, a.z);
      midpoint_finish(n, dt, x, y, z, vx, vy, vz, stage_v.x, stage_v.y, stage_v.z, a.x, a.y, a.z);
    } else {
      kick_drift(def_.integrator, n, dt, x, y, z, vx, vy, vz, a.x, a.y, a.z);
    }

    for (const ParticlePlane& plane : def_.planes)
      collide_block(n, float(plane.normal.x()), float(plane.normal.y()), float(plane.normal.z()),
                    float(plane.point.dot(plane.normal)), float(-def_.gravity.dot(plane.normal)),
                    restitution, keep_tangential, x, y, z, vx, vy, vz);
  }
}

void ParticleSystem::step(double dt) {
  const std::size_t n = px_.size();
  const float h = static_cast<float>(dt);
  // both cores for large counts: one contiguous range per thread, no allocation
  const int threads = def_.threads > 1 && n >= 16384 ? def_.threads : 1;
#pragma omp parallel for num_threads(threads) schedule(static)
  for (int t = 0; t < threads; ++t) {
    const std::size_t chunk = (n + threads - 1) / threads;
    const std::size_t begin = std::min(n, t * chunk);
    update_range(begin, std::min(n, begin + chunk), h);
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
