// rtp particles against closed forms and the seed's promises for each mode.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <tuple>
#include <vector>

#include "rtp/particles.h"

namespace {

using rtp::ParticleIntegrator;
using rtp::ParticleSystem;
using rtp::ParticleSystemDef;
using rtp::Vec3;

ParticleSystemDef one_particle(Vec3 position, Vec3 velocity) {
  ParticleSystemDef def;
  def.count = 1;
  def.spawn_min = def.spawn_max = position;
  def.velocity_min = def.velocity_max = velocity;
  return def;
}

TEST(Particles, BounceApexHeightsFallAsRestitutionSquared) {
  // dropped from 1 m onto y = 0 with e = 0.8: the n-th apex is e^(2n) m
  ParticleSystemDef def = one_particle(Vec3(0, 1, 0), Vec3::Zero());
  def.planes = {rtp::ParticlePlane{}};
  def.restitution = 0.8;
  def.integrator =
      ParticleIntegrator::Midpoint;  // exact in free flight: what is left is the bounce
  ParticleSystem particles(def);
  std::vector<double> apexes;
  double previous_vy = 0.0;
  for (int i = 0; i < 4000 && apexes.size() < 4; ++i) {
    particles.step(1e-3);
    const double vy = particles.velocity(0).y();
    if (previous_vy > 0.0 && vy <= 0.0) apexes.push_back(particles.position(0).y());
    previous_vy = vy;
  }
  ASSERT_EQ(apexes.size(), 4u);
  for (std::size_t n = 0; n < apexes.size(); ++n) {
    const double expected = std::pow(0.8, 2.0 * (n + 1));
    EXPECT_NEAR(apexes[n], expected, 0.01 * expected + 2e-3)
        << "apex " << n + 1;  // 1 % and a step's rise
  }
}

// a particle on a circular orbit around one attractor: speed √(s/r) at radius r (ε ≪ r)
double orbit_radius_error(ParticleIntegrator integrator, double dt) {
  const double strength = 10.0, radius = 2.0;
  ParticleSystemDef def =
      one_particle(Vec3(radius, 0, 0), Vec3(0, 0, std::sqrt(strength / radius)));
  def.gravity = Vec3::Zero();
  def.attractors = {rtp::Attractor{Vec3::Zero(), strength}};
  def.softening = 1e-4;
  def.integrator = integrator;
  ParticleSystem particles(def);
  const double period = 2.0 * M_PI * std::sqrt(radius * radius * radius / strength);
  double worst = 0.0;
  for (long i = 0; i < std::lround(period / dt); ++i) {
    particles.step(dt);
    worst = std::max(worst, std::abs(particles.position(0).norm() - radius));
  }
  return worst;
}

TEST(Particles, OrbitMidpointBeatsEuler) {
  const double dt = 1.0 / 120.0;
  const double midpoint = orbit_radius_error(ParticleIntegrator::Midpoint, dt);
  const double semi = orbit_radius_error(ParticleIntegrator::SemiImplicitEuler, dt);
  const double explicit_euler = orbit_radius_error(ParticleIntegrator::ExplicitEuler, dt);
  EXPECT_LT(midpoint, semi);
  EXPECT_LT(midpoint, explicit_euler);
  EXPECT_LT(midpoint, 1e-3 * 2.0);  // float state: a radius held to 0.1 % over one orbit
}

TEST(Particles, ParticleAtAnAttractorStaysFinite) {
  ParticleSystemDef def = one_particle(Vec3(1, 2, 3), Vec3::Zero());
  def.attractors = {rtp::Attractor{Vec3(1, 2, 3), 50.0}, rtp::Attractor{Vec3(1, 2, 3), -80.0}};
  ParticleSystem particles(def);
  for (int i = 0; i < 100; ++i) particles.step(1.0 / 60.0);
  EXPECT_TRUE(particles.position(0).allFinite());
  EXPECT_TRUE(particles.velocity(0).allFinite());
}

TEST(Particles, SnowSticksToThePlane) {
  // zero restitution and full friction: once a flake touches the ground it stays on it
  ParticleSystemDef def;
  def.count = 2000;
  def.spawn_min = Vec3(-1, 0.0, -1);
  def.spawn_max = Vec3(1, 0.5, 1);
  def.velocity_min = Vec3(-0.2, -1, -0.2);
  def.velocity_max = Vec3(0.2, 0, 0.2);
  def.planes = {rtp::ParticlePlane{}};
  def.restitution = 0.0;
  def.friction = 1.0;
  def.drag = 1.0;
  def.wind = Vec3(0.5, 0, 0);
  def.wind_jitter = 0.2;
  def.integrator = ParticleIntegrator::SemiImplicitEuler;
  ParticleSystem snow(def);
  std::vector<bool> landed(def.count, false);
  for (int step = 0; step < 600; ++step) {
    snow.step(1.0 / 60.0);
    for (std::size_t i = 0; i < def.count; ++i) {
      const double y = snow.position(i).y();
      ASSERT_GE(y, -1e-6) << "particle " << i << " sank";
      if (landed[i]) {
        ASSERT_LT(y, 1e-5) << "particle " << i << " left the ground";
      }
      landed[i] = landed[i] || y < 1e-6;
    }
  }
  EXPECT_EQ(std::count(landed.begin(), landed.end(), true), static_cast<long>(def.count));
}

TEST(Particles, RecyclingKeepsTheCountAndTheBuffers) {
  ParticleSystemDef def;
  def.count = 5000;
  def.spawn_min = Vec3(-1, 4, -1);
  def.spawn_max = Vec3(1, 5, 1);
  def.lifetime = 0.5;
  def.drag = 0.5;
  ParticleSystem particles(def);
  const float* buffer = particles.x_data();
  for (int i = 0; i < 120; ++i)
    particles.step(1.0 / 60.0);  // 2 s: every particle re-emitted ~4 times
  EXPECT_EQ(particles.x_data(), buffer) << "recycling reallocated the particle arrays";
  EXPECT_EQ(particles.size(), def.count);
  EXPECT_GT(particles.recycled(), 3 * def.count);
  for (std::size_t i = 0; i < def.count; ++i) {
    ASSERT_LT(particles.age(i), def.lifetime);
    ASSERT_GT(particles.position(i).y(), -5.0) << "a particle outlived its lifetime";
  }
}

TEST(Particles, PlumeFrictionDragsParticlesAlongThePlane) {
  // high friction: particles sliding on the ground lose most of their tangential speed per contact
  auto slide = [](double friction) {
    ParticleSystemDef def = one_particle(Vec3(0, 0, 0), Vec3(3, 0, 0));
    def.planes = {rtp::ParticlePlane{}};
    def.restitution = 0.0;
    def.friction = friction;
    def.integrator = ParticleIntegrator::SemiImplicitEuler;
    ParticleSystem particles(def);
    for (int i = 0; i < 60; ++i) particles.step(1.0 / 60.0);
    return particles.position(0).x();
  };
  EXPECT_LT(slide(0.9), 0.2 * slide(0.0));
}

TEST(Particles, TwoThreadsGiveTheSameStateAsOne) {
  auto run = [](int threads) {
    ParticleSystemDef def;
    def.count = 40000;
    def.spawn_min = Vec3(-2, 1, -2);
    def.spawn_max = Vec3(2, 3, 2);
    def.attractors = {rtp::Attractor{Vec3(0, 2, 0), 5.0}};
    def.planes = {rtp::ParticlePlane{}};
    def.lifetime = 1.0;
    def.threads = threads;
    ParticleSystem p(def);
    for (int i = 0; i < 30; ++i) p.step(1.0 / 60.0);
    return p;
  };
  const ParticleSystem one = run(1), two = run(2);
  for (std::size_t i = 0; i < one.size(); i += 97) ASSERT_EQ(one.position(i), two.position(i)) << i;
}

// The hand-written AVX-512 kernels (on cores that have them) compute what the portable loops do:
// the seed's attractor mode, 4,099 particles (the last block holds 3: a partial group of 16, the
// masked tail), with per-particle wind and without drag (no wind arrays). After one step every particle agrees to float rounding;
// after sixty, bounces amplify rounding, but 99 % still agree to 0.1 mm (measured: 1e-5 m).
TEST(Particles, Avx512KernelsMatchThePortableOnes) {
  ParticleSystemDef def;
  def.count = 4099;
  def.spawn_min = Vec3(-3, 0.5, -3);
  def.spawn_max = Vec3(3, 5, 3);
  def.velocity_min = Vec3(-1, -3, -1);
  def.velocity_max = Vec3(1, 1, 1);
  def.attractors = {rtp::Attractor{Vec3(-2, 3, 0), 20.0}, rtp::Attractor{Vec3(2, 3, 1), 15.0},
                    rtp::Attractor{Vec3(0, 4, -2), -10.0}};
  def.softening = 0.2;
  def.planes = {rtp::ParticlePlane{Vec3::Zero(), Vec3(0.25, 1.0, 0.0).normalized()},
                rtp::ParticlePlane{Vec3::Zero(), Vec3(-0.25, 1.0, 0.1).normalized()},
                rtp::ParticlePlane{Vec3::Zero(), Vec3(0.0, 1.0, -0.25).normalized()}};
  def.restitution = 0.6;
  def.friction = 0.1;
  def.wind = Vec3(0.5, 0, 0);
  def.wind_jitter = 0.3;
  if (std::string(ParticleSystem(def).kernels()) != "avx512")
    GTEST_SKIP() << "this core has no AVX-512: only the portable kernels run";
  for (const double drag : {0.1, 0.0}) {
    def.drag = drag;
    def.kernels = rtp::ParticleKernels::Best;
    ParticleSystem fast(def);
    def.kernels = rtp::ParticleKernels::Portable;
    ParticleSystem portable(def);
    ASSERT_STREQ(portable.kernels(), "portable");
    // the largest position and velocity differences, or the given quantile of them
    auto differences = [&](double quantile) {
      std::vector<double> dx(fast.size()), dv(fast.size());
      for (std::size_t i = 0; i < dx.size(); ++i) {
        dx[i] = (fast.position(i) - portable.position(i)).norm();
        dv[i] = (fast.velocity(i) - portable.velocity(i)).norm();
      }
      std::sort(dx.begin(), dx.end());
      std::sort(dv.begin(), dv.end());
      const auto at = std::size_t(quantile * double(dx.size() - 1));
      return std::pair{dx[at], dv[at]};
    };
    // one step from the spawn box, above every plane: no bounce, forces only. The velocities
    // change by a dt ≈ 0.3 m/s; an attractor's 1/√r² to 14 bits (no Newton step) would differ
    // by ~2e-5 m/s
    fast.step(1.0 / 60.0);
    portable.step(1.0 / 60.0);
    auto [dx, dv] = differences(1.0);
    EXPECT_LT(dx, 2e-6) << "drag " << drag;
    EXPECT_LT(dv, 2e-6) << "drag " << drag;
    for (int i = 1; i < 60; ++i) fast.step(1.0 / 60.0), portable.step(1.0 / 60.0);
    std::tie(dx, dv) = differences(0.99);
    EXPECT_LT(dx, 1e-4) << "drag " << drag;
    EXPECT_LT(dv, 1e-3) << "drag " << drag;
  }
}

// the update's 1/√x is as good as float arithmetic allows: within 2.5e-7 (two ulps) of the
// double-precision value from 1e-30 to 1e30, sampled ten thousand times a decade
TEST(Particles, ReciprocalSquareRootIsWithinTwoUlps) {
  double worst = 0.0, worst_at = 0.0;
  for (int k = -300000; k <= 300000; ++k) {
    const auto x = static_cast<float>(std::pow(10.0, k * 1e-4));
    const double exact = 1.0 / std::sqrt(static_cast<double>(x));
    const double error = std::abs(static_cast<double>(rtp::reciprocal_sqrt(x)) - exact) / exact;
    if (error > worst) worst = error, worst_at = x;
  }
  EXPECT_LT(worst, 2.5e-7) << "at x = " << worst_at;
}

}  // namespace
