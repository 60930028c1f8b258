// rtp unit tests: integrator order, invariants, impulses and spring torque, each against
// a closed form; and what a contact step's profile times.
#include <gtest/gtest.h>

#include <cmath>

#include "contact_worlds.h"
#include "rtp/world.h"

namespace {

using rtp::BodyDef;
using rtp::Integrator;
using rtp::Quat;
using rtp::Vec3;
using rtp::World;

constexpr double kPi = 3.14159265358979323846;

void expect_finite(const World& world) {
  for (rtp::BodyId i = 0; i < world.body_count(); ++i) {
    const rtp::BodyState& s = world.state(i);
    ASSERT_TRUE(s.position.allFinite() && s.linear_momentum.allFinite() &&
                s.orientation.coeffs().allFinite() && s.angular_momentum.allFinite())
        << "body " << i << " has a non-finite state";
  }
}

// largest |E − E0| / E0 of a world stepped for a duration
double largest_energy_drift(World world, double dt, double duration) {
  const double initial = world.mechanical_energy();
  double worst = 0.0;
  for (long i = 0; i < std::lround(duration / dt); ++i) {
    world.step(dt);
    worst = std::max(worst, std::abs(world.mechanical_energy() - initial) / initial);
  }
  return worst;
}

// a 1 kg mass on a k = 100 N/m spring from the origin, released 0.1 m out, no gravity:
// x(t) = 0.1 cos(ω t), ω = 10 rad/s
struct Oscillator {
  static constexpr double kStiffness = 100.0, kMass = 1.0, kAmplitude = 0.1;
  static double omega() { return std::sqrt(kStiffness / kMass); }

  static World make(Integrator integrator) {
    World world(Vec3::Zero(), integrator);
    BodyDef def;
    def.mass = kMass;
    def.position = Vec3(kAmplitude, 0.0, 0.0);
    const rtp::BodyId body = world.add_body(def);
    rtp::SpringDef spring;
    spring.body_a = body;
    spring.stiffness = kStiffness;
    world.add_spring(spring);
    return world;
  }

  // position error at t = duration
  static double error(Integrator integrator, double dt, double duration) {
    World world = make(integrator);
    const long steps = std::lround(duration / dt);
    for (long i = 0; i < steps; ++i) world.step(dt);
    expect_finite(world);
    const double exact = kAmplitude * std::cos(omega() * steps * dt);
    return std::abs(world.state(0).position.x() - exact);
  }

  static double energy_drift(Integrator integrator, double dt, double duration) {
    return largest_energy_drift(make(integrator), dt, duration);
  }
};

// observed order from the error at dt and dt/2: log2(e(dt) / e(dt/2))
double observed_order(Integrator integrator, double dt) {
  return std::log2(Oscillator::error(integrator, dt, 1.0) /
                   Oscillator::error(integrator, dt / 2.0, 1.0));
}

TEST(Integrators, Rk4ErrorFallsAbout16TimesWhenDtHalves) {
  const double coarse = Oscillator::error(Integrator::RungeKutta4, 1.0 / 60.0, 1.0);
  const double fine = Oscillator::error(Integrator::RungeKutta4, 1.0 / 120.0, 1.0);
  EXPECT_GT(coarse / fine, 13.0);
  EXPECT_LT(coarse / fine, 19.5);
}

TEST(Integrators, ObservedOrderMatchesTheory) {
  // orders within ±0.3 of theory: semi-implicit Euler 1, midpoint 2, RK4 4
  EXPECT_NEAR(observed_order(Integrator::SemiImplicitEuler, 1.0 / 240.0), 1.0, 0.3);
  EXPECT_NEAR(observed_order(Integrator::Midpoint, 1.0 / 240.0), 2.0, 0.3);
  EXPECT_NEAR(observed_order(Integrator::RungeKutta4, 1.0 / 60.0), 4.0, 0.3);
}

TEST(Integrators, Rk4KeepsOscillatorEnergyToOnePartIn1e5) {
  EXPECT_LT(Oscillator::energy_drift(Integrator::RungeKutta4, 1.0 / 120.0, 10.0), 1e-5);
}

TEST(Integrators, EnergyErrorOrderedRk4BelowMidpointBelowEulerOverOnePeriodsWorth) {
  const double dt = 1.0 / 60.0, duration = 1.0;
  const double rk4 = Oscillator::energy_drift(Integrator::RungeKutta4, dt, duration);
  const double midpoint = Oscillator::energy_drift(Integrator::Midpoint, dt, duration);
  const double euler = Oscillator::energy_drift(Integrator::SemiImplicitEuler, dt, duration);
  EXPECT_LT(rk4, midpoint);
  EXPECT_LT(midpoint, euler);
}

TEST(Integrators, SemiImplicitEulerEnergyStaysBoundedWhereMidpointGrows) {
  // symplectic Euler's energy error oscillates with amplitude about ω dt / 2 and never grows;
  // midpoint's grows every period, so over 100 s it passes Euler's
  const double dt = 1.0 / 60.0;
  const double bound = 0.6 * Oscillator::omega() * dt;
  const double euler = Oscillator::energy_drift(Integrator::SemiImplicitEuler, dt, 100.0);
  EXPECT_LT(euler, bound);
  EXPECT_GT(Oscillator::energy_drift(Integrator::Midpoint, dt, 100.0), euler);
}

// a free asymmetric box spinning near its intermediate axis
World tumbling(Integrator integrator) {
  World world(Vec3::Zero(), integrator);
  BodyDef def;
  def.mass = 1.0;
  def.principal_inertia = Vec3(97.0, 82.0, 17.0) / 12.0;  // a 1 x 4 x 9 box
  def.angular_velocity = Vec3(0.01, 2.0, 0.0);
  def.orientation = Quat(Eigen::AngleAxisd(0.3, Vec3(1, 2, 3).normalized()));
  world.add_body(def);
  return world;
}

TEST(Integrators, QuaternionStaysNormalised) {
  for (Integrator integrator :
       {Integrator::SemiImplicitEuler, Integrator::Midpoint, Integrator::RungeKutta4}) {
    World world = tumbling(integrator);
    for (int i = 0; i < 2000; ++i) world.step(1.0 / 30.0);
    expect_finite(world);
    EXPECT_NEAR(world.state(0).orientation.norm(), 1.0, 1e-12);
  }
}

TEST(Integrators, TorqueFreeAngularMomentumIsConservedByEveryIntegrator) {
  for (Integrator integrator :
       {Integrator::SemiImplicitEuler, Integrator::Midpoint, Integrator::RungeKutta4}) {
    World world = tumbling(integrator);
    const Vec3 initial = world.state(0).angular_momentum;
    for (int i = 0; i < 1000; ++i) world.step(1.0 / 60.0);
    // the world-frame L derived from the integrated state, not the stored momentum alone
    const Vec3 derived = world.inertia_world(0) * world.angular_velocity(0);
    EXPECT_LT((derived - initial).norm() / initial.norm(), 1e-12);
  }
}

double tumbling_energy_drift(Integrator integrator, double dt, double duration) {
  return largest_energy_drift(tumbling(integrator), dt, duration);
}

TEST(Integrators, SymplecticSplittingKeepsFreeRotationEnergyBounded) {
  // over 200 s of tumbling, the splitting's energy error stays small and does not grow;
  // semi-implicit Euler's, with ω from the old orientation, does
  const double dt = 1.0 / 60.0;
  const double short_run = tumbling_energy_drift(Integrator::Symplectic, dt, 20.0);
  const double long_run = tumbling_energy_drift(Integrator::Symplectic, dt, 200.0);
  EXPECT_LT(long_run, 1e-3);
  EXPECT_LT(long_run, 2.0 * short_run + 1e-12);
  EXPECT_GT(tumbling_energy_drift(Integrator::SemiImplicitEuler, dt, 200.0), 100.0 * long_run);
}

TEST(Integrators, SymplecticSplittingIsSecondOrderForFreeRotation) {
  // orientation after 2 s against RK4 at a tiny step; halving dt quarters the error
  auto orientation_after = [](Integrator integrator, double dt) {
    World world = tumbling(integrator);
    for (long i = 0; i < std::lround(2.0 / dt); ++i) world.step(dt);
    return world.state(0).orientation;
  };
  const Quat exact = orientation_after(Integrator::RungeKutta4, 1.0 / 7680.0);
  auto error = [&](double dt) {
    return orientation_after(Integrator::Symplectic, dt).angularDistance(exact);
  };
  EXPECT_NEAR(std::log2(error(1.0 / 120.0) / error(1.0 / 240.0)), 2.0, 0.3);
}

TEST(Integrators, ExponentialMapIsExactForAFixedAxis) {
  // a body spinning about a principal axis keeps that axis: the rotation is exact at any dt
  for (Integrator integrator : {Integrator::SemiImplicitEuler, Integrator::Symplectic}) {
    World world(Vec3::Zero(), integrator);
    BodyDef def;
    def.principal_inertia = Vec3(1.0, 2.0, 3.0);
    def.angular_velocity = Vec3(0.0, 0.0, 3.0);
    world.add_body(def);
    for (int i = 0; i < 100; ++i) world.step(0.1);
    EXPECT_LT(
        world.state(0).orientation.angularDistance(Quat(Eigen::AngleAxisd(30.0, Vec3::UnitZ()))),
        1e-12);
  }
}

TEST(Bodies, ImpulseAtAPointChangesLinearAndAngularMomentum) {
  World world(Vec3::Zero());
  BodyDef def;
  def.mass = 2.0;
  def.principal_inertia = Vec3(1.0, 2.0, 3.0);
  def.position = Vec3(1.0, 0.0, 0.0);
  const rtp::BodyId body = world.add_body(def);
  const Vec3 impulse(0.0, 4.0, 0.0);
  const Vec3 point(1.0, 0.0, 0.5);  // 0.5 m above the centre along z
  world.apply_impulse(body, impulse, point);
  EXPECT_TRUE(world.velocity(body).isApprox(Vec3(0.0, 2.0, 0.0)));
  // ΔL = r × J = (0, 0, 0.5) × (0, 4, 0) = (−2, 0, 0); ω = I⁻¹ L
  EXPECT_TRUE(world.state(body).angular_momentum.isApprox(Vec3(-2.0, 0.0, 0.0)));
  EXPECT_TRUE(world.angular_velocity(body).isApprox(Vec3(-2.0, 0.0, 0.0)));
}

TEST(Springs, TorqueEqualsLeverArmCrossForce) {
  // one semi-implicit step from rest: ΔP = F dt and ΔL = (p − x) × F dt exactly
  World world(Vec3::Zero(), Integrator::SemiImplicitEuler);
  BodyDef def;
  def.mass = 1.0;
  def.principal_inertia = Vec3(0.1, 0.2, 0.3);
  def.orientation = Quat(Eigen::AngleAxisd(kPi / 5.0, Vec3::UnitZ()));
  const rtp::BodyId body = world.add_body(def);
  rtp::SpringDef spring;
  spring.body_a = body;
  spring.local_point_a = Vec3(0.5, 0.5, 0.5);
  spring.point_b = Vec3(0.0, 3.0, 0.0);
  spring.stiffness = 40.0;
  spring.rest_length = 1.0;
  world.add_spring(spring);

  const Vec3 attach = def.orientation * spring.local_point_a;
  const Vec3 delta = attach - spring.point_b;
  const Vec3 force = -spring.stiffness * (delta.norm() - spring.rest_length) * delta.normalized();
  const double dt = 1e-3;
  world.step(dt);
  EXPECT_TRUE(world.state(body).linear_momentum.isApprox(force * dt, 1e-12));
  EXPECT_TRUE(world.state(body).angular_momentum.isApprox(attach.cross(force) * dt, 1e-12));
}

TEST(Bodies, StaticBodyNeverMoves) {
  World world;
  BodyDef def;
  def.mass = 0.0;
  def.position = Vec3(1, 2, 3);
  world.add_body(def);
  for (int i = 0; i < 100; ++i) world.step(1.0 / 60.0);
  EXPECT_EQ(world.state(0).position, Vec3(1, 2, 3));
}

// A contact step's stages are disjoint parts of it, timed back to back on the step's clock, and
// every part is in one (writing the results out is `store`): their sum cannot pass the step's
// own total, and `store` is timed, on each solver's path through the step.
TEST(StepProfile, AContactStepsStagesAreDisjointAndItsResultsAreTimed) {
  using rtp::ContactSolver;
  namespace worlds = rtp::contact_worlds;
  for (const ContactSolver solver :
       {ContactSolver::SoftStep, ContactSolver::SequentialImpulse, ContactSolver::Seed}) {
    rtp::ContactSettings settings;
    settings.solver = solver;
    World world(worlds::kGravity, Integrator::SemiImplicitEuler, settings);
    worlds::add_ground(world, 0.6);
    for (int k = 0; k < 10; ++k) worlds::add_box(world, {0.0, 0.5 + k, 0.0}, 1.0, 0.6);
    double store = 0.0;
    for (int i = 0; i < 30; ++i) {
      world.step(worlds::kDt);
      const rtp::StepProfile& p = world.profile();
      double stages = 0.0;
      for (const double seconds : p.stage_seconds()) stages += seconds;
      EXPECT_LE(stages, p.total) << "a part of the step was timed twice (step " << i << ")";
      store += p.store;
    }
    EXPECT_GT(store, 0.0) << "the results written out are in no stage";
  }
}

TEST(Bodies, RejectsNegativeMass) {
  World world;
  BodyDef def;
  def.mass = -1.0;
  EXPECT_THROW(world.add_body(def), std::invalid_argument);
}

}  // namespace
