// The contact pipeline's per-step constants: the bodies' solver records (load_bodies), and each
// colour's contacts packed into the solver's blocks, one manifold a lane, with their points'
// effective masses, the friction's centre and masses, and the approach speeds restitution
// reverses (prepare, prepare_lanes; docs/solver.md has the method and the blocks' layout). The
// passes that read the blocks are in contact_solver.cpp, the lane helpers both use in
// contact_solver_internal.h, the blocks in contact_lanes.h, the colouring in constraint_graph.cpp.
#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <type_traits>
#include <utility>
#include <vector>

#if defined(_OPENMP)
#include <omp.h>
#endif

#include "contact_solver_internal.h"
#include "contacts.h"
#include "threads.h"

namespace rtp {
inline namespace RTP_CONTACT_ISA_NAMESPACE {

// where prepare() finds a contact's numbers among its floats (ContactConstraint's layout)
constexpr std::size_t kContactFloats = sizeof(ContactConstraint) / sizeof(float);
constexpr std::size_t kNormalFloat = offsetof(ContactConstraint, normal) / sizeof(float);
constexpr std::size_t kPointFloat = offsetof(ContactConstraint, points) / sizeof(float);
constexpr std::size_t kPointFloats = sizeof(ContactPointConstraint) / sizeof(float);
static_assert(sizeof(ContactConstraint) % sizeof(float) == 0 &&
              sizeof(ContactPointConstraint) % sizeof(float) == 0);
// the header's floats in the order prepare() reads them, two records from the normal on
static_assert(offsetof(ContactConstraint, tangent) == offsetof(ContactConstraint, normal) + 12 &&
              offsetof(ContactConstraint, friction) == offsetof(ContactConstraint, normal) + 36 &&
              offsetof(ContactConstraint, restitution) ==
                  offsetof(ContactConstraint, normal) + 40 &&
              offsetof(ContactConstraint, friction_impulse) ==
                  offsetof(ContactConstraint, normal) + 44 &&
              offsetof(ContactConstraint, twist_impulse) ==
                  offsetof(ContactConstraint, normal) + 52);
// a point's first eight floats: its anchors, base separation and normal impulse
static_assert(offsetof(ContactPointConstraint, anchor_b) == 12 &&
              offsetof(ContactPointConstraint, base_separation) == 24 &&
              offsetof(ContactPointConstraint, normal_impulse) == 28);
// the records read past the header and each point stay inside the contact
static_assert((kNormalFloat + 16) * sizeof(float) <= sizeof(ContactConstraint) &&
              kPointFloat + 3 * kPointFloats + 8 <= kContactFloats);

// the one lane a block keeps for its tangents (ContactBlock::tangent_scale): the narrow phase's
// form decided by the same test on the same single-precision normal (contacts.cpp,
// tangent_basis), 1 / √(n_x² + n_y²) for the first form and its negative for the second; 0 in an
// empty lane (n = 0), whose tangents are then 0
Lane tangent_scale(const V3& n) {
  const Lane zero = splat(0.0f);
  const LaneMask along_x = simd::abs(n.x) >= splat(0.57735026919f);
  const Lane squared = simd::select(along_x, n.x * n.x + n.y * n.y, n.y * n.y + n.z * n.z);
  const LaneMask valid = squared > zero;
  const Lane scale = simd::select(
      valid, splat(1.0f) / simd::sqrt(simd::select(valid, squared, splat(1.0f))), zero);
  return simd::select(along_x, scale, zero - scale);
}

void ContactPipeline::load_bodies(std::span<const BodyState> states,
                                  std::span<const BodyMass> masses) {
  // one body past the last, at rest and static: what an empty lane reads
  bodies_.resize(states.size() + 1);
  masses_.resize(states.size() + 1);
  mass_records_.resize(states.size() + 1);
  bodies_.back() = SolverBody{};
  masses_.back() = SolverMass{};
  mass_records_.back() = {};
  // each body by itself, on the threads
  const std::ptrdiff_t n = std::ptrdiff_t(states.size());
  parallel_for(threads_, n, n >= 2048, [&](std::ptrdiff_t i) {
    SolverBody& body = bodies_[i];
    SolverMass& mass = masses_[i];
    mass.inverse_mass = masses[i].inverse_mass;
    body.inverse_mass = 0.0f;
    body.inverse_inertia_xx = 0.0f;
    body.delta_position.setZero();
    body.delta_rotation.setIdentity();
    if (mass.inverse_mass == 0.0) {
      mass.inverse_inertia.setZero();
      body.linear_velocity.setZero();
      body.angular_velocity.setZero();
      mass_records_[i] = {};
      return;
    }
    // a body whose inertia is the same about every axis (a cube, a sphere) has it so in the
    // world too, exactly: R (c 1) Rᵀ = c 1, where the product leaves round-off off the diagonal
    // (and the solve's isotropic blocks need it exact)
    const Vec3& body_inertia = masses[i].inverse_inertia_body;
    mass.inverse_inertia =
        body_inertia.x() == body_inertia.y() && body_inertia.y() == body_inertia.z()
            ? Mat3(body_inertia.x() * Mat3::Identity())
            : world_inverse_inertia(states[i].orientation, body_inertia);
    body.linear_velocity = (states[i].linear_momentum * mass.inverse_mass).cast<float>();
    body.angular_velocity = (mass.inverse_inertia * states[i].angular_momentum).cast<float>();
    const Mat3& m = mass.inverse_inertia;
    mass_records_[i] = {float(mass.inverse_mass), float(m(0, 0)), float(m(1, 1)), float(m(2, 2)),
                        float(m(0, 1)),           float(m(0, 2)), float(m(1, 2)), 0.0f};
    body.inverse_mass = mass_records_[i][0];
    body.inverse_inertia_xx = mass_records_[i][1];
  });
}

double ContactPipeline::hold_contacts(double dt, const Vec3& gravity) {
  // Each point's separation at the step's start is where last step's solve left it, computed
  // from the bodies' final poses (a relax pass follows the positions' last integration): the
  // base the passes add this step's motion to, less the frame offset prepare_lanes() takes off.
  // Which points start cold, and so which lanes are fresh, from the velocities now, as
  // cold_points() and prepare_lanes() decide it (kept from the step the block was packed, a
  // block would be solved several times a pass for a point that has pushed since). In every
  // block but those packed again (block_refresh_), each thread the blocks it solves
  std::vector<ContactBlock>& blocks = lanes_->blocks;
  std::vector<ContactBlockRest>& rest = lanes_->rest;
  const std::vector<std::uint32_t>& block_start = lanes_->colour_start;
  const int colours = int(block_start.size()) - 1;
  const std::size_t block_count = blocks.size();
  const double h = settings_.solver == ContactSolver::SoftStep ? dt / settings_.substeps : dt;
  const Lane zero = splat(0.0f);
  const Lane horizon = splat(float(2.0 * dt)), half_horizon_squared = splat(float(2.0 * dt * dt));
  const Lane half_step = splat(float(0.5 * h));
  const Lane threshold = splat(float(-settings_.restitution_threshold));
  const V3 g{splat(float(gravity.x())), splat(float(gravity.y())), splat(float(gravity.z()))};
  held_classes_.resize(block_count);
  std::vector<float>& deepest_of = hold_deepest_;
  deepest_of.assign(std::size_t(std::max(1, threads_)), 0.0f);
  parallel_region(threads_, block_count >= 64, [&] {
    Lane deepest = zero;
    for (int k = 0; k < colours; ++k) {
      const auto [begin, end] =
          share_of(block_start[k + 1] - block_start[k], team_size(), team_index());
      for (std::size_t bi = block_start[k] + begin; bi < block_start[k] + end; ++bi) {
        if (block_refresh_[bi]) continue;
        ContactBlock& c = blocks[bi];
        ContactBlockRest& r = rest[bi];
        const FrameOffset offset(c);
        const LanePair pair(bodies_, c);
        const V3 n = load3(c.normal);
        const Tangents tangents = tangents_of(c, n);
        // the gravity along n that free flight closes a gap with (b's less a's)
        const Lane g_n = dot(n, g);
        const Lane acceleration = simd::select(pair.inverse_mass_b > zero, g_n, zero) -
                                  simd::select(pair.inverse_mass_a > zero, g_n, zero);
        LaneMask fresh = zero != zero;
        for (int j = 0; j < 4; ++j) {
          const ContactBlock::Point& p = c.points[j];
          const Lane s = p.separation;
          r.points[j].base_separation = s - offset.d[2];
          const LaneMask exists = p.normal_mass > zero;  // (a point not there has no mass)
          deepest = simd::max(deepest, simd::select(exists, zero - s, zero));
          const Lane v = pair.normal_velocity(n, NormalRow(p, tangents.t0, tangents.t1, offset));
          // no impulse carried, and touching or closed by free flight within two steps
          const LaneMask cold =
              exists & (p.normal_impulse == zero) &
              ((s <= zero) | (s + horizon * v + half_horizon_squared * acceleration < zero));
          // or an approach fast enough to bounce, at the instant of the positions
          const Lane approach = v + half_step * acceleration;
          const LaneMask apart = exists & (s > zero);
          const Lane squared = approach * approach - splat(2.0f) * acceleration * s;
          r.points[j].approach_velocity =
              simd::select(apart, zero - simd::sqrt(simd::max(squared, zero)), approach);
          fresh |= cold | (exists & (r.points[j].approach_velocity < threshold));
        }
        r.fresh = fresh;
        lanes_->flags[bi] = std::uint8_t((lanes_->flags[bi] & ~kFreshBlock) |
                                         (simd::any_of(fresh) ? kFreshBlock : 0));
        held_classes_[bi] = lane_classes(c, r);
      }
    }
    float most = 0.0f;
    for (std::size_t i = 0; i < W; ++i) most = std::max(most, deepest[i]);
    deepest_of[std::size_t(team_index())] = most;
  });
  return *std::max_element(deepest_of.begin(), deepest_of.end());
}

namespace {
// lane i of a block and lane j of another exchanged: every row of both structs is kBlockLanes
// four-byte lanes (ContactBlock's 44, ContactBlockRest's 25)
template <class Block>
void swap_lane(Block& x, std::size_t i, Block& y, std::size_t j) {
  static_assert(sizeof(Block) % (4 * kBlockLanes) == 0 && std::is_trivially_copyable_v<Block>);
  auto* bx = reinterpret_cast<unsigned char*>(&x);
  auto* by = reinterpret_cast<unsigned char*>(&y);
  for (std::size_t row = 0; row < sizeof(Block) / (4 * kBlockLanes); ++row) {
    unsigned char* a = bx + (row * kBlockLanes + i) * 4;
    unsigned char* b = by + (row * kBlockLanes + j) * 4;
    std::uint32_t u, v;
    std::memcpy(&u, a, 4);
    std::memcpy(&v, b, 4);
    std::memcpy(a, &v, 4);
    std::memcpy(b, &u, 4);
  }
}
}  // namespace

ContactPipeline::LaneClasses ContactPipeline::lane_classes(const ContactBlock& c,
                                                         const ContactBlockRest& r) {
  // (a filled lane's first point is there, and has a mass; an empty lane's none)
  const Lane zero = splat(0.0f);
  LaneMask pushing = (c.friction_impulse[0] != zero) | (c.friction_impulse[1] != zero) |
                     (c.twist_impulse != zero);
  for (int j = 0; j < 4; ++j) pushing |= c.points[j].normal_impulse != zero;
  const unsigned filled = simd::lane_bits(c.points[0].normal_mass > zero);
  const unsigned fresh = simd::lane_bits(r.fresh) & filled;
  return {std::uint32_t(fresh), std::uint32_t(filled & ~fresh & ~simd::lane_bits(pushing)),
          std::uint32_t(filled)};
}

void ContactPipeline::order_held_lanes() {
  // A held step keeps last step's blocks, whose lanes were put in class order when their colour
  // was packed: fresh (cold) contacts first, so that few blocks are solved several times a pass,
  // and quiet ones last, so that blocks of them alone skip their friction and the write of
  // their bodies (colour_contacts()). Held for hundreds of steps, the classes change under that
  // order (a settled pyramid's side contacts start and stop pushing) and the passes slow down.
  // So each part of a colour (the share one thread solves, as colour_contacts() packed it) is
  // put back in class order by exchanging lanes between its blocks: the misplaced lanes alone
  // move, in two partitions (fresh from the rest, then quiet from pushing). Only isotropic
  // blocks exchange lanes, so no block's kind of rows changes; the overflow colour, solved in
  // order, is left as it is. The parts are the same on any team, so the order is too
  std::vector<ContactBlock>& blocks = lanes_->blocks;
  std::vector<ContactBlockRest>& rest = lanes_->rest;
  std::vector<std::uint8_t>& flags = lanes_->flags;
  const std::vector<std::uint32_t>& block_start = lanes_->colour_start;
  std::atomic<std::size_t> moved{0};
  parallel_region(threads_, blocks.size() >= 64, [&] {
    std::size_t exchanges = 0;
    // a part's lanes: block * W + lane of its isotropic blocks' filled lanes, and their classes
    // (0 fresh, 1 pushing, 2 quiet)
    thread_local std::vector<std::uint32_t> lanes;
    thread_local std::vector<std::uint8_t> rank;
    for (int k = 0; k + 1 < kColours; ++k) {
      const std::size_t count = block_start[k + 1] - block_start[k];
      const int parts = pack_parts(count);
      for (int part = team_index(); part < parts; part += team_size()) {
        const auto [begin, end] = share_of(count, parts, part);
        const std::size_t first = block_start[k] + begin, last = block_start[k] + end;
        // in order already (most steps): each block's fresh lanes a run from its first lane and
        // its quiet ones a run to its last filled one, and no block's lowest class below the
        // highest before it
        bool ordered = true;
        unsigned highest = 0;
        for (std::size_t bi = first; bi < last && ordered; ++bi) {
          if ((flags[bi] & kIsotropicBlock) == 0) continue;
          // (a block packed again this step has no classes from hold_contacts())
          if (block_refresh_[bi]) held_classes_[bi] = lane_classes(blocks[bi], rest[bi]);
          const LaneClasses& classes = held_classes_[bi];
          if (classes.filled == 0) continue;
          const unsigned fresh = classes.fresh, loud = classes.filled & ~classes.quiet;
          const unsigned lowest = (fresh & 1u) ? 0 : (loud & 1u) ? 1 : 2;
          ordered = (fresh & (fresh + 1)) == 0 && (loud & (loud + 1)) == 0 && lowest >= highest;
          highest = loud == classes.filled ? (fresh == classes.filled ? 0 : 1) : 2;
        }
        if (ordered) continue;
        lanes.clear();
        rank.clear();
        for (std::size_t bi = first; bi < last; ++bi) {
          if ((flags[bi] & kIsotropicBlock) == 0) continue;
          if (block_refresh_[bi]) held_classes_[bi] = lane_classes(blocks[bi], rest[bi]);
          const LaneClasses& classes = held_classes_[bi];
          for (unsigned bits = classes.filled; bits != 0; bits &= bits - 1) {
            const unsigned i = unsigned(std::countr_zero(bits));
            lanes.push_back(std::uint32_t(bi * W + i));
            rank.push_back((classes.fresh >> i & 1u) ? 0 : (classes.quiet >> i & 1u) ? 2 : 1);
          }
        }
        // the lanes of rank below `split` to the front of [from, to): a misplaced one from the
        // front exchanged with a misplaced one from the back
        auto partition = [&](std::size_t from, std::size_t to, std::uint8_t split) {
          std::size_t front = from, back = to;
          while (true) {
            while (front < back && rank[front] < split) ++front;
            while (front < back && rank[back - 1] >= split) --back;
            if (front == back) return front;
            const std::size_t x = lanes[front], y = lanes[back - 1];
            swap_lane(blocks[x / W], x % W, blocks[y / W], y % W);
            swap_lane(rest[x / W], x % W, rest[y / W], y % W);
            for (const std::size_t lane : {x, y}) {
              const std::size_t bi = lane / W;
              block_of_contact_[rest[bi].contact[lane % W]] = std::uint32_t(bi);
              flags[bi] = std::uint8_t((flags[bi] & ~kFreshBlock) |
                                       (simd::any_of(rest[bi].fresh) ? kFreshBlock : 0));
            }
            std::swap(rank[front], rank[back - 1]);
            ++exchanges;
            ++front;
            --back;
          }
        };
        partition(partition(0, lanes.size(), 1), lanes.size(), 2);
      }
    }
    moved.fetch_add(2 * exchanges, std::memory_order_relaxed);
  });
  reordered_ = moved.load(std::memory_order_relaxed);
}

void ContactPipeline::prepare(const Vec3& gravity, double h) {
  separations_stale_ = true;
  gravity_ = gravity;
  restitution_step_ = h;
  if (held_ && held_count_ == contacts_.size()) {  // every block as last step left it
    bounces_ = false;
    order_held_lanes();
    return;
  }
  if (!held_) colour_contacts();  // (holding, the blocks keep their contacts and order)
  if (settings_.solver == ContactSolver::Seed) return;  // the seed reads the contacts themselves
  const std::vector<std::uint32_t>& block_start = lanes_->colour_start;
  std::vector<ContactBlock>& blocks = lanes_->blocks;
  const std::size_t block_count = blocks.size();
  block_of_contact_.resize(contacts_.size());
  std::atomic<bool> bounces{false};
  // a block's contacts, [first, last) in colour_order_: which colour it is of, and where in it
  // (W contacts a block, one in the overflow colour)
  auto contacts_of = [&](std::size_t bi) {
    const int colour = int(std::upper_bound(block_start.begin(), block_start.end(),
                                            std::uint32_t(bi)) -
                           block_start.begin()) -
                       1;
    const std::size_t per_block = colour + 1 < kColours ? W : 1;
    const std::size_t first = colour_start_[colour] + (bi - block_start[colour]) * per_block;
    return std::pair{first,
                     std::min<std::size_t>(first + per_block, colour_start_[colour + 1])};
  };
  auto prepare_block = [&](std::size_t bi) {
    std::array<std::uint32_t, W> record_of;
    if (held_) {
      // a step that holds packs again only the blocks with a lane moved past the hold distance,
      // each lane its contact as before (hold_contacts() carried the others on)
      if (!block_refresh_[bi]) return;
      record_of = lanes_->rest[bi].contact;
    } else {
      const auto [first, last] = contacts_of(bi);
      for (std::size_t i = 0; i < W; ++i) {
        record_of[i] = first + i < last ? colour_order_[first + i] : kNoContact;
        lanes_->rest[bi].contact[i] = record_of[i];
        if (record_of[i] != kNoContact) block_of_contact_[record_of[i]] = std::uint32_t(bi);
      }
      // the next block's contacts asked for now (a colour's contacts lie far apart in contacts_,
      // a 5,050-box pyramid's 3.4 MB), so that their lines arrive while this one is packed
      if (bi + 1 < block_count) {
        const auto [next_first, next_last] = contacts_of(bi + 1);
        for (std::size_t k = next_first; k < next_last; ++k)
          simd::prefetch(&contacts_[colour_order_[k]], sizeof(ContactConstraint));
      }
    }
    if (pack_block(bi, record_of, gravity, h)) bounces.store(true, std::memory_order_relaxed);
  };
  // each thread the blocks it solves: of each colour its share (for_each_block; a colour too
  // small to share is split here too, and solved on one thread there), so that the contacts it
  // reads are mostly those it built (collide_pairs: a share of the pair order, as a colour's
  // share is) and the blocks it writes are in its own cache when it solves them. Spread over the
  // blocks in order, each thread read half its contacts from the other core's cache, and two
  // threads took longer over this stage than one
  const int colours = int(block_start.size()) - 1;
  parallel_region(threads_, block_count >= 64, [&] {
    for (int k = 0; k < colours; ++k) {
      const auto [begin, end] =
          share_of(block_start[k + 1] - block_start[k], team_size(), team_index());
      for (std::size_t bi = block_start[k] + begin; bi < block_start[k] + end; ++bi)
        prepare_block(bi);
    }
  });
  bounces_ = bounces.load(std::memory_order_relaxed);
  if (held_) order_held_lanes();
  blocks_follow_contacts_ = true;
  any_restitution_ = std::any_of(lanes_->flags.begin(), lanes_->flags.end(),
                                 [](std::uint8_t f) { return (f & kBouncingBlock) != 0; });
}

bool ContactPipeline::pack_block(std::size_t bi, const std::array<std::uint32_t, W>& record_of,
                                 const Vec3& gravity, double h) {
  // block bi's lanes from the contacts: lane i from contacts_[record_of[i]], empty where that is
  // kNoContact (an empty lane reads the body at rest past the last)
  const std::uint32_t at_rest = std::uint32_t(bodies_.size() - 1);
  const Lane zero_lane = splat(0.0f);
  ContactBlock& block = lanes_->blocks[bi];
  ContactBlockRest& rest = lanes_->rest[bi];
  // every lane of the block and its rest is written below (not cleared first: 3 KB a block,
  // a base-100 step's 5.7 MB written twice); these two are not, until the solve
  for (int j = 0; j < 4; ++j) {
    block.points[j].separation = zero_lane;
    rest.points[j].max_normal_impulse = zero_lane;
  }
  for (std::size_t i = 0; i < W; ++i) block.body_a[i] = block.body_b[i] = at_rest;
  std::array<LaneMask, 4> exists{};  // the lanes where each point is
  std::array<LaneMask, 4> cold{};    // and where it is cold (ContactConstraint::cold)
  Lane acceleration{};
  // the lanes' contacts and bodies; an empty lane reads contact 0 and the body at rest, and its
  // contact's numbers are cleared below
  LaneIndex contact_offsets, mass_a_offsets, mass_b_offsets;
  LaneMask filled = zero_lane != zero_lane;
  for (std::size_t i = 0; i < W; ++i) {
    std::uint32_t index = 0;
    if (record_of[i] != kNoContact) {
      index = record_of[i];
      const ContactConstraint& c = contacts_[index];
      block.body_a[i] = c.body_a;
      block.body_b[i] = c.body_b;
      filled[i] = -1;
      for (std::uint8_t j = 0; j < c.count; ++j) {
        exists[j][i] = -1;
        cold[j][i] = (c.cold >> j & 1u) ? -1 : 0;
      }
    }
    contact_offsets[i] = std::int32_t(index * kContactFloats);
    mass_a_offsets[i] = std::int32_t(block.body_a[i] * 8);
    mass_b_offsets[i] = std::int32_t(block.body_b[i] * 8);
  }
  // each contact's numbers by records transposed to lanes (ContactConstraint's floats: the
  // normal, the tangents, friction, restitution and the friction impulses, then each point's
  // anchors, base separation and normal impulse; a point past the contact's count is zero)
  const float* contact_floats = reinterpret_cast<const float*>(contacts_.data());
  Lane rows[8];
  auto clear = [&](Lane x) { return simd::select(filled, x, zero_lane); };
  simd::gather_records(contact_floats + kNormalFloat, contact_offsets, rows);
  // (the contact's tangents are not kept: the passes compute them from the normal)
  for (int k = 0; k < 3; ++k) block.normal[k] = clear(rows[k]);
  block.tangent_scale = tangent_scale(load3(block.normal));
  simd::gather_records(contact_floats + kNormalFloat + 8, contact_offsets, rows);
  block.friction = clear(rows[1]), rest.restitution = clear(rows[2]);
  block.friction_impulse[0] = clear(rows[3]), block.friction_impulse[1] = clear(rows[4]);
  block.twist_impulse = clear(rows[5]);
  // (the anchors as the contacts hold them, world vectors from each centre: prepare_lanes()
  // keeps them in the manifold's frame)
  PointAnchors anchors;
  for (int j = 0; j < 4; ++j) {
    ContactBlock::Point& p = block.points[j];
    simd::gather_records(contact_floats + kPointFloat + j * kPointFloats, contact_offsets, rows);
    for (int k = 0; k < 6; ++k) anchors[j][k] = clear(rows[k]);
    rest.points[j].base_separation = clear(rows[6]);
    p.normal_impulse = clear(rows[7]);
  }
  // each body's masses (mass_records_: the body at rest's are zero; the passes read the
  // inverse mass and the inertia's xx from the body's record, the rest of the inertia from the
  // block's rest: c·1 where both are isotropic)
  const float* mass_floats = mass_records_.front().data();
  auto isotropic = [&](const Lane(&m)[8]) {
    return (m[2] == m[1]) & (m[3] == m[1]) & (m[4] == zero_lane) & (m[5] == zero_lane) &
           (m[6] == zero_lane);
  };
  simd::gather_records(mass_floats, mass_a_offsets, rows);
  const Lane inverse_mass_a = rows[0];
  for (int k = 0; k < 5; ++k) rest.inverse_inertia_a[k] = rows[2 + k];
  LaneMask round = isotropic(rows);
  simd::gather_records(mass_floats, mass_b_offsets, rows);
  const Lane inverse_mass_b = rows[0];
  for (int k = 0; k < 5; ++k) rest.inverse_inertia_b[k] = rows[2 + k];
  round &= isotropic(rows);
  const bool isotropic_block = simd::all_of(round);
  for (std::size_t i = 0; i < W; ++i) {
    if (record_of[i] == kNoContact) continue;
    // the gravity along n that free flight closes a gap with (relative, b's less a's)
    const Vec3 normal(double(block.normal[0][i]), double(block.normal[1][i]),
                      double(block.normal[2][i]));
    const Vec3 gravity_a = inverse_mass_a[i] > 0.0f ? gravity : Vec3::Zero();
    const Vec3 gravity_b = inverse_mass_b[i] > 0.0f ? gravity : Vec3::Zero();
    acceleration[i] = float(normal.dot(gravity_b - gravity_a));
  }
  const bool bounces = prepare_lanes(block, rest, anchors, exists, cold, acceleration, h);
  const bool bouncing_block = simd::any_of(rest.restitution > zero_lane);
  lanes_->flags[bi] = std::uint8_t((isotropic_block ? kIsotropicBlock : 0) |
                                   (simd::any_of(rest.fresh) ? kFreshBlock : 0) |
                                   (bouncing_block ? kBouncingBlock : 0));
  return bounces;
}

bool ContactPipeline::prepare_lanes(ContactBlock& c, ContactBlockRest& r,
                                    const PointAnchors& anchors,
                                    const std::array<LaneMask, 4>& exists,
                                    const std::array<LaneMask, 4>& cold, Lane acceleration,
                                    double h) const {
  // the rows, effective masses and approach speeds of a block's points, lane by lane
  const Lane zero = splat(0.0f);
  const Lane threshold = splat(float(-settings_.restitution_threshold));
  const LanePair pair(bodies_, c);
  const V3 n = load3(c.normal);
  const Tangents tangents = tangents_of(c, n);
  const V3 &t0 = tangents.t0, &t1 = tangents.t1;
  auto anchor_a = [&](int j) { return V3{anchors[j][0], anchors[j][1], anchors[j][2]}; };
  auto anchor_b = [&](int j) { return V3{anchors[j][3], anchors[j][4], anchors[j][5]}; };
  const BlockInertia m = inertia_of<false>(pair, r);
  // 1 / (the velocity change along a row per unit impulse), its angular parts ja, jb (r × d); 0
  // for an empty point
  auto row_mass = [&](const V3& ja, const V3& jb, LaneMask point) {
    const Lane k = pair.inverse_mass_a + pair.inverse_mass_b + dot(ja, times(m.a, ja)) +
                   dot(jb, times(m.b, jb));
    const LaneMask valid = point & (k > zero);
    return simd::select(valid, splat(1.0f) / simd::select(valid, k, splat(1.0f)), zero);
  };
  // along d at the anchors ra, rb
  auto effective_mass = [&](const V3& ra, const V3& rb, const V3& d, LaneMask point) {
    return row_mass(cross(ra, d), cross(rb, d), point);
  };
  LaneMask fresh = zero != zero, bounces = zero != zero;
  // the centre of each manifold's points, and their mean distance from it: of the points that
  // touch (within the linear slop), where some do, for friction acts where the bodies touch (a
  // door toppling about its edge, its other edge a speculative point 4 cm up, took friction
  // between the two and fell 2 % slow)
  const Lane slop = splat(float(settings_.linear_slop));
  std::array<LaneMask, 4> holds;
  LaneMask any_touches = zero != zero;
  for (int j = 0; j < 4; ++j) {
    holds[j] = exists[j] & (r.points[j].base_separation <= slop);
    any_touches |= holds[j];
  }
  for (int j = 0; j < 4; ++j) holds[j] = simd::select(any_touches, holds[j], exists[j]);
  V3 sum_a{zero, zero, zero}, sum_b{zero, zero, zero};
  Lane count = zero;
  for (int j = 0; j < 4; ++j) {
    const Lane one_if = simd::select(holds[j], splat(1.0f), zero);
    sum_a = sum_a + one_if * anchor_a(j);
    sum_b = sum_b + one_if * anchor_b(j);
    count = count + one_if;
  }
  const LaneMask any = count > zero;
  const Lane inverse_count =
      simd::select(any, splat(1.0f) / simd::select(any, count, splat(1.0f)), zero);
  const V3 centre_a = inverse_count * sum_a, centre_b = inverse_count * sum_b;
  Lane arm = zero;
  for (int j = 0; j < 4; ++j) {
    const V3 d = anchor_a(j) - centre_a;
    arm = arm + simd::select(holds[j], simd::sqrt(dot(d, d)), zero);
  }
  c.centre_a[0] = dot(centre_a, t0), c.centre_a[1] = dot(centre_a, t1);
  c.centre_a[2] = dot(centre_a, n);
  c.centre_b[0] = dot(centre_b, t0), c.centre_b[1] = dot(centre_b, t1);
  c.centre_b[2] = dot(centre_b, n);
  // the passes take b's anchors as a's plus this (FrameOffset), the points' separations from
  // the bodies' motion likewise
  const FrameOffset offset(c);
  c.twist_arm = inverse_count * arm;
  c.tangent_mass[0] = effective_mass(centre_a, centre_b, t0, any);
  c.tangent_mass[1] = effective_mass(centre_a, centre_b, t1, any);
  {
    const Lane k = dot(n, times(m.a, n)) + dot(n, times(m.b, n));
    const LaneMask valid = any & (k > zero);
    c.twist_mass = simd::select(valid, splat(1.0f) / simd::select(valid, k, splat(1.0f)), zero);
  }
  for (int j = 0; j < 4; ++j) {
    ContactBlock::Point& p = c.points[j];
    ContactBlockRest::Point& q = r.points[j];
    const V3 ra = anchor_a(j);
    p.anchor[0] = dot(ra, t0), p.anchor[1] = dot(ra, t1), p.anchor[2] = dot(ra, n);
    const Lane separation = q.base_separation;
    // the separation is tracked from here: s = base + n·(motion of b's anchor − a's), with b's
    // anchor a's plus the offset, as the passes take it (NormalMotion)
    q.base_separation = separation - offset.d[2];
    // the effective mass of the row the passes compute (NormalRow)
    const NormalRow row(p, t0, t1, offset);
    p.normal_mass = row_mass(row.angular_a, row.angular_b, exists[j]);
    // The approach speed restitution reverses: what the forces alone give the point when it
    // hits, never a speed another contact's impulse gave it this step (in a row of touching
    // balls, one struck, the balls behind the first meet each other at a speed the first
    // contact's push made: reversed as well, that speed created energy, 2.3 times the strike's
    // in a row of five). It is the speed at the instant of the positions (restitution()): a
    // solve's velocity is the one over its last step h, half a step behind them, so the speed
    // at the positions is v + a h/2 with a the relative acceleration gravity gives along n. A
    // point still apart hits, if it hits this step, at the speed free flight gives it over the
    // gap, v² = v₀² − 2 a s₀; a touching one hits at its speed now
    const Lane approach =
        pair.normal_velocity(n, row) + splat(float(0.5 * h)) * acceleration;
    const LaneMask starts_apart = exists[j] & (separation > zero);
    const Lane squared = approach * approach - splat(2.0f) * acceleration * separation;
    q.approach_velocity = simd::select(starts_apart, zero - simd::sqrt(simd::max(squared, zero)),
                                       approach);
    // no warm start where it may push, or an approach fast enough to bounce: the manifold is
    // solved locally
    const LaneMask hits = exists[j] & (q.approach_velocity < threshold);
    fresh |= cold[j] | hits;
    bounces |= hits & (r.restitution > zero);
  }
  r.fresh = fresh;
  return simd::any_of(bounces);
}

}  // namespace RTP_CONTACT_ISA_NAMESPACE
}  // namespace rtp
