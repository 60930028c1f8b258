// rtp world: rigid bodies in momentum form, springs, and a fixed-step integrator.
//
// The state of a body is the seed's primary set — position, linear momentum, orientation
// quaternion, angular momentum — from which velocity, angular velocity and the world-frame
// inverse inertia are derived. Integrating momenta rather than velocities keeps angular
// momentum of a torque-free body exactly constant under every integrator, and it is what
// lets RK4 re-evaluate forces at every stage from a consistent state (Baraff, "Physically
// Based Modeling", SIGGRAPH 2001 course notes, §2; Fiedler, "Physics in 3D").
#pragma once

#include <array>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "rtp/collision.h"
#include "rtp/math.h"
#include "rtp/thread_governor.h"

namespace rtp {

enum class Integrator : std::uint8_t {
  SemiImplicitEuler,  // momenta first, then positions from the new velocities (symplectic)
  Midpoint,           // second order: derivatives at the half step
  RungeKutta4,        // fourth order: four force evaluations per step
  Symplectic,         // kick, then the free rotation by splitting about the principal axes
                      // (Dullweber, Leimkuhler, McLachlan 1997): second order for free bodies,
                      // energy error bounded, angular momentum exact, one force evaluation
};

// a body's collision shape in its body frame; a body without one passes through everything
enum class BodyShape : std::uint8_t { None, Sphere, Box, Hull, Plane };

struct ShapeDef {
  BodyShape kind = BodyShape::None;
  Vec3 half_extents = Vec3::Constant(0.5);  // box (m)
  double radius = 0.5;                      // sphere (m)
  std::vector<Vec3> hull_points;            // hull: the convex hull of these points, body
                                            // frame, centre of mass at its origin (m)
  // plane: the body's local y = 0 surface, solid below; only a static body can be a plane
};

// a body to create; principal axes of inertia are the body's axes
struct BodyDef {
  Vec3 position = Vec3::Zero();           // centre of mass, world (m)
  Quat orientation = Quat::Identity();    // body to world
  Vec3 linear_velocity = Vec3::Zero();    // world (m/s)
  Vec3 angular_velocity = Vec3::Zero();   // world (rad/s)
  double mass = 1.0;                      // kg; 0 makes the body static
  Vec3 principal_inertia = Vec3::Ones();  // body frame diagonal (kg m²)
  ShapeDef shape;
  double friction = 0.5;     // Coulomb coefficient; a pair uses √(μa μb)
  double restitution = 0.0;  // a pair uses max(ea, eb)
};

// the primary state the integrators advance (112 bytes: 13 doubles and the padding that keeps the
// quaternion 16-byte aligned; 128 where AVX has Eigen align it to 32)
struct BodyState {
  Vec3 position;          // centre of mass, world (m)
  Vec3 linear_momentum;   // world (kg m/s)
  Quat orientation;       // body to world, unit
  Vec3 angular_momentum;  // about the centre of mass, world (kg m²/s)
};
static_assert(sizeof(BodyState) == (alignof(Quat) > 16 ? 128 : 112));

// the time derivative of a BodyState
struct BodyRate {
  Vec3 velocity;          // dx/dt (m/s)
  Vec3 force;             // dP/dt (N)
  Quat orientation_rate;  // dq/dt (1/s)
  Vec3 torque;            // dL/dt (N m)
};

// a body's constant mass properties
struct BodyMass {
  double inverse_mass = 0.0;                 // 1/kg; 0 for static bodies
  Vec3 inverse_inertia_body = Vec3::Zero();  // body frame diagonal (1/(kg m²))
};

using BodyId = std::uint32_t;
inline constexpr BodyId kWorldAnchor = ~BodyId{0};

// Hooke's law plus damping along the line between two attachment points
struct SpringDef {
  BodyId body_a = 0;
  Vec3 local_point_a = Vec3::Zero();  // body-a frame (m)
  BodyId body_b = kWorldAnchor;       // kWorldAnchor: point_b is a fixed world point
  Vec3 point_b = Vec3::Zero();        // body-b frame, or world when anchored (m)
  double stiffness = 0.0;             // N/m
  double damping = 0.0;               // N s/m, along the spring's line
  double rest_length = 0.0;           // m
};

// How a world with contacts steps (docs/solver.md). RK4 and midpoint re-evaluate forces at
// stages, which a velocity-level contact solver cannot follow: a world whose bodies have shapes
// steps by semi-implicit Euler inside the solver's own scheme, and World::integrator applies
// only to a world without them.
enum class ContactSolver : std::uint8_t {
  SoftStep,           // substeps, each a soft biased solve and a relax solve without bias, then
                      // one restitution pass (Catto, Solver2D 2024; Box2D v3's solver)
  SequentialImpulse,  // one step of accumulated, clamped impulses with warm starting and a
                      // Baumgarte bias past a slop (Catto, GDC 2006)
  Seed,               // the seed's lab 5: impulse magnitudes with restitution and a penalty
                      // term past a slop, iterated over every contact at once, no warm start,
                      // each pair dropped once its impulses converge
};

// The defaults are the soft step at the stiffness a 20-box tower needs to sink under 1 cm
// (docs/solver.md: contact stiffness is capped at a quarter of the substep rate, and a column
// of n unit boxes on 30 Hz contacts sinks several centimetres); Box2D v3's own defaults are 4
// substeps, 30 Hz, damping ratio 10 and one relax pass (the adapter's soft-step-4 variant).
struct ContactSettings {
  ContactSolver solver = ContactSolver::SoftStep;
  int substeps = 8;                // soft step: substeps per step
  int velocity_iterations = 10;    // sequential impulse and seed: iterations per step
  int relax_iterations = 2;        // soft step: relax solves per substep at least (one lets
                                   // stiff contacts jitter: a 210-box pyramid drifts 5 cm)
  int max_relax_iterations = 10;   // soft step: more relax solves per substep, up to this many,
                                   // while the last one still changed a point's normal velocity
                                   // by more than relax_tolerance (a 5,050-box pyramid rings
                                   // otherwise, and drifts 4.5 cm where it drifts 0.9)
  double relax_tolerance = 0.01;   // m/s (0: always relax_iterations)
  int recovery_relax_iterations = 4;  // soft step: relax solves per substep, no more, in a step
                                      // recovering from an overlap deeper than the push-out
                                      // removes in it (boxes spawned into each other): two left
                                      // a 5 cm overlap's push-out in the boxes, thrown 0.3 m up
  int recovery_position_iterations = 12; // soft step: in a step recovering from an overlap,
                                         // passes over the contacts that move the bodies apart,
                                         // poses only, where they overlap deeper than the
                                         // push-out removes in the step (0: none). Pushed out
                                         // by velocity alone at max_push_speed, a 64-box heap
                                         // started 0.4 m deep turned 0.12 m deeper on the way
  int restitution_iterations = 32;  // passes of the restitution solve at most, while the last
                                    // one still changed a point's normal velocity by more than
                                    // restitution_tolerance (a step without a bounce runs none)
  double restitution_tolerance = 1e-6;  // m/s
  int local_iterations = 4;        // a new or hitting manifold's points solved this many times
                                   // in a row (sequential impulses on a face's four points
                                   // otherwise spin a box that lands flat)
  double contact_hertz = 120.0;    // soft step: contact stiffness, capped at a quarter of the
                                   // substep rate, twice as stiff against static bodies
  double damping_ratio = 3.0;      // soft step: over-damped, so pushes out do not ring
  double max_push_speed = 2.0;     // m/s: the fastest a soft contact pushes bodies apart (3, as
                                   // Box2D, sends boxes started 5 cm deep apart at 3.5 m/s; 1.5
                                   // lets a 1000:1 stack sink through)
  double baumgarte = 0.2;          // sequential impulse and seed: fraction of the
                                   // penetration past the slop removed per step
  double linear_slop = 0.005;      // m: sequential impulse and seed leave this much
                                   // penetration alone, so resting contacts persist
  double speculative_distance = 0.02;  // m: contacts are made this far apart, so a body
                                       // arrives at a surface instead of sinking into it
  double motion_margin_share = 1.0;    // a body's bounds and contacts grow by its motion in
                                       // the step, up to this times its smallest half extent
  double bounds_margin = 0.05;  // m: the broad phase holds each body's bounds grown by this
                                // more, and looks for pairs again only in a step where some
                                // body's bounds leave the box it holds (0: every step)
  double restitution_threshold = 1.0;  // m/s: slower approaches do not bounce
  bool warm_start = true;              // soft step and sequential impulse
  bool alternate_order = true;  // soft step: odd substeps visit the colours backwards, so the
                                // sweep's order leans a stack neither way (docs/solver.md)
  double match_distance = 0.02;  // m: a point with no feature match takes the impulses of last
                                 // step's nearest point within this distance
  double pair_cache_distance = 1e-3;  // m: a pair found apart is not tested again while
                                      // neither shape has moved more than this in the other's
                                      // frame since (0: off)
  double manifold_reuse_distance = 1e-4;  // m: a box pair found touching keeps its manifold, its
                                         // points moved with the bodies and their separations
                                         // measured again, while neither box has moved more
                                         // than this in the other's frame since it was
                                         // computed (0: every touching pair tested each step)
  double contact_hold_distance = 5e-5;  // m: a step whose pairs are last step's keeps the
                                        // solver's contacts as packed, each point's separation
                                        // carried on from the solve's, while no touching pair
                                        // has moved more than this in its bodies' frames since
                                        // its contact was packed (0: off; needs the reuse on)
  int threads = 1;  // the narrow phase and each colour of the solve (identical results at any
                    // count: a colour's contacts share no dynamic body)
  // with threads > 1, each step runs on the team or on one thread, whichever the recent steps
  // found faster (ThreadGovernor: a busy machine's descheduled thread stalls every colour)
  bool adaptive_threads = true;
  // the contact passes' instruction set, where the build carries several (the x86-64 baseline
  // build: "x86-64", "x86-64-v3" with AVX2 and FMA, "x86-64-v4" with AVX-512; a build for one has
  // "native" alone): empty takes the RTP_CONTACT_ISA environment variable's, or else the widest
  // the core runs. A set the build or the core lacks is refused when the world is made.
  std::string instruction_set;
};

// how many manifolds the contact solver's lanes hold in a world with the default settings: the
// widest float register of the contact passes it runs (a block's manifolds share no dynamic body,
// but which share a block decides whether it takes the isotropic rows, which round differently:
// docs/solver.md, "The step, stage by stage")
std::size_t contact_block_lanes();

// the instruction set this build of rtp was compiled for, in words ("AVX-512F, AVX2, FMA",
// "x86-64 baseline (SSE2)", …), and in the baseline build the contact passes a world with the
// default settings runs: what a settings table states
const char* instruction_set();

// wall time of each stage of the last step (s)
struct StepProfile {
  double integrate = 0.0;  // forces and velocities (all of it in a world without contacts)
  double bounds = 0.0;
  double broad_phase = 0.0;
  double narrow_phase = 0.0;  // collide every pair, match last step's contacts
  double prepare = 0.0;       // effective masses, anchors, softness, tangent basis
  double warm_start = 0.0;
  double solve = 0.0;         // velocity iterations (with bias)
  double integrate_positions = 0.0;
  double relax = 0.0;         // velocity iterations without bias
  double restitution = 0.0;
  double continuous = 0.0;  // fast bodies swept against the static shapes
  double store = 0.0;  // the step's results written out: the impulses kept for the next step's
                       // warm start, the poses from the solver's lanes, the momenta
  double total = 0.0;
  std::size_t contact_pairs = 0;   // touching manifolds this step
  std::size_t contact_points = 0;
  std::size_t matched_points = 0;  // points that carried last step's impulses
  std::size_t reused_pairs = 0;    // candidate pairs the pair cache found still apart
  std::size_t reused_manifolds = 0;  // touching pairs whose manifold was moved, not computed
  // contacts held in last step's solver blocks, no manifold moved and no contact built for them
  // (ContactSettings::contact_hold_distance)
  std::size_t held_contacts = 0;
  // of those, the ones moved to another lane of their colour to put it in class order again
  std::size_t reordered_contacts = 0;
  // the broad phase kept last step's pairs: no body's bounds left the box it holds for it
  // (ContactSettings::bounds_margin)
  bool pairs_kept = false;
  std::size_t swept_stops = 0;     // fast bodies the continuous stage stopped short
  std::size_t relax_passes = 0;    // relax solves this step, over its substeps
  int threads = 1;                 // the team the step ran on (ThreadGovernor)

  // the stages above by name, in the step's order (whoever reports them reads this one list)
  static constexpr std::array<const char*, 12> kStageNames = {
      "integrate", "bounds", "broad_phase", "narrow_phase", "prepare", "warm_start",
      "solve", "integrate_positions", "relax", "restitution", "continuous", "store"};
  std::array<double, 12> stage_seconds() const {
    return {integrate, bounds, broad_phase, narrow_phase, prepare, warm_start,
            solve, integrate_positions, relax, restitution, continuous, store};
  }
};

class ContactStages;
struct ContactIsa;

class World {
 public:
  explicit World(Vec3 gravity = Vec3(0.0, -9.81, 0.0),
                 Integrator integrator = Integrator::RungeKutta4,
                 ContactSettings contacts = ContactSettings{});
  ~World();
  World(World&&) noexcept;
  World& operator=(World&&) noexcept;

  BodyId add_body(const BodyDef& def);
  void add_spring(const SpringDef& def);

  // advance by one fixed step of dt seconds
  void step(double dt);

  // apply an impulse (N s) at a world point: changes linear and angular momentum at once
  void apply_impulse(BodyId body, const Vec3& impulse, const Vec3& world_point);

  std::size_t body_count() const { return states_.size(); }
  const BodyState& state(BodyId body) const { return states_[body]; }
  Vec3 velocity(BodyId body) const;
  Vec3 angular_velocity(BodyId body) const;
  double mass(BodyId body) const;
  Mat3 inertia_world(BodyId body) const;
  const Vec3& gravity() const { return gravity_; }
  Integrator integrator() const { return integrator_; }
  void set_integrator(Integrator integrator) { integrator_ = integrator; }
  const StepProfile& profile() const { return profile_; }
  const ContactSettings& contact_settings() const { return contact_settings_; }
  // true when some body has a shape: the world steps by its contact solver
  bool has_contacts() const { return pipeline_ != nullptr; }
  // the instruction set of the contact passes this world runs ("x86-64", "x86-64-v3",
  // "x86-64-v4", or "native" in a build for one; ContactSettings::instruction_set)
  const char* contact_instruction_set() const;
  // the deepest penetration among this step's contacts (m, 0 when none): from the narrow phase
  // at the start of the last step
  double deepest_penetration() const;

  // total mechanical energy: kinetic + gravitational potential + spring potential (J)
  double mechanical_energy() const;

 private:
  // time derivative of every body's state, forces re-evaluated from that state
  void evaluate(const std::vector<BodyState>& states, std::vector<BodyRate>& rates) const;
  // the first half of both Euler-type integrators: momenta by the forces, positions by the new
  // velocities
  void kick_and_translate(double dt);
  void integrate_semi_implicit_euler(double dt);
  void integrate_midpoint(double dt);
  void integrate_runge_kutta4(double dt);
  void integrate_symplectic(double dt);
  // states = base + h * rates, quaternions left unnormalised until the step ends
  void advance(const std::vector<BodyState>& base, const std::vector<BodyRate>& rates, double h,
               std::vector<BodyState>& out) const;
  void normalise_orientations();
  // the stages of a step with contacts that belong to the world's forces and state
  void step_with_contacts(double dt);
  void integrate_velocities(double h);
  void integrate_positions(double h);
  // the substeps' poses in lanes (pose_lanes_), from and back to states_
  void load_pose_lanes();
  void store_pose_lanes();
  void store_momenta();

  Vec3 gravity_;
  Integrator integrator_;
  std::vector<BodyState> states_;
  std::vector<BodyMass> masses_;
  std::vector<SpringDef> springs_;
  StepProfile profile_;
  // integrator scratch, sized once per body count: no allocation inside a step
  std::vector<BodyState> stage_state_;
  std::vector<BodyRate> k1_, k2_, k3_, k4_;
  ContactSettings contact_settings_;
  const ContactIsa* contact_isa_ = nullptr;  // the copy of the contact passes it runs
  std::unique_ptr<ContactStages> pipeline_;  // made by the first body with a shape
  ThreadGovernor governor_{1, false};  // this world's choice of team, step by step
  int active_threads_ = 1;             // the team of the step being run
  // a step with contacts integrates positions in lanes: eight bodies a group, each group 56
  // doubles (position x, y, z, then orientation w, x, y, z, eight lanes each), loaded from
  // states_ at the step's first substep and stored back once the solver is done
  std::vector<double> pose_lanes_;
  bool poses_in_lanes_ = false;
};

}  // namespace rtp
