#include "rtp/particles.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "hash.h"
#include "simd.h"

namespace rtp {

namespace {

// a counter-based random number in [0, 1) (splitmix64): the same particle index and generation
// give the same number on any thread, so emission needs no shared generator
double unit_random(std::uint64_t seed, std::uint64_t index, std::uint64_t salt) {
  const std::uint64_t z = detail::mix64(seed + 0x9E3779B97F4A7C15ull * (index + 1) +
                                        0xBF58476D1CE4E5B9ull * (salt + 1));
  return static_cast<double>(z >> 11) * (1.0 / 9007199254740992.0);
}

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
  // the one run-time dispatch: the AVX-512 kernels where the core has AVX-512F
  avx512_ = def_.kernels == ParticleKernels::Best && simd::core_has_avx512();
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

// The AVX-512 kernels, for cores that have it (chosen at run time, so a portable build uses them
// too): 16 particles per register, and 1/√r² at each attractor and the bounce's 1/vₙ by the
// core's 14-bit estimates and one Newton step each (relative error ≤ 1.5 (2⁻¹⁴)² and (2⁻¹⁴)²,
// under float rounding), where the portable loops take reciprocal_sqrt and divide: fewer vector
// operations, which is what bounds the update in cache (docs/particles.md).
using simd::Float16;
using simd::Mask16;

// a = g + drag (wind − v) + Σ attractors for n particles; wx is null when the scene has no drag
// (no wind is kept then). The attractors are summed in registers.
RTP_SIMD_TARGET_AVX512 void accelerate_avx512(
    std::size_t n, const float* px, const float* py, const float* pz, const float* vx,
    const float* vy, const float* vz, const float* wx, const float* wy, const float* wz,
    const std::array<float, 3>& gravity, float drag, const std::array<float, 4>* attractors,
    std::size_t count, float eps2, float* ax, float* ay, float* az) {
  using namespace simd;
  const Float16 half = splat16(0.5f), three_halves = splat16(1.5f), softening = splat16(eps2),
                k = splat16(drag), gx = splat16(gravity[0]), gy = splat16(gravity[1]),
                gz = splat16(gravity[2]);
  for (std::size_t j = 0; j < n; j += 16) {
    const Mask16 m = lanes_below(n, j);
    const Float16 x = load16(m, px + j), y = load16(m, py + j), z = load16(m, pz + j);
    Float16 sx = load16(m, vx + j), sy = load16(m, vy + j), sz = load16(m, vz + j);
    if (wx) {
      sx = fmadd(k, sub(load16(m, wx + j), sx), gx);
      sy = fmadd(k, sub(load16(m, wy + j), sy), gy);
      sz = fmadd(k, sub(load16(m, wz + j), sz), gz);
    } else {
      sx = fnmadd(k, sx, gx);
      sy = fnmadd(k, sy, gy);
      sz = fnmadd(k, sz, gz);
    }
    for (std::size_t i = 0; i < count; ++i) {
      const std::array<float, 4>& a = attractors[i];
      const Float16 rx = sub(splat16(a[0]), x), ry = sub(splat16(a[1]), y),
                    rz = sub(splat16(a[2]), z);
      const Float16 r2 = fmadd(rx, rx, fmadd(ry, ry, fmadd(rz, rz, softening)));
      // y ← y (3/2 − r² y²/2) from the estimate
      const Float16 guess = rsqrt_estimate(r2);
      const Float16 half_r2_guess = mul(mul(half, r2), guess);
      const Float16 inverse = mul(guess, fnmadd(half_r2_guess, guess, three_halves));
      const Float16 scale = mul(mul(splat16(a[3]), inverse), mul(inverse, inverse));
      sx = fmadd(scale, rx, sx);
      sy = fmadd(scale, ry, sy);
      sz = fmadd(scale, rz, sz);
    }
    store16(ax + j, m, sx);
    store16(ay + j, m, sy);
    store16(az + j, m, sz);
  }
}

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
  if (avx512_) {
    const bool wind = !wx_.empty();
    accelerate_avx512(n, px, py, pz, vx, vy, vz, wind ? wx_.data() + first : nullptr,
                      wind ? wy_.data() + first : nullptr, wind ? wz_.data() + first : nullptr,
                      {gx, gy, gz}, drag, attractors_.data(), attractors_.size(), eps2, ax, ay,
                      az);
    return;
  }
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
// hands every bounce the (1 + e) gₙ τ it gained below the plane, and the apexes come out high
// (docs/particles.md). Its tangential velocity loses the friction fraction; it never ends below the plane.
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

// collide() with AVX-512: the same arithmetic, 1/vₙ from the estimate and r ← r (2 − vₙ r)
RTP_SIMD_TARGET_AVX512 void collide_avx512(std::size_t n, float nx, float ny, float nz,
                                           float offset, float gravity_into_plane,
                                           float restitution, float keep_tangential, float* x,
                                           float* y, float* z, float* vx, float* vy, float* vz) {
  using namespace simd;
  const Float16 n_x = splat16(nx), n_y = splat16(ny), n_z = splat16(nz), plane = splat16(offset),
                gn = splat16(gravity_into_plane), half_gn = splat16(0.5f * gravity_into_plane),
                minus_e = splat16(-restitution), keep_t = splat16(keep_tangential),
                zero = zero16(), one = splat16(1.0f), two = splat16(2.0f);
  for (std::size_t j = 0; j < n; j += 16) {
    const Mask16 m = lanes_below(n, j);
    const Float16 px = load16(m, x + j), py = load16(m, y + j), pz = load16(m, z + j),
                  ux = load16(m, vx + j), uy = load16(m, vy + j), uz = load16(m, vz + j);
    const Float16 depth = fmadd(px, n_x, fmadd(py, n_y, fmsub(pz, n_z, plane)));
    const Float16 vn = fmadd(ux, n_x, fmadd(uy, n_y, mul(uz, n_z)));
    const Mask16 hit = less(depth, zero) & less(vn, zero);
    const Float16 guess = reciprocal_estimate(vn);
    const Float16 reciprocal = mul(guess, fnmadd(vn, guess, two));
    const Float16 tau = select_or_zero(hit, mul(depth, reciprocal));
    const Float16 impact = min(fmadd(gn, tau, vn), zero);
    const Float16 rise = mul(minus_e, impact);
    const Float16 height = max(mul(tau, fnmadd(half_gn, tau, rise)), zero);
    const Float16 climb = fnmadd(gn, tau, rise);
    const Float16 after = select(greater(height, zero), climb, max(climb, zero));
    const Float16 lift = select(hit, sub(height, depth), max(sub(zero, depth), zero));
    const Float16 keep = select(hit, keep_t, one);
    const Float16 normal = select_or_zero(hit, fnmadd(keep_t, vn, after));
    store16(x + j, m, fmadd(lift, n_x, px));
    store16(y + j, m, fmadd(lift, n_y, py));
    store16(z + j, m, fmadd(lift, n_z, pz));
    store16(vx + j, m, fmadd(normal, n_x, mul(keep, ux)));
    store16(vy + j, m, fmadd(normal, n_y, mul(keep, uy)));
    store16(vz + j, m, fmadd(normal, n_z, mul(keep, uz)));
  }
}

}  // namespace

void ParticleSystem::update_range(std::size_t begin, std::size_t end, float dt) {
  const float restitution = static_cast<float>(def_.restitution);
  const float keep_tangential = static_cast<float>(1.0 - def_.friction);
  const auto collide_block = avx512_ ? collide_avx512 : collide;
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
