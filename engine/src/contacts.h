// rtp's contact pipeline (the seed's lab 5): from the bodies' poses to solved contact impulses.
//
// A step with contacts runs, in World::step_with_contacts:
//   bounds        each shaped body's AABB, from its transformed vertices (the seed's lab 3),
//                 grown by half the speculative distance and by how far it can move this step
//   broad phase   box pruning over the bounded shapes; static planes are not in it (they are
//                 unbounded) and meet every dynamic body whose bounds reach them
//   narrow phase  the collision table (lab 4.2) on each candidate pair, every shape grown by
//                 half the speculative distance, so a manifold holds points up to that far
//                 apart; then this step's manifolds are matched to last step's by body pair
//                 (both lists sorted by pair) and by feature id, and the accumulated impulses of
//                 matched points carried over for warm starting
//   prepare       the per-step constants once: anchors, effective masses, tangent basis,
//                 softness, the separation at the step's start
//   then the solver's own scheme (contact_solver.cpp): warm start, velocity iterations,
//   position integration, relax, restitution.
//
// Contacts are solved in velocity form (v, ω) with the world inverse inertia fixed at the
// step's start, as Box2D, Jolt and Bullet do; the world converts back to momenta at the end.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <span>
#include <utility>
#include <vector>

#include "contact_lanes.h"
#include "contact_stages.h"
#include "rtp/broadphase.h"
#include "rtp/collision.h"
#include "rtp/world.h"

namespace rtp {
// this copy's own names: one copy of the pipeline per instruction set the build carries, each in
// its namespace (contact_lanes.h)
inline namespace RTP_CONTACT_ISA_NAMESPACE {

// the box pair's test this copy calls: its own, compiled with it (narrowphase_box.cpp), where the
// build carries a copy for each instruction set; the library's otherwise
namespace box_pairs {
#ifdef RTP_CONTACT_ISA_ENTRY
bool collide_boxes(std::span<const ConvexHull> hulls, const Shape& a, const Pose& pose_a,
                   const Shape& b, const Pose& pose_b, Manifold& out);
#else
using rtp::collide_boxes;
#endif
}  // namespace box_pairs

// a point of a manifold as the narrow phase made it, with the impulse it starts the step with:
// what prepare() packs and the next step's match needs (the solver's own per-step numbers live
// in its lanes, packed by contact_prepare.cpp; the impulses it ends the step with, in the pipeline's
// StoredImpulses). In single precision, as the solver reads them: the narrow phase measures in
// double and rounds once here, and a contact is 228 bytes (four cache lines), which the narrow
// phase writes and prepare() reads every step
struct ContactPointConstraint {
  Eigen::Vector3f anchor_a = Eigen::Vector3f::Zero(),  // the point from each centre of mass,
      anchor_b = Eigen::Vector3f::Zero();              // world (m)
  float base_separation = 0.0f;  // separation at the step's start (m); < 0 penetrating
  float normal_impulse = 0.0f;   // accumulated, carried from last step's (N s)
  ContactFeature feature;
};

// one touching pair: a manifold of up to four points, normal from a to b
struct ContactConstraint {
  BodyId body_a = 0, body_b = 0;
  Eigen::Vector3f normal = Eigen::Vector3f::Zero();
  Eigen::Vector3f tangent[2] = {Eigen::Vector3f::Zero(), Eigen::Vector3f::Zero()};
  float friction = 0.0f;
  float restitution = 0.0f;
  // the manifold's friction, at the centre of its points: accumulated along the two tangents
  // (N s), and about the normal (N m s), carried from last step's
  std::array<float, 2> friction_impulse{};
  float twist_impulse = 0.0f;
  std::uint8_t count = 0;
  // bit j: point j starts without an accumulated normal impulse and may push this step (it
  // touches, or free flight closes its gap within two steps). The solve runs such a manifold's
  // points several times in a row, and the colouring packs such contacts together
  std::uint8_t cold = 0;
  std::array<ContactPointConstraint, 4> points;
  std::uint64_t key() const { return std::uint64_t(body_a) << 32 | body_b; }
};
static_assert(sizeof(ContactConstraint) == 228);

// a contact with a cold point (ContactConstraint::cold); a quiet one carries no impulse and has
// none: a speculative contact that has not pushed (9 % of a settled 5,050-box pyramid's; most of
// its side neighbours press on each other). The colouring packs each class together
inline constexpr std::uint8_t kColdContact = 0x80, kQuietContact = 0x40;

// 1 / (the velocity change along d at the anchors per unit impulse), in double
inline double effective_mass(const Vec3& ra, const Vec3& rb, const Vec3& d, const SolverMass& a,
                             const SolverMass& b) {
  const Vec3 ja = ra.cross(d), jb = rb.cross(d);
  const double k = a.inverse_mass + b.inverse_mass + ja.dot(a.inverse_inertia * ja) +
                   jb.dot(b.inverse_inertia * jb);
  return k > 0.0 ? 1.0 / k : 0.0;
}

// a colour's blocks go to threads only past this many contacts: below it the barrier costs more
inline constexpr std::size_t kParallelColour = 256;

// such a colour is packed into blocks in this many parts on any team (colour_contacts), so that
// its blocks hold the same contacts on one thread as on two: a team of two solves a part each
inline constexpr int kPackParts = 2;
// the parts a colour of `blocks` blocks is packed in: kPackParts where it is wide enough to share
inline constexpr int pack_parts(std::size_t blocks) {
  return blocks >= kParallelColour / kBlockLanes ? kPackParts : 1;
}

// colours beyond the 63rd are one last group, solved one contact a block, in order
inline constexpr int kColours = 64;


class ContactPipeline final : public ContactStages {
 public:
  explicit ContactPipeline(const ContactSettings& settings);
  ~ContactPipeline() override;

  // called for every body in order, shaped or not
  void add_body(BodyId id, const ShapeDef& shape, double friction, double restitution,
                bool is_static) override;

  // the team this step's parallel loops use, from 1 to settings.threads (World's ThreadGovernor);
  // the results are the same on any team
  void set_threads(int threads) override { threads_ = threads; }

  // ---- the stages, in order ----
  void update_bounds(std::span<const BodyState> states, double dt) override;
  void find_pairs() override;
  // dt and gravity tell which points without a warm start may push this step
  // (ContactConstraint::cold)
  void collide_pairs(std::span<const BodyState> states, double dt, const Vec3& gravity) override;
  // masses and velocities at the step's start
  void load_bodies(std::span<const BodyState> states, std::span<const BodyMass> masses) override;
  // the solver's blocks, each contact in its colour's lanes (gravity gives a point's approach: a
  // point still apart the speed it closes at; h: the first solve's step, over which gravity acts
  // before the first push)
  void prepare(const Vec3& gravity, double h) override;
  // the warm start: each contact's accumulated impulses applied to its bodies. On the first
  // substep of a step (and for a solver without substeps) by a pass over the contacts; on a later
  // one each body takes the velocity change its contacts gave it over the substep before, which
  // is the same impulses (a substep's impulses on a contact sum to its accumulated impulse, and
  // the velocity change is linear in them) for a pass over the bodies alone
  void warm_start(bool first_substep = true) override;
  // the end of a substep: each body's velocity change by its contacts since the warm start, for
  // the next substep's warm start
  void end_substep() override;
  // end_substep(), a kick of every dynamic body's velocity by `kick` (gravity over a substep: what
  // the world's velocity integration does without springs) and warm_start(false), in one pass
  // over the bodies
  void next_substep(const Eigen::Vector3f& kick) override;
  // one pass of the velocity solve; bias: push out penetration (soft step, sequential impulse);
  // backwards: the colours in reverse order
  // returns whether every point's normal velocity changed by under `tolerance` (m/s) in the pass
  // (a relax pass's, bias false; true for a biased pass or without a tolerance: nothing is
  // tracked then)
  // a step recovering from an overlap: `passes` Gauss–Seidel passes over the contacts' points,
  // in order, each moving the two bodies' poses apart along the normal by a share of the point's
  // overlap beyond `depth` (the push-out's reach in the step), no velocity changed; each
  // point's separation follows its bodies' moves, so the solve pushes out only the rest
  void project_overlaps(std::span<BodyState> states, double depth, int passes) override;
  bool solve(double h, bool bias, bool backwards = false, double tolerance = 0.0) override;
  void solve_seed(double dt) override;
  // the positions of the first `count` bodies by their velocities over h, their orientations by
  // the exponential map, in pose_lanes (groups of kPoseGroup bodies: contact_stages.h), and each
  // body's motion since the step's start with them (pose_lanes.cpp); the next solve then
  // computes each point's separation from that motion again, rather than read the one it stored
  void integrate_positions(std::span<double> pose_lanes, std::size_t count, double h) override;
  void restitution() override;
  // continuous collision: each body that moved further this step than its speculative contacts
  // reach is swept from its start pose to its end against the static shapes, and stopped where it
  // first comes within the speculative distance of one (its velocity kept: the next step's
  // contact meets it). Returns the bodies stopped.
  std::size_t sweep_fast_bodies(std::span<BodyState> states) override;
  // the accumulated impulses, by contact, for the next step's warm start (the seed's solve
  // accumulates them in the contacts themselves: copied from there)
  void store_impulses() override;

  std::vector<SolverBody>& bodies() override { return bodies_; }
  const std::vector<SolverMass>& masses() const override { return masses_; }
  std::size_t contact_count() const override { return contacts_.size(); }
  std::size_t point_count() const override;
  double deepest_penetration() const override;
  std::size_t matched_points() const override { return matched_; }
  std::size_t reused_pairs() const override { return reused_; }
  std::size_t reused_manifolds() const override { return moved_; }
  std::size_t held_contacts() const override { return held_ ? held_count_ : 0; }
  std::size_t reordered_contacts() const override { return held_ ? reordered_ : 0; }
  bool pairs_kept() const override { return pairs_kept_; }

 private:
  struct BodyShapeData;
  // ContactConstraint::cold for c, its impulses carried; velocities from load_bodies
  std::uint8_t cold_points(const ContactConstraint& c, double dt, const Vec3& gravity) const;
  // each contact's accumulated impulses as the step's solve left them, by its index in contacts_
  // (store_impulses(); 28 bytes a contact, 420 KB at base 100, where writing them into the
  // contacts touched 3.4 MB at random)
  struct StoredImpulses {
    std::array<float, 4> normal{};    // a point's (N s)
    std::array<float, 2> friction{};  // along the contact's tangents (N s)
    float twist = 0.0f;               // about its normal (N m s)
  };
  // the blocks' impulses into impulses_, every contact's
  void write_impulses();
  // contact i's impulses: impulses_[i], or its lane's where the blocks still hold them
  StoredImpulses stored_impulses(std::size_t i) const;
  // a block's impulses in one lane
  static StoredImpulses lane_impulses(const ContactBlock& block, std::size_t lane);
  // the number of c's points that took an old point's impulses (old's stored)
  std::size_t carry_impulses(const ContactConstraint& old, const StoredImpulses& impulses,
                             ContactConstraint& c) const;
  // whether a dynamic body's box reaches a plane's grown surface
  bool reaches_plane(BodyId plane, const Aabb& box) const;
  // whether two bodies' bounds this step overlap (a plane's: whether the other's reach it)
  bool bounds_meet(BodyId a, BodyId b) const;
  // a pair's growth this step, the two bodies' together (m); and the two shapes grown by it
  double pair_growth(const BodyShapeData& a, const BodyShapeData& b) const;
  // how far each shape's surface lies beyond the true one in the pair's narrow phase (m)
  std::pair<double, double> surface_growth(const BodyShapeData& a, const BodyShapeData& b) const;
  void grow_pair(const BodyShapeData& a, const BodyShapeData& b, Shape& grown_a,
                 Shape& grown_b) const;
  const ContactSettings settings_;
  int threads_ = 1;  // this step's team (set_threads): settings_.threads, or fewer on a busy machine
  std::vector<BodyShapeData> shapes_;  // per body
  std::vector<ConvexHull> hulls_;      // the grown hulls: the pool Shape::hull indexes
  std::map<std::array<double, 3>, std::uint32_t> box_hulls_;  // a grown box size's hull
  std::unique_ptr<BroadPhase> broad_phase_;
  std::vector<BodyId> proxy_body_;     // proxy id → body
  std::vector<std::uint8_t> proxy_static_;  // proxy id → 1 for a static body's
  // per body, this step's bounds, grown (not for planes); apart from the shapes, so the passes
  // over every body's bounds read 24 bytes a body
  std::vector<Aabb> bounds_;
  // per body, the box the broad phase holds: this step's bounds grown by bounds_margin when they
  // last left it (Box2D's enlarged boxes), so a body resting or creeping keeps its box; while no
  // body's bounds leave its box the pairs are last step's, and find_pairs() keeps them
  std::vector<Aabb> broad_bounds_;
  bool boxes_moved_ = true;   // this step: a body's bounds left its box, or a body came
  bool pairs_kept_ = false;   // this step's candidates are last step's (find_pairs())
  std::vector<BodyId> planes_;
  std::vector<BodyId> dynamic_shaped_;  // bodies that meet the planes
  std::vector<BodyId> static_shaped_;   // what a fast body is swept against
  struct FastBody {
    BodyId id;
    Vec3 position;  // at the step's start
    Quat orientation;
  };
  // find_pairs' counting sort: each body's first key, and each thread's keys and their counts
  // by first body (then their places)
  std::vector<std::uint32_t> bucket_start_;
  std::vector<std::vector<std::uint64_t>> part_keys_;
  std::vector<std::vector<std::uint32_t>> part_counts_;
  std::vector<std::uint64_t> sorted_candidates_;  // and its output
  std::vector<std::uint8_t> fast_flags_;  // update_bounds' scratch: 1 for a fast body
  std::vector<FastBody> fast_;  // this step's bodies that move beyond their bounds' growth
  std::vector<std::uint64_t> candidates_;  // pair keys, sorted
  std::vector<ContactConstraint> contacts_, previous_;
  std::vector<StoredImpulses> impulses_, previous_impulses_;  // contacts_' and previous_'s
  bool impulses_in_blocks_ = false;  // impulses_ not written since the solve (store_impulses())
  std::vector<std::uint64_t> contact_keys_, previous_keys_;  // each contact's key(), in order
  // contacts by colour (graph colouring, as Box2D v3's constraint graph): no two contacts of a
  // colour share a dynamic body, so a colour's contacts are solved at once, on any number of
  // threads, with the same result as on one; every solve visits contacts in this order
  void colour_contacts();
  // each contact's colour in colour_scratch_ (its class in the top bits), each colour's
  // contacts from colour_start_, and each colour's contacts in pair order in
  // colour_scratch_order_: greedily in pair order, each contact's search for a free colour
  // starting at one drawn from a hash of its key
  void colour_greedily();
  // a kernel on every block of lanes_, colour by colour, each colour's blocks on the threads
  // backwards: the colours in reverse order (the soft step alternates, docs/solver.md)
  template <class Kernel>
  void for_each_block(Kernel&& kernel, bool backwards = false);
  // a block's rows, effective masses, approach speeds and fresh lanes from its raw points
  // (whether some lane's point hits fast enough to bounce)
  // (each point's anchors from a and from b as the contacts hold them: world vectors, in lanes)
  using PointAnchors = std::array<std::array<Lane, 6>, 4>;
  bool prepare_lanes(ContactBlock& block, ContactBlockRest& rest, const PointAnchors& anchors,
                     const std::array<LaneMask, 4>& exists,
                     const std::array<LaneMask, 4>& cold, Lane acceleration, double h) const;
  // a touching pair's contact from its manifold, no impulse carried and no point cold yet;
  // returns its deepest overlap (m)
  double build_contact(const Manifold& manifold, BodyId a, BodyId b,
                       std::span<const BodyState> states, ContactConstraint& c) const;
  std::vector<std::uint32_t> colour_order_;  // contact indices, colour by colour
  std::vector<std::uint32_t> colour_start_;  // colour k: colour_order_[start[k], start[k + 1])
  std::vector<std::uint64_t> body_colours_;  // per body, the colours holding it this step
  // each contact's class for the colouring, set as it is built: kColdContact, kQuietContact or 0
  std::vector<std::uint8_t> contact_class_;
  std::vector<std::uint8_t> colour_scratch_;
  std::vector<std::uint32_t> colour_scratch_order_;  // the contacts by colour, in pair order
  // the narrow phase's results per candidate, filled in parallel
  std::vector<Manifold> manifolds_;
  // the pair cache (as Jolt's body pair cache): each candidate's result with the two bodies'
  // relative pose when it was computed. While neither body's shape has moved more than
  // ContactSettings::pair_cache_distance in the other's frame since, a pair found apart is taken
  // to be apart still instead of tested again; while they have moved less than
  // ContactSettings::manifold_reuse_distance, a box pair found touching keeps its manifold, its
  // points carried with the bodies and their depths measured again (docs/solver.md)
  // (In single precision, 208 bytes: a part in 10⁷ of a metre is far inside either distance,
  // and the narrow phase walks 15,000 of them a step at base 100)
  struct CachedPair {
    // Raᵀ(xb − xa), Rbᵀ(xa − xb) and Raᵀ Rb when the entry was made; the pair's growth then (m)
    Eigen::Vector3f offset_in_a = Eigen::Vector3f::Zero(), offset_in_b = Eigen::Vector3f::Zero();
    Eigen::Matrix3f relative_rotation = Eigen::Matrix3f::Identity();
    float growth = 0.0f;
    // a touching pair's manifold in the bodies' frames (count 0: a pair found apart): the
    // normal in the frame of the body whose face it is, each point as the two surface points
    // it joins, each in its own body's frame
    std::uint8_t count = 0;
    bool normal_on_b = false;
    Eigen::Vector3f normal = Eigen::Vector3f::Zero();
    struct Point {
      Eigen::Vector3f on_a = Eigen::Vector3f::Zero(), on_b = Eigen::Vector3f::Zero();
      ContactFeature feature;
    };
    std::array<Point, 4> points;
  };
  static_assert(sizeof(CachedPair) == 208);
  // how far each body's shape has moved in the other's frame since its entry's pose (m), for
  // the candidates ks[0, count) with an entry, up to kMotionLanes (a lane each, as out[i]; a
  // lane without an entry holds a number that means nothing, and none is written where no
  // candidate of the group has one)
  static constexpr std::size_t kMotionLanes = simd::kNativeFloats;
  void motion_in_lanes(const std::uint32_t* ks, std::size_t count,
                       std::array<std::array<float, 2>, kMotionLanes>& out) const;
  // the same for the contacts [first, last), since their blocks were packed (packed_poses_)
  void held_motion_in_lanes(std::size_t first, std::size_t last,
                            std::array<std::array<float, 2>, kMotionLanes>& out) const;
  // the test both read: lane i's pair keys[i] against the pose recorded at entries + at[i]
  // (floats; CachedPair's first fifteen), where valid[i]
  void motion_since(const float* entries, const std::array<std::uint64_t, kMotionLanes>& keys,
                    const std::array<std::int32_t, kMotionLanes>& at,
                    const std::array<bool, kMotionLanes>& valid,
                    std::array<std::array<float, 2>, kMotionLanes>& out) const;
  // a pair's pose as an entry records it, into its first fifteen floats (Raᵀ(xb − xa),
  // Rbᵀ(xa − xb), Raᵀ Rb): cache_pair()'s, and a packed contact's (PackedPose, padded)
  static constexpr std::size_t kPackedPoseFloats = 16;
  using PackedPose = std::array<float, kPackedPoseFloats>;
  void record_pose(BodyId a, BodyId b, float* out) const;
  // Contacts held (docs/solver.md, "Held contacts"): a step whose candidate pairs and touching
  // pairs are last step's keeps its blocks' contacts and order, and each block none of whose
  // pairs has moved more than ContactSettings::contact_hold_distance in its bodies' frames since
  // its contact was packed stays as it is: each point's separation goes on from where last
  // step's solve left it, and no manifold is moved, no contact built, matched or packed for it.
  // The other blocks' contacts are built again, in place, and packed again.
  // Each contact's pose when its block was packed (by contact, as contacts_)
  std::vector<PackedPose> packed_poses_;
  bool poses_packed_ = false;  // packed_poses_ holds every contact's (the last build's, if held)
  bool held_ = false;                  // this step holds
  bool blocks_follow_contacts_ = false;  // the blocks hold contacts_, packed or held last step
  bool any_restitution_ = false;       // some lane's restitution is above zero (prepare())
  // each held block's separations carried on, and its cold and fresh lanes taken again from the
  // velocities (block_refresh_ 0); their deepest overlap (m)
  double hold_contacts(double dt, const Vec3& gravity);
  // a held step's lanes exchanged within each part of a colour so that its classes are in
  // order again, fresh first and quiet last (prepare(), after the blocks packed again)
  void order_held_lanes();
  // a block's lanes by class, a bit each: fresh, quiet (no impulse carried, not fresh), filled
  struct LaneClasses {
    std::uint32_t fresh, quiet, filled;
  };
  static LaneClasses lane_classes(const ContactBlock& c, const ContactBlockRest& r);
  std::vector<LaneClasses> held_classes_;  // per block, from hold_contacts()
  std::size_t reordered_ = 0;  // the lanes order_held_lanes() moved this step
  std::vector<float> hold_deepest_;  // its scratch: each thread's deepest overlap (m)
  // per contact its block (prepare()); per contact, 1 where its block is packed again this
  // step (a lane of it moved past the hold distance), and per block the same
  std::vector<std::uint32_t> block_of_contact_;
  std::vector<std::uint8_t> contact_refresh_, block_refresh_;
  std::size_t held_count_ = 0;  // the contacts held this step (in blocks not packed again)
  std::vector<std::uint32_t> refreshed_;  // the others, the contacts packed again, in order
  std::vector<ContactConstraint> refreshed_contacts_;  // and their contacts, built this step
  // pack_block(): block bi's lanes from contacts_ (lane i from contacts_[record_of[i]];
  // kNoContact: empty), with prepare_lanes(); whether some lane's point bounces
  bool pack_block(std::size_t bi, const std::array<std::uint32_t, kBlockLanes>& record_of,
                  const Vec3& gravity, double h);
  // each body's rotation in single precision, row by row (nine floats, then zeros), a record of
  // kRotationFloats floats: what motion_in_lanes reads
  static constexpr std::size_t kRotationFloats = 16;
  std::vector<std::array<float, kRotationFloats>> rotations_;
  // the pair's pose now into out; with the manifold in the bodies' frames if one is given
  void cache_pair(BodyId a, BodyId b, double growth, const Manifold* manifold,
                  CachedPair& out) const;
  // a cached manifold at the bodies' poses now, its depths for the pair's growth now
  void move_manifold(const CachedPair& cached, BodyId a, BodyId b, double growth,
                     Manifold& out) const;
  // the entries, each in a slot that keeps it from step to step (an entry recomputed is
  // written over its old self, one kept is not copied); the slots of last step's entries by
  // pair, sorted by key; the slots free
  std::vector<CachedPair> cache_pool_;
  struct CacheSlot {
    std::uint64_t key;
    std::uint32_t slot;
  };
  std::vector<CacheSlot> cache_slots_, next_cache_slots_;
  std::vector<std::uint32_t> free_slots_;
  std::vector<std::uint32_t> candidate_slot_;  // per candidate: its slot this step
  std::vector<std::uint8_t> has_entry_;        // per candidate: 1 if its slot holds last step's
  std::vector<std::uint8_t> outcome_;  // per candidate: touching, found apart, still apart...
  std::vector<std::uint32_t> visit_;   // the candidates the narrow phase tests this step
  std::vector<std::uint8_t> visit_touched_;  // holding: whether each touched last step
  std::vector<std::uint32_t> touching_;     // the candidates whose manifold has points
  std::size_t reused_ = 0, moved_ = 0;
  std::vector<Pose> poses_;  // per body, this step
  std::vector<double> pair_growth_;
  std::vector<SolverBody> bodies_;  // per body, and one at rest past the last, for empty lanes
  // per body: its velocities as the substep's warm start found them, then the change its
  // contacts made over the substep (warm_start(), end_substep())
  struct Velocities {
    Eigen::Vector3f linear = Eigen::Vector3f::Zero(), angular = Eigen::Vector3f::Zero();
    float dynamic = 0.0f;  // substep_start_: 1 for a dynamic body, 0 for a static one
  };
  std::vector<Velocities> substep_start_, substep_change_;
  std::vector<SolverMass> masses_;
  // each body's masses as prepare() packs them, 8 floats: 1/m, then the world inverse inertia's
  // xx yy zz xy xz yz, then 0 (one record a body, read by transposes)
  std::vector<std::array<float, 8>> mass_records_;
  std::unique_ptr<ContactLanes> lanes_;
  std::vector<bool> seed_converged_;  // seed: per contact, its impulses stopped changing
  // project_overlaps' scratch, per body (each body's move so far; whether it moved) and the
  // contacts a pass visits: kept, so a recovering step allocates nothing once they have grown
  std::vector<Vec3> projection_shift_, projection_turn_;
  std::vector<std::uint8_t> projection_moved_;
  std::vector<std::uint32_t> projection_visit_;
  double deepest_ = 0.0;
  std::size_t matched_ = 0;
  std::size_t point_count_ = 0;  // the points of contacts_, counted as they are built
  bool separations_stale_ = true;  // the blocks' separations predate the positions
  bool bounces_ = false;  // some point hits fast enough to bounce this step (prepare())
  Vec3 gravity_ = Vec3::Zero();   // this step's, and its solve's last step length (s): what
  double restitution_step_ = 0.0;  // restitution() reads (prepare())
};

// a shaped body as the pipeline keeps it (contacts.cpp, and the pair cache, the match with last
// step's contacts and the sweep of fast bodies in files of their own)
struct ContactPipeline::BodyShapeData {
  BodyShape kind = BodyShape::None;
  Shape shape;  // grown by half the speculative distance
  double reach = 0.0;   // the farthest its surface is from its centre of mass (m)
  double thinnest = 0.0;  // its smallest half extent, or radius (m)
  double growth = 0.0;  // this step: half the speculative distance and the motion bound (m)
  bool is_static = false;
  double friction = 0.0, restitution = 0.0;
  ProxyId proxy = 0;
  Vec3 plane_normal = Vec3::UnitY();  // a plane's, in the world, this step
  double plane_offset = 0.0;          // (m), grown by half the speculative distance
};

// a body's pose from its state
inline Pose pose_of(const BodyState& s) { return Pose(s.position, s.orientation); }

}  // namespace RTP_CONTACT_ISA_NAMESPACE
}  // namespace rtp
