// The contact pipeline as World drives it: the stages of a step with contacts and the solver state
// the world reads back, behind one interface. The pipeline itself (contacts.h, ContactPipeline) is
// compiled once for each instruction set the build carries: the x86-64 baseline build carries
// three (SSE2, AVX2 with FMA, AVX-512) and picks the widest the core runs when a world is made;
// a build for one instruction set (-march=native, or without vector code) carries that one
// (docs/solver.md, "One binary, the widest passes the core has").
#pragma once

#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "rtp/collision.h"
#include "rtp/world.h"

namespace rtp {

// the velocity state the solver reads and writes, per body, in single precision (64 bytes: one
// cache line). The solve works on velocities and on the motion since the step's start, both
// small numbers, so floats hold them as well as Box2D's and Jolt's solvers do; positions and
// momenta stay in double in the world.
struct alignas(64) SolverBody {
  Eigen::Vector3f linear_velocity = Eigen::Vector3f::Zero();   // world (m/s)
  Eigen::Vector3f angular_velocity = Eigen::Vector3f::Zero();  // world (rad/s)
  // its inverse mass and the xx of its world inverse inertia (the whole of it, c in c·1, for a
  // cube or a sphere), for the step: the contact passes read them with the velocities, in the
  // same 32-byte record (zero for a static body)
  float inverse_mass = 0.0f, inverse_inertia_xx = 0.0f;
  Eigen::Vector3f delta_position = Eigen::Vector3f::Zero();    // moved since the step's start (m)
  Eigen::Quaternionf delta_rotation = Eigen::Quaternionf::Identity();  // turned since then
};
static_assert(sizeof(SolverBody) == 64);

// a body's mass as the solver sees it this step: zero for a static body
struct SolverMass {
  double inverse_mass = 0.0;                 // 1/kg
  Mat3 inverse_inertia = Mat3::Zero();       // world, at the step's start (1/(kg m²))
};

// the world's poses in lanes during a step with contacts: a group of kPoseGroup bodies is
// kPoseDoubles doubles, position x, y, z, then orientation w, x, y, z, each a lane a body
inline constexpr std::ptrdiff_t kPoseGroup = 8, kPoseDoubles = 7 * kPoseGroup;

// The stages of a step with contacts, in World::step_with_contacts' order; contacts.h says what
// each does (ContactPipeline, the one implementation)
class ContactStages {
 public:
  virtual ~ContactStages();

  // called for every body in order, shaped or not
  virtual void add_body(BodyId id, const ShapeDef& shape, double friction, double restitution,
                        bool is_static) = 0;
  virtual void set_threads(int threads) = 0;

  virtual void update_bounds(std::span<const BodyState> states, double dt) = 0;
  virtual void find_pairs() = 0;
  virtual void collide_pairs(std::span<const BodyState> states, double dt,
                             const Vec3& gravity) = 0;
  virtual void load_bodies(std::span<const BodyState> states,
                           std::span<const BodyMass> masses) = 0;
  virtual void project_overlaps(std::span<BodyState> states, double depth, int passes) = 0;
  virtual void prepare(const Vec3& gravity, double h) = 0;
  virtual void warm_start(bool first_substep = true) = 0;
  virtual void end_substep() = 0;
  virtual void next_substep(const Eigen::Vector3f& kick) = 0;
  virtual bool solve(double h, bool bias, bool backwards = false, double tolerance = 0.0) = 0;
  virtual void integrate_positions(std::span<double> pose_lanes, std::size_t count, double h) = 0;
  virtual void solve_seed(double dt) = 0;
  virtual void restitution() = 0;
  virtual std::size_t sweep_fast_bodies(std::span<BodyState> states) = 0;
  virtual void store_impulses() = 0;

  virtual std::vector<SolverBody>& bodies() = 0;
  virtual const std::vector<SolverMass>& masses() const = 0;
  virtual std::size_t contact_count() const = 0;
  virtual std::size_t point_count() const = 0;
  virtual double deepest_penetration() const = 0;
  virtual std::size_t matched_points() const = 0;
  virtual std::size_t reused_pairs() const = 0;
  virtual std::size_t reused_manifolds() const = 0;
  // the contacts this step held in last step's solver blocks, none built (ContactPipeline)
  virtual std::size_t held_contacts() const = 0;
  // the held contacts moved to another lane this step to put their colour in class order again
  virtual std::size_t reordered_contacts() const = 0;
  // whether this step's candidate pairs are last step's, the broad phase not run (its boxes kept)
  virtual bool pairs_kept() const = 0;
};

// the sizes and alignments of the types the world and a copy of the pipeline pass each other, as
// the code compiling this sees them: every copy must see them as the world does (Eigen aligns its
// fixed-size types to the widest register the compiler targets: engine/CMakeLists.txt pins it)
struct ContactInterfaceLayout {
  std::size_t body_state, body_state_align, body_mass, body_mass_align, quat_align, shape_def,
      contact_settings, solver_mass;
  bool operator==(const ContactInterfaceLayout&) const = default;
};
inline constexpr ContactInterfaceLayout kContactInterfaceLayout{
    sizeof(BodyState), alignof(BodyState), sizeof(BodyMass),        alignof(BodyMass),
    alignof(Quat),     sizeof(ShapeDef),   sizeof(ContactSettings), sizeof(SolverMass)};

// one instruction set's copy of the pipeline
struct ContactIsa {
  const char* name;          // "x86-64", "x86-64-v3", "x86-64-v4"; "native" in a one-set build
  const char* instructions;  // what its code was compiled for, in words (simd::kInstructionSet)
  std::size_t block_lanes;   // manifolds a block of its solver holds
  ContactStages* (*make)(const ContactSettings& settings);  // a new pipeline, owned by the caller
  ContactInterfaceLayout interface_layout;  // kContactInterfaceLayout as the copy was compiled
};

// The copy a world with these settings runs: `wanted` (ContactSettings::instruction_set) names
// one; empty, the RTP_CONTACT_ISA environment variable does, and without it the widest the core
// runs. Throws std::invalid_argument naming what this build and core offer when the named one is
// not among them.
const ContactIsa& contact_isa(const std::string& wanted);

}  // namespace rtp
