// Each peer adapter loads a scene and shows a physical fact about its result. These check the
// adapters' mapping (frames, units, mass properties), not the peers' quality.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "physbench/particle_driver.h"
#include "physbench/scenarios.h"
#include "support.h"
#include "physbench/registry.h"

// the linked MuJoCo build's name ("mujoco-2.2" where MuJoCo 4, in physbench-mujoco4, is the
// mujoco row)
static const std::string kMujoco = physbench::mujoco_engine_name();

namespace {

using namespace physbench;
using physbench::testing::measure;

// a projectile with a general orientation and spin: frame conversions have nowhere to hide
Scene turned_projectile(bool planar) {
  Scene scene = planar ? projectile_planar_scene() : projectile_scene();
  scene.bodies[0].orientation = planar ? Quat(Eigen::AngleAxisd(0.8, Vec3::UnitZ()))
                                       : Quat(Eigen::AngleAxisd(0.8, Vec3(1, 2, 3).normalized()));
  return scene;
}

void expect_initial_state_read_back(const std::string& engine, const std::string& variant,
                                    bool planar, double tolerance) {
  const Scene scene = turned_projectile(planar);
  const RunResult r = measure(engine, variant, scene).run;
  ASSERT_FALSE(r.trajectory.samples.empty());
  const SampledState& s = r.trajectory.samples.front().bodies[0];
  const BodySpec& b = scene.bodies[0];
  EXPECT_LT((s.position - b.position).norm(), tolerance) << engine;
  EXPECT_LT(orientation_angle(s.orientation, b.orientation), tolerance) << engine;
  EXPECT_LT((s.linear_velocity - b.linear_velocity).norm(), tolerance) << engine;
  EXPECT_LT((s.angular_velocity - b.angular_velocity).norm(), tolerance) << engine;
}

// semi-implicit Euler under constant gravity ends ½ g dt T behind the parabola
void expect_semi_implicit_signature(const std::string& engine, const std::string& variant,
                                    bool planar, double tolerance) {
  const Scene scene = planar ? projectile_planar_scene() : projectile_scene();
  const auto m = measure(engine, variant, scene);
  ASSERT_TRUE(m.summary.position);
  EXPECT_NEAR(m.summary.position->final, 0.5 * scene.gravity.norm() * scene.dt * scene.duration,
              tolerance)
      << engine << "/" << variant;
}

// Across each scheduled push of pushed-box, from the sample before to the sample after, linear
// momentum jumps by J and angular momentum about the origin by p × J (zero gravity, one step of
// the engine's own drift in between): a push at the wrong step, point or frame breaks one of them.
void expect_impulses_land(const std::string& engine, const std::string& variant, bool planar,
                          double angular_tolerance) {
  const Scene scene = pushed_box_scene(planar);
  const RunResult r = measure(engine, variant, scene).run;
  const BodySpec& b = scene.bodies[0];
  auto momenta = [&](const SampledState& s) {
    const Mat3 rotation = s.orientation.toRotationMatrix();
    const Vec3 p = b.mass * s.linear_velocity;
    const Vec3 spin = rotation * principal_inertia(b.shape, b.mass).asDiagonal() *
                      rotation.transpose() * s.angular_velocity;
    return std::pair<Vec3, Vec3>(p, spin + s.position.cross(p));
  };
  for (const ImpulseSpec& push : scene.impulses) {
    const auto after = std::find_if(r.trajectory.samples.begin(), r.trajectory.samples.end(),
                                    [&](const Sample& x) { return x.time > push.time + 1e-9; });
    ASSERT_TRUE(after != r.trajectory.samples.end() && after != r.trajectory.samples.begin());
    const auto [p0, l0] = momenta(std::prev(after)->bodies[0]);
    const auto [p1, l1] = momenta(after->bodies[0]);
    const Vec3 expected = push.point.cross(push.impulse);
    EXPECT_LT((p1 - p0 - push.impulse).norm(), 1e-5) << engine << " at t = " << push.time;
    EXPECT_LT((l1 - l0 - expected).norm(), angular_tolerance * expected.norm())
        << engine << "/" << variant << " at t = " << push.time;
  }
}

// a native implicit spring holds a stiff spring at a step where explicit integration explodes,
// and pays in energy: the soft constraint is implicit Euler, which damps
void expect_native_spring_holds_but_damps(const std::string& engine, const std::string& variant) {
  Scene scene = stiff_spring_scene(1e4);
  scene.dt = 1.0 / 30.0;  // ω dt = 3.3: every explicit method here explodes
  const auto m = measure(engine, variant, scene);
  ASSERT_EQ(m.run.status, Status::Ok) << m.run.message;
  const Trajectory reference = analytic_reference(scene, m.run.trajectory);
  EXPECT_EQ(stability_of(scene, compare(scene, m.run.trajectory, &reference)), "over-damped")
      << engine << "/" << variant;
}

// the apex heights of particles-bounce after each impact, from the probed particle's samples
std::vector<double> bounce_apexes(const std::string& engine, const std::string& variant) {
  const Trajectory run = measure(engine, variant, particles_bounce_scene()).run.trajectory;
  std::vector<double> apexes;
  for (std::size_t k = 1; k < run.samples.size(); ++k)
    if (run.samples[k - 1].bodies[0].linear_velocity.y() > 0.0 &&
        run.samples[k].bodies[0].linear_velocity.y() <= 0.0)
      apexes.push_back(run.samples[k].bodies[0].position.y());
  return apexes;
}

// the first `count` apexes of particles-bounce (e = 0.8, from 1 m) are e^(2n) m within 3 cm
void expect_apexes_follow_restitution(const std::string& engine, const std::string& variant,
                                      std::size_t count) {
  const std::vector<double> apexes = bounce_apexes(engine, variant);
  ASSERT_GE(apexes.size(), count) << engine << "/" << variant;
  for (std::size_t n = 1; n <= count; ++n)
    EXPECT_NEAR(apexes[n - 1], std::pow(0.8, 2.0 * double(n)), 0.03)
        << engine << "/" << variant << " apex " << n;
}

// The planar attractor mode: every probed particle stays in z = 0 and above every plane. An engine
// that detects contacts at the end of a step may find a particle below a plane by up to one
// step's travel (they reach ~14 m/s near an attractor); by the last sample every one must be out
// again, within `sink`. A line placed on the wrong side, or too short, loses particles for good.
void expect_planar_particles_stay_above(const std::string& engine, const std::string& variant,
                                        double sink) {
  Scene scene = planar_particles(particles_attractors_scene(400));
  scene.particles->probe.clear();
  for (long i = 0; i < 40; ++i) scene.particles->probe.push_back(i * 10);
  SimulateOptions options;
  options.timing_budget = 0.0;
  const RunResult r = simulate(physbench::testing::engine(engine), variant, scene, options);
  ASSERT_EQ(r.status, Status::Ok) << r.message;
  ASSERT_GT(r.trajectory.samples.size(), 100u);
  auto lowest_in = [&](const Sample& sample) {
    double lowest = std::numeric_limits<double>::infinity();
    for (const SampledState& particle : sample.bodies)
      for (const ParticlePlaneSpec& plane : scene.particles->planes)
        lowest = std::min(lowest, plane.normal.dot(particle.position - plane.point));
    return lowest;
  };
  double lowest = std::numeric_limits<double>::infinity(), fastest = 0.0, off_plane = 0.0;
  for (const Sample& sample : r.trajectory.samples) {
    lowest = std::min(lowest, lowest_in(sample));
    for (const SampledState& particle : sample.bodies) {
      fastest = std::max(fastest, particle.linear_velocity.norm());
      off_plane = std::max(off_plane, std::abs(particle.position.z()));
    }
  }
  EXPECT_LT(off_plane, 1e-9) << engine;
  EXPECT_GT(lowest, -(sink + fastest * scene.dt)) << engine << "/" << variant;
  EXPECT_GT(lowest_in(r.trajectory.samples.back()), -sink) << engine << "/" << variant;
}

// every engine starts the same particles: the shared driver reproduces rtp's emitter
void expect_same_particle_starts_as_rtp(const std::string& engine, const std::string& variant) {
  const Scene scene = particles_attractors_scene(1000);
  SimulateOptions options;
  options.timing_budget = 0.0;
  const RunResult peer = simulate(physbench::testing::engine(engine), variant, scene, options);
  const RunResult ours = simulate(rtp_engine_info(), "midpoint", scene, options);
  ASSERT_EQ(peer.status, Status::Ok) << peer.message;
  const Sample& a = peer.trajectory.samples.front();
  const Sample& b = ours.trajectory.samples.front();
  // the seed modes probe 200 particles spread over the set (the replay viewer's sample)
  ASSERT_EQ(a.bodies.size(), 200u);
  ASSERT_EQ(b.bodies.size(), a.bodies.size());
  for (std::size_t i = 0; i < a.bodies.size(); ++i) {
    EXPECT_LT((a.bodies[i].position - b.bodies[i].position).norm(), 1e-5)
        << engine << " particle " << i;
    EXPECT_LT((a.bodies[i].linear_velocity - b.bodies[i].linear_velocity).norm(), 1e-5) << engine;
  }
}

TEST(Rtp, ParticleBounceApexesFollowRestitution) {
  expect_apexes_follow_restitution("rtp", "midpoint", 2);
}

TEST(Rtp, PlanarParticlesStayAboveThePlanes) {
  // points, kept on or above every plane by the bounce
  expect_planar_particles_stay_above("rtp", "midpoint", 1e-5);
}
TEST(Rtp, ImpulsesLand) { expect_impulses_land("rtp", "rk4", false, 1e-9); }

TEST(Rtp, ReadsBackTheInitialState) { expect_initial_state_read_back("rtp", "rk4", false, 1e-12); }

// Springs as the same force law integrated by the same method give the same trajectory: a peer's
// semi-implicit Euler on the oscillator must match rtp's semi-implicit Euler. A wrong attachment
// point, sign, or a force applied twice or a step late shows up at once.
void expect_same_spring_trajectory_as_rtp(const std::string& engine, const std::string& variant,
                                          const std::string& rtp_variant, const Scene& scene,
                                          double tolerance) {
  const Trajectory peer = measure(engine, variant, scene).run.trajectory;
  const Trajectory ours = measure("rtp", rtp_variant, scene).run.trajectory;
  ASSERT_EQ(peer.samples.size(), ours.samples.size());
  double worst = 0.0;
  for (std::size_t k = 0; k < peer.samples.size(); ++k)
    for (std::size_t b = 0; b < peer.samples[k].bodies.size(); ++b)
      worst = std::max(
          worst, (peer.samples[k].bodies[b].position - ours.samples[k].bodies[b].position).norm());
  EXPECT_LT(worst, tolerance) << engine << "/" << variant << " against rtp/" << rtp_variant
                              << " on " << scene.name;
}

#ifdef PHYSBENCH_HAVE_BULLET
TEST(Bullet, ReadsBackTheInitialState) {
  expect_initial_state_read_back("bullet", "float", false, 1e-6);
}
TEST(Bullet, SpringsMatchRtpSemiImplicitEuler) {
  expect_same_spring_trajectory_as_rtp("bullet", "float", "euler", spring_oscillator_scene(), 1e-5);
}
TEST(Bullet, ImpulsesLand) { expect_impulses_land("bullet", "float", false, 0.02); }
TEST(Bullet, ParticlesStartWhereRtpsDo) { expect_same_particle_starts_as_rtp("bullet", "float"); }
TEST(Bullet, ParticleBounceApexesFollowRestitution) {
  // with split impulse at every depth: Baumgarte correction of the 2 cm the particle sinks used to
  // add speed (first apex 0.84 m)
  expect_apexes_follow_restitution("bullet", "float", 3);
}
TEST(Bullet, PlanarParticlesStayAboveThePlanes) {
  expect_planar_particles_stay_above("bullet", "float", 0.03);
}
TEST(Bullet, ProjectileShowsSemiImplicitEuler) {
  expect_semi_implicit_signature("bullet", "float", false, 1e-4);
}
TEST(Bullet, GyroscopicTorqueIsOnSoTheBoxFlips) {
  // without the gyroscopic term ω stays constant and the intermediate-axis spin never reverses
  const auto run = measure("bullet", "float", tumbling_box_scene()).run.trajectory;
  bool reversed = false;
  for (const Sample& s : run.samples)
    reversed |= (s.bodies[0].orientation.conjugate() * s.bodies[0].angular_velocity).y() < 0.0;
  EXPECT_TRUE(reversed);
}
#endif

#ifdef PHYSBENCH_HAVE_ODE
TEST(Ode, ReadsBackTheInitialState) {
  expect_initial_state_read_back("ode", "quickstep", false, 1e-12);
}
TEST(Ode, SpringsMatchRtpSemiImplicitEuler) {
  expect_same_spring_trajectory_as_rtp("ode", "step", "euler", spring_oscillator_scene(), 1e-12);
}
TEST(Ode, ImpulsesLand) { expect_impulses_land("ode", "step", false, 0.02); }
TEST(Ode, JointSpringHoldsButDamps) { expect_native_spring_holds_but_damps("ode", "step-joint"); }
TEST(Ode, JointVariantOnlyAppliesToSpringScenes) {
  const EngineInfo& ode = physbench::testing::engine("ode");
  EXPECT_FALSE(ode.applies(projectile_scene(), "step-joint"));
  EXPECT_TRUE(ode.applies(spring_oscillator_scene(), "step-joint"));
  EXPECT_TRUE(ode.applies(projectile_scene(), "step"));
}
TEST(Ode, ParticleBounceApexesFollowRestitution) {
  // e = 0.8 from 1 m: apexes 0.64, 0.41 m (centre of a 1 cm sphere: + 0.01 m at most)
  expect_apexes_follow_restitution("ode", "step", 2);
}
TEST(Ode, ParticlesStartWhereRtpsDo) { expect_same_particle_starts_as_rtp("ode", "quickstep"); }
TEST(Ode, PlanarParticlesStayAboveThePlanes) {
  expect_planar_particles_stay_above("ode", "quickstep", 0.03);
}
TEST(Ode, ProjectileShowsSemiImplicitEuler) {
  expect_semi_implicit_signature("ode", "step", false, 1e-9);
}
TEST(Ode, BothSteppersAgreeOnAFreeBody) {
  // with no constraints there is nothing for the two solvers to differ on
  const Scene scene = tumbling_box_scene();
  const auto quick = measure("ode", "quickstep", scene).run.trajectory;
  const auto exact = measure("ode", "step", scene).run.trajectory;
  ASSERT_EQ(quick.samples.size(), exact.samples.size());
  for (std::size_t k = 0; k < quick.samples.size(); ++k)
    ASSERT_LT(orientation_angle(quick.samples[k].bodies[0].orientation,
                                exact.samples[k].bodies[0].orientation),
              1e-12);
}
#endif

#ifdef PHYSBENCH_HAVE_BOX2D
TEST(Box2d, ReadsBackTheInitialState) {
  expect_initial_state_read_back("box2d", "default", true, 1e-6);
}
TEST(Box2d, SpringsMatchRtpSemiImplicitEuler) {
  // a chain in the plane: attachment points off the centre, so spring torques count too
  expect_same_spring_trajectory_as_rtp("box2d", "default", "euler", spring_chain_scene(4), 1e-4);
}
TEST(Box2d, ImpulsesLand) { expect_impulses_land("box2d", "default", true, 1e-5); }
TEST(Box2d, DistanceJointSpringHoldsButDamps) {
  expect_native_spring_holds_but_damps("box2d", "joint");
}
TEST(Box2d, PlanarProjectileShowsSemiImplicitEuler) {
  expect_semi_implicit_signature("box2d", "default", true, 1e-4);
}
TEST(Box2d, SpinIsConstantInFreeFlight) {
  const Scene scene = projectile_planar_scene();
  const auto run = measure("box2d", "default", scene).run.trajectory;
  const SampledState& last = run.samples.back().bodies[0];
  const double expected = scene.bodies[0].angular_velocity.z() * scene.duration;
  const double turned = 2.0 * std::atan2(last.orientation.z(), last.orientation.w());
  EXPECT_NEAR(std::remainder(turned - expected, 2.0 * M_PI), 0.0, 1e-4);
}
TEST(Box2d, ParticleBounceApexesFollowRestitution) {
  // circles on an edge whose 1 cm skin sits below the plane; restitution threshold lowered
  expect_apexes_follow_restitution("box2d", "default", 3);
}
TEST(Box2d, ParticleOrbitMatchesRtpSemiImplicitEuler) {
  // the driver's attractor force applied once per step is semi-implicit Euler, as rtp's "euler"
  expect_same_spring_trajectory_as_rtp("box2d", "default", "euler", particles_orbit_scene(), 1e-4);
}
TEST(Box2d, PlanarParticlesStayAboveThePlanes) {
  expect_planar_particles_stay_above("box2d", "default", 0.03);
}
TEST(Box2d, ParticlesAboveThePeerLimitSayWhy) {
  Scene scene = particles_bounce_scene();
  scene.particles->count = kMaxPeerParticles + 1;
  const auto why = physbench::testing::engine("box2d").unsupported(scene, "default");
  ASSERT_TRUE(why);
  EXPECT_NE(why->find("Box2D"), std::string::npos);
}
TEST(Box2d, RefusesA3dScene) {
  const auto why = physbench::testing::engine("box2d").unsupported(projectile_scene(), "default");
  ASSERT_TRUE(why);
  EXPECT_NE(why->find("2D"), std::string::npos);
}
#endif

#ifdef PHYSBENCH_HAVE_MUJOCO
TEST(Mujoco, ReadsBackTheInitialStateIncludingBodyFrameSpin) {
  expect_initial_state_read_back(kMujoco, "euler", false, 1e-12);
}
TEST(Mujoco, TendonSpringsMatchRtpAtTheSameIntegrator) {
  // MuJoCo's tendon is the scene's spring law evaluated at every stage: RK4 matches rtp's RK4
  // (to 1e-7 m, not round-off: MuJoCo's RK4 integrates orientation differently, see the report)
  expect_same_spring_trajectory_as_rtp(kMujoco, "rk4", "rk4", spring_chain_scene(4), 1e-7);
  expect_same_spring_trajectory_as_rtp(kMujoco, "euler", "euler", spring_oscillator_scene(),
                                       1e-12);
}
TEST(Mujoco, ParticlesStartWhereRtpsDo) { expect_same_particle_starts_as_rtp(kMujoco, "euler"); }
TEST(Mujoco, ParticleOrbitForcesAreSeenAtEveryRk4Stage) {
  // the attractor is a passive force (mjcb_passive): RK4 must beat semi-implicit Euler by
  // orders of magnitude; held through the stages as an applied force it came out 45x worse
  const double rk4 = measure(kMujoco, "rk4", particles_orbit_scene()).summary.position->max;
  const double euler = measure(kMujoco, "euler", particles_orbit_scene()).summary.position->max;
  EXPECT_LT(rk4, 1e-3 * euler) << "rk4 " << rk4 << " m, euler " << euler << " m";
}
TEST(Mujoco, ParticleBounceApexesFollowRestitution) {
  // a soft contact damped to keep 0.8 of the normal speed: apexes 0.64, 0.41 m (it sinks a few
  // cm into the plane meanwhile: MuJoCo's contacts are springs)
  expect_apexes_follow_restitution(kMujoco, "euler", 2);
}
TEST(Mujoco, ParticleSetsBeyondItsLimitSayWhy) {
  const auto why =
      physbench::testing::engine(kMujoco).unsupported(particles_attractors_scene(10000), "euler");
  ASSERT_TRUE(why.has_value());
  EXPECT_NE(why->find("mjData"), std::string::npos) << *why;
}
TEST(Mujoco, ImpulsesLand) { expect_impulses_land(kMujoco, "rk4", false, 1e-3); }
TEST(Mujoco, Rk4ProjectileIsExact) {
  EXPECT_LT(measure(kMujoco, "rk4", projectile_scene()).summary.position->max, 1e-10);
}
TEST(Mujoco, EulerProjectileShowsSemiImplicitEuler) {
  expect_semi_implicit_signature(kMujoco, "euler", false, 1e-9);
}
TEST(Mujoco, Rk4KeepsTumblingBoxEnergy) {
  EXPECT_LT(measure(kMujoco, "rk4", tumbling_box_scene()).summary.energy->max, 1e-6);
}
#endif

}  // namespace
