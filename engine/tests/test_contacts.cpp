// rtp contact tests on small worlds: each against a closed form or an invariant. The stacking
// gates (towers, pyramids) run the scenarios' scenes through the harness (validation/tests).

// This file replaces the global operator new and delete with malloc and free, to count
// allocations; GCC then sees a new-expression (inlined from GoogleTest) freed by std::free and
// warns of a mismatch that the replacement makes none
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
#endif

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <new>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "contact_worlds.h"
#include "rtp/world.h"

// every heap allocation of this test program, counted (the step must make none once settled)
namespace {
std::atomic<long> g_allocations{0};
}  // namespace

void* operator new(std::size_t size) {
  ++g_allocations;
  if (void* p = std::malloc(size ? size : 1)) return p;
  throw std::bad_alloc();
}
void* operator new(std::size_t size, std::align_val_t alignment) {
  ++g_allocations;
  const std::size_t a = static_cast<std::size_t>(alignment);
  if (void* p = std::aligned_alloc(a, (size + a - 1) / a * a)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }

namespace rtp {
namespace {

using namespace contact_worlds;

World world_with(ContactSolver solver, const Vec3& gravity = kGravity) {
  ContactSettings settings;
  settings.solver = solver;
  return World(gravity, Integrator::SemiImplicitEuler, settings);
}

// two equal boxes head-on, e = 1, no gravity, no friction: they exchange velocities (Newton's
// law of restitution with equal masses) and keep the momentum
TEST(Contacts, HeadOnElasticBoxesExchangeVelocities) {
  for (ContactSolver solver : {ContactSolver::SoftStep, ContactSolver::SequentialImpulse}) {
    World world = world_with(solver, Vec3::Zero());
    const BodyId left = add_box(world, {-1.0, 0.0, 0.0}, 1.0, 0.0, 1.0);
    const BodyId right = add_box(world, {1.0, 0.0, 0.0}, 1.0, 0.0, 1.0);
    world.apply_impulse(left, {2.0, 0.0, 0.0}, world.state(left).position);
    world.apply_impulse(right, {-1.0, 0.0, 0.0}, world.state(right).position);
    for (int i = 0; i < 120; ++i) world.step(kDt);
    EXPECT_NEAR(world.velocity(left).x(), -1.0, 0.01);
    EXPECT_NEAR(world.velocity(right).x(), 2.0, 0.02);
    const Vec3 momentum = world.state(left).linear_momentum + world.state(right).linear_momentum;
    // to the round-off of the solver's single precision (a lost or one-sided impulse is 0.1 or
    // more)
    EXPECT_NEAR((momentum - Vec3(1.0, 0.0, 0.0)).norm(), 0.0, 1e-6);
  }
}

// a box resting on the ground neither bounces nor jitters: RMS speed over the last second
TEST(Contacts, RestingBoxDoesNotJitter) {
  World world = world_with(ContactSolver::SoftStep);
  add_ground(world, 0.6);
  const BodyId box = add_box(world, {0.0, 0.5, 0.0}, 1.0, 0.6);
  double sum_squared = 0.0;
  int samples = 0;
  for (int i = 0; i < 300; ++i) {
    world.step(kDt);
    if (i >= 240) {
      sum_squared += world.velocity(box).squaredNorm();
      ++samples;
    }
  }
  EXPECT_LT(std::sqrt(sum_squared / samples), 1e-3);  // m/s
  EXPECT_NEAR(world.state(box).position.y(), 0.5, 1e-3);
}

// A unit cube turned 45° about z stands on one edge, balanced (its fall from there takes seconds
// to grow from rounding), on a static box and on a plane: the contact points are the edge's two
// corners, and the centre must stand √½ m above the surface, as on the plane. The narrow phase
// finds the corners on the boxes grown by the speculative margin, whose corners lie the growth
// beyond the true ones along each of the cube's axes: √2 times it along the normal here. Taken as
// the growth along the normal, the cube stood 4 mm high on the box. The box is the pair's first
// body and then its second (the face on the second body, the corners on the first)
TEST(Contacts, ACubeOnItsEdgeStandsAsHighOnABoxAsOnAPlane) {
  enum class Under { kPlane, kBoxFirst, kBoxSecond };  // the box as the pair's first body or second
  auto height = [](Under under) {
    World world = world_with(ContactSolver::SoftStep);
    auto add_under = [&] {
      if (under == Under::kPlane)
        add_ground(world, 0.6);
      else
        add_box(world, {0.0, -1.0, 0.0}, 0.0, 0.6, 0.0, Quat::Identity(), Vec3(4.0, 1.0, 4.0));
    };
    if (under != Under::kBoxSecond) add_under();
    const Quat turn(Eigen::AngleAxisd(M_PI / 4.0, Vec3::UnitZ()));
    const BodyId cube = add_box(world, {0.0, std::sqrt(0.5), 0.0}, 1.0, 0.6, 0.0, turn);
    if (under == Under::kBoxSecond) add_under();
    for (int i = 0; i < 30; ++i) world.step(kDt);
    EXPECT_LT(std::abs(world.state(cube).position.x()), 1e-4) << "balanced";
    return world.state(cube).position.y();
  };
  const double on_plane = height(Under::kPlane);
  EXPECT_NEAR(on_plane, std::sqrt(0.5), 1e-3);
  EXPECT_NEAR(height(Under::kBoxFirst), on_plane, 2e-4);
  EXPECT_NEAR(height(Under::kBoxSecond), on_plane, 2e-4);
}

// A box spun about the vertical on the ground stops by friction: with its weight on the four
// corners of its face, each sliding at ω r, the friction torque is μ m g r̄, r̄ the corners' mean
// distance from the centre (√½ m for a unit box; the friction at a manifold's centre carries it
// as the twist row), so ω falls at μ m g r̄ / I, I = m/6, and from 4 rad/s stops in 0.16 s
TEST(Contacts, SpinningBoxStopsByTwistFriction) {
  World world = world_with(ContactSolver::SoftStep);
  add_ground(world, 0.6);
  BodyDef box;
  box.position = {0.0, 0.5, 0.0};
  box.principal_inertia = Vec3::Constant(1.0 / 6.0);
  box.shape.kind = BodyShape::Box;
  box.shape.half_extents = Vec3::Constant(0.5);
  box.friction = 0.6;
  box.angular_velocity = {0.0, 4.0, 0.0};
  const BodyId id = world.add_body(box);
  const double deceleration = 0.6 * 9.81 * std::sqrt(0.5) * 6.0;  // rad/s²
  // it starts resting on the ground, so friction acts from the first step
  for (int i = 0; i < 5; ++i) world.step(kDt);  // 1/12 s
  EXPECT_NEAR(world.angular_velocity(id).y(), 4.0 - deceleration * 5 * kDt, 0.1 * 4.0);
  for (int i = 0; i < 25; ++i) world.step(kDt);
  EXPECT_LT(world.angular_velocity(id).norm(), 0.01);
  EXPECT_LT(std::abs(world.state(id).position.x()) + std::abs(world.state(id).position.z()), 1e-3);
}

// A door-shaped box, 0.2 × 2 × 2 m and 1 kg (its inertia differs by axis: I_z, about its edges
// along z, is half I_x), stood on its edge (hx, −hy) at x = 0 on a ground of μ = 1 and leaning φ
// past it towards +x: φ is the lean of the line from the edge to the centre, r its length
struct Door {
  const double hx = 0.1, hy = 1.0, hz = 1.0, mass = 1.0;
  const double inertia_z = mass / 3.0 * (hx * hx + hy * hy);
  const double r = std::hypot(hx, hy), rest_angle = std::atan(hx / hy);
  // about the edge: I_z + m r²
  double pivot_inertia() const { return inertia_z + mass * r * r; }
  // the door leaning phi, its edge lift above the ground
  BodyDef def(double phi, double lift) const {
    const double tilt = rest_angle + phi;
    BodyDef door;
    door.mass = mass;
    door.principal_inertia = {mass / 3.0 * (hy * hy + hz * hz), mass / 3.0 * (hx * hx + hz * hz),
                              inertia_z};
    door.shape.kind = BodyShape::Box;
    door.shape.half_extents = {hx, hy, hz};
    door.friction = 1.0;
    // turned by −tilt about z (its top towards +x)
    door.orientation = Quat(Eigen::AngleAxisd(-tilt, Vec3::UnitZ()));
    door.position = {-hx * std::cos(tilt) + hy * std::sin(tilt),
                     hx * std::sin(tilt) + hy * std::cos(tilt) + lift, 0.0};
    return door;
  }
  // φ as the door stands: its tilt (its y axis from the vertical, towards +x) less the rest
  double lean(const World& world, BodyId id) const {
    const Vec3 up = world.state(id).orientation * Vec3::UnitY();
    return std::atan2(up.x(), up.y()) - rest_angle;
  }
  // the edge it stands on, from its centre
  Vec3 edge_offset(const World& world, BodyId id) const {
    return world.state(id).orientation * Vec3(hx, -hy, 0.0);
  }
};

// The door leaning 0.1 rad topples about its edge as a rigid body on a pivot:
// φ'' = m g r sin φ / (I_z + m r²) (its world inverse inertia has off-diagonal terms once it
// turns). The time to lean 0.8 rad, against the equation's (about 1 s; 2.2 % longer, measured)
TEST(Contacts, ToppledDoorFallsAsAPivotedBody) {
  World world = world_with(ContactSolver::SoftStep);
  add_ground(world, 1.0);
  const Door door;
  const double phi0 = 0.1, phi_end = 0.8;
  const BodyId id = world.add_body(door.def(phi0, 0.0));
  ASSERT_NEAR(door.lean(world, id), phi0, 1e-12);
  // the pivot's equation by RK4 at 0.1 ms, to the time φ reaches phi_end
  const double rate = door.mass * 9.81 * door.r / door.pivot_inertia();
  auto accel = [&](double p) { return rate * std::sin(p); };
  double phi = phi0, speed = 0.0, t_reference = 0.0;
  const double h = 1e-4;
  while (phi < phi_end) {
    const double k1p = speed, k1v = accel(phi);
    const double k2p = speed + 0.5 * h * k1v, k2v = accel(phi + 0.5 * h * k1p);
    const double k3p = speed + 0.5 * h * k2v, k3v = accel(phi + 0.5 * h * k2p);
    const double k4p = speed + h * k3v, k4v = accel(phi + h * k3p);
    phi += h / 6.0 * (k1p + 2 * k2p + 2 * k3p + k4p);
    speed += h / 6.0 * (k1v + 2 * k2v + 2 * k3v + k4v);
    t_reference += h;
  }
  // the simulation's time to phi_end, between steps by the lean's straight line
  double t = 0.0, before = door.lean(world, id);
  for (int step = 0; step < 600; ++step) {
    world.step(kDt);
    const double now = door.lean(world, id);
    if (now >= phi_end) {
      t += kDt * (phi_end - before) / (now - before);
      break;
    }
    before = now;
    t += kDt;
  }
  EXPECT_NEAR(t, t_reference, 0.03 * t_reference) << "reference " << t_reference << " s";
  // the edge stayed where it stood (no slip on μ = 1 by then)
  EXPECT_LT(std::abs((world.state(id).position + door.edge_offset(world, id)).x()), 0.01);
}

// The door dropped on its edge at 3 m/s, leaning 0.3 rad, without bounce (e = 0) or slip: the
// impact keeps the angular momentum about the edge, m v r sin φ, and turns it into a turn about
// the edge, ω = m v r sin φ / (I_z + m r²). Measured at the end of the step the edge lands in,
// where the solve alone (no warm start yet) applied the whole impact through the door's inverse
// inertia
TEST(Contacts, DoorDroppedOnItsEdgeTurnsByItsAngularMomentum) {
  World world = world_with(ContactSolver::SoftStep);
  add_ground(world, 1.0);
  const Door door;
  const double phi = 0.3, speed = 3.0;
  // its edge 1 mm above the ground, falling at `speed`: it lands within the first step
  BodyDef def = door.def(phi, 1e-3);
  def.linear_velocity = {0.0, -speed, 0.0};
  const BodyId id = world.add_body(def);
  world.step(kDt);
  // the turn about −z (towards +x) the angular momentum about the edge gives, and what gravity's
  // torque about the edge adds over the rest of the step (6 % of it)
  const double expected = -door.mass * speed * door.r * std::sin(phi) / door.pivot_inertia() -
                          door.mass * 9.81 * door.r * std::sin(phi) / door.pivot_inertia() * kDt;
  EXPECT_NEAR(world.angular_velocity(id).z(), expected, 0.03 * std::abs(expected));
  // and the edge at rest on the ground
  const Vec3 edge_velocity = world.state(id).linear_momentum / door.mass +
                             world.angular_velocity(id).cross(door.edge_offset(world, id));
  EXPECT_LT(edge_velocity.norm(), 0.05 * speed);
}

// A world with contacts turns its bodies by the exponential map (a substep's turn by Taylor
// series below a half angle of 0.1, by the sine and cosine past it) and keeps them unit by a
// Newton step: a cube (isotropic, so ω stays constant) spinning far above the ground for a
// minute ends where the exact rotation puts it, on the soft step (8 substeps: the series) and on
// sequential impulse (one step of 1/60 s: half angles of 0.15, the sine and cosine)
TEST(Contacts, SpinningCubeTurnsByTheExponentialMap) {
  for (ContactSolver solver : {ContactSolver::SoftStep, ContactSolver::SequentialImpulse}) {
    World world = world_with(solver, Vec3::Zero());
    add_ground(world, 0.6);
    const Vec3 omega(3.0, 17.0, -5.0);
    BodyDef cube;
    cube.position = {0.0, 100.0, 0.0};
    cube.principal_inertia = Vec3::Constant(1.0 / 6.0);
    cube.shape.kind = BodyShape::Box;
    cube.shape.half_extents = Vec3::Constant(0.5);
    cube.angular_velocity = omega;
    const BodyId id = world.add_body(cube);
    const int steps = 3600;
    for (int i = 0; i < steps; ++i) world.step(kDt);
    const Quat exact(Eigen::AngleAxisd(omega.norm() * steps * kDt, omega.normalized()));
    const Quat& q = world.state(id).orientation;
    EXPECT_NEAR(q.norm(), 1.0, 1e-12) << "solver " << int(solver);
    // the angle between them (ω's components are floats exactly, so the solver's single
    // precision adds nothing; 3e-14 and 7e-14 rad were measured)
    EXPECT_LT(q.angularDistance(exact), 1e-10) << "solver " << int(solver);
  }
}

// A spring on a box resting on the ground: a substep's warm start gives each body the velocity
// change its contacts made over the substep before, which must leave the spring's own impulse
// out (counted there, a spring holding up 0.6 of the weight would lift the box) and must not
// drop it (a spring pulling with 1.5 times the weight must lift the box off)
TEST(Contacts, SpringOnARestingBoxActsOnceEverySubstep) {
  for (const double share : {0.6, 1.5}) {
    World world = world_with(ContactSolver::SoftStep);
    add_ground(world, 0.6);
    const BodyId box = add_box(world, {0.0, 0.5, 0.0}, 1.0, 0.6);
    SpringDef spring;  // from the box's top to a point 2 m above it, stretched 1 m
    spring.body_a = box;
    spring.local_point_a = {0.0, 0.5, 0.0};
    spring.point_b = {0.0, 3.0, 0.0};
    spring.rest_length = 1.0;
    spring.stiffness = share * 9.81;  // N/m: share × the weight at 1 m of stretch
    world.add_spring(spring);
    for (int i = 0; i < 30; ++i) world.step(kDt);
    const double rise = world.state(box).position.y() - 0.5;
    if (share < 1.0)
      EXPECT_NEAR(rise, 0.0, 1e-3) << "share " << share;
    else  // 0.5 g up at first, less as the spring shortens: about 0.4 m within 0.5 s
      EXPECT_GT(rise, 0.2) << "share " << share;
  }
}

// The soft step's later substeps start in one pass over the bodies where the world has no
// springs (ContactPipeline::next_substep), and in three with them: a spring of stiffness zero
// takes the second way and must change nothing
TEST(Contacts, SubstepsStartTheSameWithOrWithoutASpringOfNoForce) {
  auto run = [](bool spring) {
    World world = world_with(ContactSolver::SoftStep);
    add_ground(world, 0.6);
    for (int i = 0; i < 3; ++i)
      add_box(world, {0.1 * i, 0.5 + 1.01 * i, 0.0}, 1.0 + i, 0.6, 0.0,
              Quat(Eigen::AngleAxisd(0.1 * i, Vec3::UnitY())));
    if (spring) {
      SpringDef none;
      none.body_a = 2;
      none.point_b = {5.0, 5.0, 5.0};
      world.add_spring(none);
    }
    for (int i = 0; i < 120; ++i) world.step(kDt);
    std::vector<BodyState> states;
    for (BodyId b = 0; b < world.body_count(); ++b) states.push_back(world.state(b));
    return states;
  };
  const std::vector<BodyState> with = run(true), without = run(false);
  for (std::size_t b = 0; b < with.size(); ++b) {
    EXPECT_EQ(with[b].position, without[b].position) << "body " << b;
    EXPECT_EQ(with[b].orientation.coeffs(), without[b].orientation.coeffs()) << "body " << b;
    EXPECT_EQ(with[b].linear_momentum, without[b].linear_momentum) << "body " << b;
  }
  EXPECT_GT(with[3].position.y() - with[1].position.y(), 1.9);  // the stack stood
}

// a closed stack (no work done on it) never gains mechanical energy
TEST(Contacts, ClosedStackNeverGainsEnergy) {
  for (ContactSolver solver : {ContactSolver::SoftStep, ContactSolver::SequentialImpulse}) {
    World world = world_with(solver);
    add_ground(world, 0.6);
    for (int i = 0; i < 5; ++i) add_box(world, {0.0, 0.5 + i, 0.0}, 1.0, 0.6);
    const double initial = world.mechanical_energy();
    double largest = initial;
    for (int i = 0; i < 600; ++i) {
      world.step(kDt);
      largest = std::max(largest, world.mechanical_energy());
    }
    EXPECT_LE(largest - initial, 1e-9 * std::abs(initial)) << "solver " << int(solver);
  }
}

// a box dropped flat: each apex is e² of the one before (Newton's restitution on a flat face)
TEST(Contacts, DroppedBoxApexesFollowTheRestitution) {
  for (double e : {0.5, 0.8}) {
    World world = world_with(ContactSolver::SoftStep);
    add_ground(world, 0.6, e);
    const BodyId box = add_box(world, {0.0, 1.5, 0.0}, 1.0, 0.6, e);  // bottom 1 m up
    std::vector<double> apexes;
    double previous_velocity = 0.0;
    for (int i = 0; i < 300; ++i) {
      world.step(kDt);
      const double v = world.velocity(box).y();
      const double bottom = world.state(box).position.y() - 0.5;
      // apexes above 5 cm: sampled at 60 Hz the apex of a lower hop is off by more than 1 %
      if (previous_velocity > 0.0 && v <= 0.0 && bottom > 0.05) apexes.push_back(bottom);
      previous_velocity = v;
    }
    ASSERT_GE(apexes.size(), 2u) << "e = " << e;
    for (std::size_t n = 0; n < std::min<std::size_t>(apexes.size(), 3); ++n) {
      const double expected = std::pow(e, 2.0 * double(n + 1));
      EXPECT_NEAR(apexes[n] / expected, 1.0, 0.05) << "e = " << e << ", apex " << n + 1;
    }
  }
}

// a block on a slope, μ = 0.5: at 25° (tan θ < μ) static friction holds it; at 30° it slides
// with a = g (sin θ − μ cos θ)
TEST(Contacts, BlockOnASlopeHoldsOrSlidesByCoulomb) {
  const double mu = 0.5;
  for (double degrees : {25.0, 30.0}) {
    const double theta = degrees * std::numbers::pi / 180.0;
    const Quat tilt(Eigen::AngleAxisd(theta, Vec3::UnitZ()));
    World world = world_with(ContactSolver::SoftStep);
    add_ground(world, mu, 0.0, tilt);
    const BodyId block = add_box(world, tilt * Vec3(0.0, 0.5, 0.0), 1.0, mu, 0.0, tilt);
    const Vec3 down_slope = tilt * Vec3(-1.0, 0.0, 0.0);  // the slope falls towards −x
    // let the contact settle for a second, then measure over the next 4
    for (int i = 0; i < 60; ++i) world.step(kDt);
    const Vec3 start = world.state(block).position;
    const double start_speed = world.velocity(block).dot(down_slope);
    const double duration = 4.0;
    for (int i = 0; i < int(duration / kDt); ++i) world.step(kDt);
    const double travelled = (world.state(block).position - start).dot(down_slope);
    if (std::tan(theta) <= mu) {
      EXPECT_LT(std::abs(travelled), 1e-3) << degrees << "°";
    } else {
      const double expected = 9.81 * (std::sin(theta) - mu * std::cos(theta));
      const double measured = 2.0 * (travelled - start_speed * duration) / (duration * duration);
      EXPECT_NEAR(measured / expected, 1.0, 0.03) << degrees << "°";
    }
  }
}

// A box pair found touching keeps its manifold, moved with the bodies, while neither has moved
// more than ContactSettings::manifold_reuse_distance in the other's frame since it was computed;
// a box on a plane while the box has moved no more than that in the plane's frame. A box thrown
// along a static slab (or the ground plane) slides 0.7 m and stops, and three boxes rest on it,
// once with the manifolds reused and once computed every step: a slide must compute every step (a
// manifold moved with the box would keep points the box has left, and tip it), and at rest the
// reused manifolds must hold every box where the computed ones do
TEST(Contacts, MovedManifoldsHoldWhatComputedOnesHoldAndASlideComputesAfresh) {
  for (const bool plane : {false, true}) {
    SCOPED_TRACE(plane ? "on the ground plane" : "on a static slab");
    struct Run {
      std::vector<Vec3> positions;
      std::size_t moved_while_sliding = 0, most_moved_while_sliding = 0;
      std::size_t moved_at_rest = 0, pairs_at_rest = 0;
      double deepest = 0.0;
    };
    auto run = [plane](double reuse) {
      ContactSettings settings;
      settings.manifold_reuse_distance = reuse;
      settings.contact_hold_distance = 0.0;  // at rest the steps would hold: no manifold moved
      World world(kGravity, Integrator::SemiImplicitEuler, settings);
      if (plane)
        add_ground(world, 0.3);
      else
        add_box(world, {0.0, -0.5, 0.0}, 0.0, 0.3, 0.0, Quat::Identity(), Vec3(10.0, 0.5, 10.0));
      const BodyId thrown = add_box(world, {-3.0, 0.5, 0.0}, 1.0, 0.3);
      // a column of two, a little turned, and a box with a turned one across it
      add_box(world, {3.0, 0.5, 0.0}, 1.0, 0.3);
      add_box(world, {3.1, 1.5, 0.0}, 1.0, 0.3, 0.0, Quat(Eigen::AngleAxisd(0.3, Vec3::UnitY())));
      add_box(world, {0.0, 0.5, 3.0}, 2.0, 0.3, 0.0, Quat::Identity(), Vec3(1.0, 0.5, 0.5));
      world.apply_impulse(thrown, {2.0, 0.0, 0.0}, world.state(thrown).position);
      Run out;
      for (int i = 0; i < 240; ++i) {
        world.step(kDt);
        // sliding: 2 m/s less 2.9 m/s² for 0.68 s (and 0.1 s of landing for the others)
        if (i >= 6 && i < 36 && world.velocity(thrown).norm() > 0.5) {
          out.moved_while_sliding += world.profile().reused_manifolds;
          out.most_moved_while_sliding =
              std::max(out.most_moved_while_sliding, world.profile().reused_manifolds);
        }
        out.deepest = std::max(out.deepest, world.deepest_penetration());
      }
      out.moved_at_rest = world.profile().reused_manifolds;
      out.pairs_at_rest = world.profile().contact_pairs;
      for (BodyId b = 0; b < world.body_count(); ++b)
        out.positions.push_back(world.state(b).position);
      return out;
    };
    const Run computed = run(0.0), reused = run(1e-4);
    EXPECT_EQ(computed.moved_at_rest, 0u);
    EXPECT_EQ(reused.pairs_at_rest, 4u);
    EXPECT_EQ(reused.moved_at_rest, reused.pairs_at_rest) << "at rest every manifold is moved";
    // four pairs: the thrown box's, the column's two and the wide box's; the slide's is computed
    // every step, the others are moved once they rest
    EXPECT_LE(reused.most_moved_while_sliding, 3u);
    EXPECT_GT(reused.moved_while_sliding, 0u);
    const double slid = computed.positions[1].x() + 3.0;
    EXPECT_NEAR(slid, 2.0 * 2.0 / (2.0 * 0.3 * 9.81), 0.05);  // v² / 2μg
    for (std::size_t b = 0; b < computed.positions.size(); ++b)
      EXPECT_LT((reused.positions[b] - computed.positions[b]).norm(), 1e-4) << "body " << b;
    EXPECT_NEAR(reused.deepest, computed.deepest, 1e-4);
  }
}

// heavy on light, 10:1: the stack holds
TEST(Contacts, HeavyBoxOnALightOneHolds) {
  World world = world_with(ContactSolver::SoftStep);
  add_ground(world, 0.6);
  const BodyId light = add_box(world, {0.0, 0.5, 0.0}, 1.0, 0.6);
  const BodyId heavy = add_box(world, {0.0, 1.5, 0.0}, 10.0, 0.6);
  for (int i = 0; i < 600; ++i) world.step(kDt);
  EXPECT_LT(std::abs(world.state(light).position.y() - 0.5), 0.01);
  EXPECT_LT(std::abs(world.state(heavy).position.y() - 1.5), 0.01);
  EXPECT_LT(std::hypot(world.state(heavy).position.x(), world.state(heavy).position.z()), 0.01);
}

// a 0.1 m box at 50 m/s towards a 5 cm static wall moves 0.83 m a step at 60 Hz, eight times its
// width: the continuous stage stops it at the wall (the soft step and sequential impulse), where
// the seed's solver, which has none, lets it through; beside the wall, 1 cm clear of the
// speculative distance, it flies on
TEST(Contacts, FastBoxStopsAtAThinWallAndPassesBesideIt) {
  constexpr double kHalf = 0.05, kWallHalf = 0.025, kWallX = 2.0;
  for (ContactSolver solver :
       {ContactSolver::SoftStep, ContactSolver::SequentialImpulse, ContactSolver::Seed}) {
    for (double height : {0.0, 1.0 + kHalf + 0.03}) {
      World world = world_with(solver, Vec3::Zero());
      const BodyId bullet = add_box(world, {0.0, height, 0.0}, 0.1, 0.5, 0.0, Quat::Identity(),
                                    Vec3::Constant(kHalf));
      add_box(world, {kWallX, 0.0, 0.0}, 0.0, 0.5, 0.0, Quat::Identity(),
              Vec3(kWallHalf, 1.0, 1.0));
      world.apply_impulse(bullet, {5.0, 0.0, 0.0}, world.state(bullet).position);
      std::size_t stops = 0;
      for (int i = 0; i < 12; ++i) {
        world.step(kDt);
        stops += world.profile().swept_stops;
      }
      const double x = world.state(bullet).position.x();
      SCOPED_TRACE(testing::Message() << "solver " << int(solver) << ", height " << height);
      if (height > 0.0 || solver == ContactSolver::Seed) {
        EXPECT_GT(x, kWallX + kWallHalf + kHalf);  // through, or past
        EXPECT_EQ(stops, 0u);
        continue;
      }
      // in front of the wall's near face, within sequential impulse's 5 mm slop
      EXPECT_LT(x, kWallX - kWallHalf - kHalf + ContactSettings{}.linear_slop);
      EXPECT_GT(x, kWallX - kWallHalf - kHalf - 0.05);
      EXPECT_LT(std::abs(world.velocity(bullet).x()), 1.0);  // stopped, not still at 50 m/s
      EXPECT_GE(stops, 1u);
    }
  }
}

// a resting stack keeps every contact point from step to step (warm starting), and a settled
// step allocates nothing
TEST(Contacts, SettledStackKeepsItsContactsAndAllocatesNothing) {
  World world = world_with(ContactSolver::SoftStep);
  add_ground(world, 0.6);
  for (int i = 0; i < 4; ++i) add_box(world, {0.0, 0.5 + i, 0.0}, 1.0, 0.6);
  for (int i = 0; i < 60; ++i) world.step(kDt);
  const long before = g_allocations.load();
  for (int i = 0; i < 60; ++i) {
    world.step(kDt);
    EXPECT_EQ(world.profile().matched_points, world.profile().contact_points);
  }
  EXPECT_EQ(g_allocations.load() - before, 0);
  EXPECT_EQ(world.profile().contact_points, 16u);
}

// The baseline build carries the contact passes for x86-64, x86-64-v3 (AVX2, FMA) and x86-64-v4
// (AVX-512) and runs the widest the core has; a build for one instruction set carries "native"
// alone (engine/src/contact_stages.h). Every copy the core runs must give the stack the others
// give: their lanes differ, and which products fuse into a multiply-add, so they agree closely,
// not to the bit; each copy gives the same bits every run. A copy named that the build or core
// lacks is refused, by the setting or by the environment variable, naming what there is.
TEST(Contacts, EachCopyOfTheContactPassesTheCoreRunsGivesTheSameStack) {
  ::unsetenv("RTP_CONTACT_ISA");  // (a choice from outside the test would stand in for the widest)
  const std::string widest = World().contact_instruction_set();
  std::vector<std::string> copies = {widest};
#if defined(__x86_64__) && defined(__GNUC__)
  if (widest != "native") {
    copies = {"x86-64"};
    if (__builtin_cpu_supports("x86-64-v3")) copies.push_back("x86-64-v3");
    if (__builtin_cpu_supports("x86-64-v4")) copies.push_back("x86-64-v4");
    EXPECT_EQ(widest, copies.back()) << "a world takes the widest copy the core runs";
  }
#endif
  // a column of five boxes, and a sixth tilted, landing on it from 0.5 m
  auto run = [](const std::string& copy) {
    ContactSettings settings;
    settings.instruction_set = copy;
    World world(kGravity, Integrator::SemiImplicitEuler, settings);
    EXPECT_EQ(std::string(world.contact_instruction_set()), copy);
    add_ground(world, 0.6);
    for (int k = 0; k < 5; ++k) add_box(world, {0.0, 0.5 + k, 0.0}, 1.0, 0.6);
    add_box(world, {0.2, 6.0, 0.1}, 1.0, 0.6, 0.0,
            Quat(Eigen::AngleAxisd(0.3, Vec3(1.0, 0.0, 1.0).normalized())));
    for (int i = 0; i < 120; ++i) world.step(kDt);
    std::vector<Vec3> positions;
    for (BodyId b = 1; b < BodyId(world.body_count()); ++b)
      positions.push_back(world.state(b).position);
    return positions;
  };
  const std::vector<Vec3> reference = run(copies.front());
  for (const std::string& copy : copies) {
    const std::vector<Vec3> first = run(copy), second = run(copy);
    for (std::size_t b = 0; b < reference.size(); ++b) {
      EXPECT_EQ(first[b], second[b]) << copy << ", box " << b << ": a copy must repeat its bits";
      EXPECT_LT((first[b] - reference[b]).norm(), 1e-3)
          << copy << " against " << copies.front() << ", box " << b;
    }
  }
  ContactSettings unknown;
  unknown.instruction_set = "x86-64-v9";
  try {
    World world(kGravity, Integrator::SemiImplicitEuler, unknown);
    ADD_FAILURE() << "a copy the build does not carry must be refused";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("x86-64-v9"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(widest), std::string::npos) << e.what();
  }
  ::setenv("RTP_CONTACT_ISA", copies.front().c_str(), 1);
  EXPECT_EQ(std::string(World().contact_instruction_set()), copies.front());
  ::setenv("RTP_CONTACT_ISA", "x86-64-v9", 1);
  EXPECT_THROW(World(), std::invalid_argument);
  ::unsetenv("RTP_CONTACT_ISA");
}

// the soft step's relax passes: more while a stack takes its load (a pass still changes some
// contact's normal velocity by over the tolerance), the minimum once it rests; and exactly the
// minimum with the tolerance off
TEST(Contacts, RelaxPassesGrowWhileAStackSettlesAndFallToTheMinimumAtRest) {
  for (const double tolerance : {0.01, 0.0}) {
    ContactSettings settings;
    settings.relax_tolerance = tolerance;
    World world(kGravity, Integrator::SemiImplicitEuler, settings);
    add_ground(world, 0.6);
    // ten boxes dropped 1 cm onto each other: every contact new, every impact to converge
    for (int i = 0; i < 10; ++i) add_box(world, {0.0, 0.51 + 1.01 * i, 0.0}, 1.0, 0.6);
    const std::size_t least = std::size_t(settings.substeps * settings.relax_iterations);
    const std::size_t most = std::size_t(settings.substeps * settings.max_relax_iterations);
    std::size_t largest = 0;
    for (int i = 0; i < 60; ++i) {
      world.step(kDt);
      largest = std::max(largest, world.profile().relax_passes);
      EXPECT_GE(world.profile().relax_passes, least);
      EXPECT_LE(world.profile().relax_passes, tolerance > 0.0 ? most : least);
    }
    if (tolerance > 0.0) {
      EXPECT_GT(largest, least) << "the landings must take more passes";
    }
    for (int i = 0; i < 240; ++i) world.step(kDt);
    for (int i = 0; i < 60; ++i) {
      world.step(kDt);
      EXPECT_EQ(world.profile().relax_passes, least) << "at rest, step " << i;
    }
  }
}

// the same scene run twice gives bit-identical states
TEST(Contacts, SameSceneTwiceIsBitIdentical) {
  auto run = [] {
    World world = world_with(ContactSolver::SoftStep);
    add_ground(world, 0.6);
    for (int i = 0; i < 6; ++i)
      add_box(world, {0.05 * i, 0.5 + 1.02 * i, 0.0}, 1.0, 0.6, 0.0,
              Quat(Eigen::AngleAxisd(0.1 * i, Vec3::UnitY())));
    for (int i = 0; i < 300; ++i) world.step(kDt);
    return state_numbers(world);
  };
  const std::vector<double> first = run(), second = run();
  ASSERT_EQ(first.size(), second.size());
  for (std::size_t i = 0; i < first.size(); ++i) EXPECT_EQ(first[i], second[i]) << i;
}

// one thread and two give the same bits where a wide colour (kParallelColour: 256 contacts and
// more, shared between the threads) mixes isotropic bodies (cubes) with others (flat boxes), and
// its contacts arrive at different steps (a new contact is packed first in its block). Which
// contacts share a block decides whether the block takes the isotropic rows, which round
// differently from the general ones; so the blocks must hold the same contacts on any team
TEST(Contacts, MixedInertiaWideColoursGiveTheSameBitsOnOneAndTwoThreads) {
  auto run = [](int threads) {
    ContactSettings settings;
    settings.solver = ContactSolver::SoftStep;
    settings.threads = threads;
    settings.adaptive_threads = false;  // every step on the team asked for
    World world(kGravity, Integrator::SemiImplicitEuler, settings);
    add_ground(world, 0.6);
    // 24 × 24 columns of three boxes, cubes in the first half (the low body indices, first in
    // pair order) and flat boxes in the second, each column dropped from its own small height
    // so that its contacts are new at their own step
    for (int i = 0; i < 24; ++i)
      for (int k = 0; k < 24; ++k) {
        const bool flat = i >= 12;
        const Vec3 half = flat ? Vec3(0.5, 0.3, 0.5) : Vec3::Constant(0.5);
        const double drop = 0.01 * ((i * 7 + k * 13) % 11);
        for (int level = 0; level < 3; ++level)
          add_box(world, {1.2 * i, drop + half.y() * (2 * level + 1) + 0.03 * level, 1.2 * k},
                  1.0, 0.6, 0.0, Quat::Identity(), half);
      }
    for (int i = 0; i < 60; ++i) world.step(kDt);
    return state_numbers(world);
  };
  const std::vector<double> one = run(1), two = run(2);
  ASSERT_EQ(one.size(), two.size());
  std::size_t differ = 0;
  for (std::size_t i = 0; i < one.size(); ++i) differ += one[i] != two[i];
  EXPECT_EQ(differ, 0u) << "of " << one.size() << " numbers";
}

// a world without shapes keeps its integrator: RK4's free flight is exact
TEST(Contacts, ShapelessWorldKeepsItsIntegrator) {
  World world(kGravity, Integrator::RungeKutta4);
  BodyDef def;
  def.linear_velocity = Vec3(1.0, 5.0, 0.0);
  const BodyId body = world.add_body(def);
  for (int i = 0; i < 60; ++i) world.step(kDt);
  EXPECT_FALSE(world.has_contacts());
  EXPECT_NEAR(world.state(body).position.y(), 5.0 - 0.5 * 9.81, 1e-12);
}

// a hull (a cube given as its eight corners: the hull path, not the box path) and a sphere rest
// on the ground and on each other: nothing falls through, nothing drifts
TEST(Contacts, HullsAndSpheresRestOnTheGround) {
  World world = world_with(ContactSolver::SoftStep);
  add_ground(world, 0.6);
  BodyDef hull;
  hull.position = Vec3(0.0, 0.5, 0.0);
  hull.principal_inertia = Vec3::Constant(1.0 / 6.0);
  hull.shape.kind = BodyShape::Hull;
  for (int i = 0; i < 8; ++i)
    hull.shape.hull_points.emplace_back(i & 1 ? 0.5 : -0.5, i & 2 ? 0.5 : -0.5, i & 4 ? 0.5 : -0.5);
  hull.friction = 0.6;
  const BodyId cube = world.add_body(hull);
  BodyDef ball;
  ball.position = Vec3(3.0, 0.5, 0.0);
  ball.principal_inertia = Vec3::Constant(0.4 * 0.25);
  ball.shape.kind = BodyShape::Sphere;
  ball.shape.radius = 0.5;
  ball.friction = 0.6;
  const BodyId sphere = world.add_body(ball);
  BodyDef on_top = hull;  // a second hull cube on the first
  on_top.position = Vec3(0.0, 1.5, 0.0);
  const BodyId upper = world.add_body(on_top);
  for (int i = 0; i < 300; ++i) world.step(kDt);
  EXPECT_NEAR(world.state(cube).position.y(), 0.5, 0.01);
  EXPECT_NEAR(world.state(upper).position.y(), 1.5, 0.01);
  EXPECT_NEAR(world.state(sphere).position.y(), 0.5, 0.01);
  EXPECT_LT(std::hypot(world.state(upper).position.x(), world.state(upper).position.z()), 0.01);
  EXPECT_LT(world.velocity(sphere).norm(), 1e-3);
}

TEST(Contacts, BadShapesAndMaterialsAreRefused) {
  World world = world_with(ContactSolver::SoftStep);
  BodyDef plane;
  plane.shape.kind = BodyShape::Plane;
  plane.mass = 1.0;  // a dynamic plane
  EXPECT_THROW(world.add_body(plane), std::invalid_argument);
  BodyDef box;
  box.shape.kind = BodyShape::Box;
  box.restitution = 1.5;
  EXPECT_THROW(world.add_body(box), std::invalid_argument);
  ContactSettings settings;
  settings.substeps = 0;
  EXPECT_THROW(World(kGravity, Integrator::SemiImplicitEuler, settings), std::invalid_argument);
  for (const double tolerance : {-0.01, std::nan("")}) {
    ContactSettings bad;
    bad.relax_tolerance = tolerance;
    EXPECT_THROW(World(kGravity, Integrator::SemiImplicitEuler, bad), std::invalid_argument);
  }
  // a negative margin would hold boxes smaller than the bounds, and miss pairs
  for (const double margin : {-0.01, std::nan(""), std::numeric_limits<double>::infinity()}) {
    ContactSettings bad;
    bad.bounds_margin = margin;
    EXPECT_THROW(World(kGravity, Integrator::SemiImplicitEuler, bad), std::invalid_argument);
  }
  ContactSettings bad;
  bad.max_relax_iterations = -1;
  EXPECT_THROW(World(kGravity, Integrator::SemiImplicitEuler, bad), std::invalid_argument);
}

// The broad phase holds each body's bounds grown by bounds_margin and looks for pairs again only
// in a step where some body's bounds leave the box it holds. A box sliding on frictionless ground
// at 1 cm a step towards a static wall 1 m off leaves its box every few steps: in between, the
// pairs are kept; when it reaches the wall the pair must be found, and the run must end on the
// same bits as a broad phase run every step on the bounds themselves (margin 0), since a pair whose
// held boxes meet but whose bounds do not is apart either way. A box whose move went unseen would
// slide through the wall.
TEST(Contacts, ABoxSlidingTowardsAWallMeetsItThoughItsBroadPhaseBoxIsKept) {
  struct Run {
    std::vector<double> state;
    int kept = 0;
    double x = 0.0;
  };
  auto run = [](double margin) {
    ContactSettings settings;
    settings.bounds_margin = margin;
    World world(kGravity, Integrator::SemiImplicitEuler, settings);
    add_ground(world, 0.0);
    add_box(world, {2.0, 0.5, 0.0}, 0.0, 0.0);  // the wall: its face at x = 1.5
    BodyDef def;
    def.mass = 1.0;
    def.principal_inertia = Vec3::Constant(1.0 / 6.0);
    def.position = Vec3(0.0, 0.5, 0.0);
    def.linear_velocity = Vec3(0.6, 0.0, 0.0);  // 1 cm a step
    def.shape.kind = BodyShape::Box;
    def.shape.half_extents = Vec3::Constant(0.5);
    def.friction = 0.0;
    const BodyId box = world.add_body(def);
    Run out;
    for (int i = 0; i < 150; ++i) {
      world.step(kDt);
      out.kept += world.profile().pairs_kept;
    }
    out.state = state_numbers(world);
    out.x = world.state(box).position.x();
    return out;
  };
  const Run held = run(0.05), every = run(0.0);
  EXPECT_GT(held.kept, 75);           // most of its steps keep the pairs
  EXPECT_NEAR(held.x, 1.0, 1e-3);     // at the wall, not through it
  EXPECT_EQ(held.state, every.state);
}

}  // namespace
}  // namespace rtp
