// This step's contacts against last step's (docs/solver.md, step 4): each point takes the
// impulses of last step's point with the same features, or the nearest within the match
// distance (warm starting), and which points start cold. Part of collide_pairs() (contacts.cpp).
// And the impulses kept at a step's end for the next step's match (store_impulses()).
#include "contacts.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>

#include "contact_lanes.h"
#include "threads.h"

namespace rtp {
inline namespace RTP_CONTACT_ISA_NAMESPACE {

std::uint8_t ContactPipeline::cold_points(const ContactConstraint& c, double dt,
                                          const Vec3& gravity) const {
  // a point without a warm start that touches, or whose gap free flight closes within two steps
  // (its normal velocity at the step's start and the gravity along n; twice the step, since the
  // solve may speed the bodies on): only such a point can push this step. A settled stack's side
  // neighbours hang a hair apart without pushing, a third of a large pyramid's contacts
  // (most of a resting scene's points carry an impulse: their bodies are not read)
  bool all_carried = true;
  for (std::uint8_t j = 0; j < c.count; ++j) all_carried &= c.points[j].normal_impulse != 0.0f;
  if (all_carried) return 0;
  const SolverBody& a = bodies_[c.body_a];
  const SolverBody& b = bodies_[c.body_b];
  const bool moves_a = masses_[c.body_a].inverse_mass > 0.0;
  const bool moves_b = masses_[c.body_b].inverse_mass > 0.0;
  const Vec3 normal = c.normal.cast<double>();
  const double acceleration = normal.dot((moves_b ? gravity : Vec3::Zero()) -
                                         (moves_a ? gravity : Vec3::Zero()));
  const Vec3 va = a.linear_velocity.cast<double>(), wa = a.angular_velocity.cast<double>();
  const Vec3 vb = b.linear_velocity.cast<double>(), wb = b.angular_velocity.cast<double>();
  const double horizon = 2.0 * dt;
  std::uint8_t cold = 0;
  for (std::uint8_t j = 0; j < c.count; ++j) {
    const ContactPointConstraint& p = c.points[j];
    if (p.normal_impulse != 0.0f) continue;
    const double s = p.base_separation;
    const double approach = normal.dot((vb + wb.cross(p.anchor_b.cast<double>())) -
                                       (va + wa.cross(p.anchor_a.cast<double>())));
    if (s <= 0.0 || s + horizon * approach + 0.5 * horizon * horizon * acceleration < 0.0)
      cold |= std::uint8_t(1u << j);
  }
  return cold;
}

std::size_t ContactPipeline::carry_impulses(const ContactConstraint& old,
                                            const StoredImpulses& impulses,
                                            ContactConstraint& c) const {
  // each point takes the impulses of last step's point with the same features; failing that, of
  // the nearest unclaimed one within the match distance. Two equal boxes stacked face to face
  // have incident corners on the reference face's corners, and which candidate of the clip
  // (incident vertex, crossing, reference corner) keeps a point flips with the smallest tilt:
  // the place survives where the id does not (as Bullet's and Jolt's contact caches match by
  // position)
  // (a feature compared as the eight bytes it is; a manifold moved from the pair cache holds
  // last step's features in last step's order, and the first search finds each at once)
  auto same = [](const ContactFeature& x, const ContactFeature& y) {
    return std::bit_cast<std::uint64_t>(x) == std::bit_cast<std::uint64_t>(y);
  };
  std::array<bool, 4> claimed{};
  std::array<int, 4> source{-1, -1, -1, -1};
  bool in_order = old.count == c.count;
  for (std::uint8_t i = 0; i < c.count && in_order; ++i)
    in_order = same(old.points[i].feature, c.points[i].feature);
  if (in_order)
    for (std::uint8_t i = 0; i < c.count; ++i) source[i] = i;
  for (std::uint8_t i = 0; i < c.count && !in_order; ++i) {
    for (std::uint8_t j = 0; j < old.count; ++j)
      if (!claimed[j] && same(old.points[j].feature, c.points[i].feature)) {
        source[i] = j;
        claimed[j] = true;
        break;
      }
  }
  const double match_squared = settings_.match_distance * settings_.match_distance;
  for (std::uint8_t i = 0; i < c.count; ++i) {
    if (source[i] >= 0) continue;
    double nearest = match_squared;
    for (std::uint8_t j = 0; j < old.count; ++j) {
      if (claimed[j]) continue;
      const double d = (old.points[j].anchor_a - c.points[i].anchor_a).cast<double>().squaredNorm();
      if (d < nearest) nearest = d, source[i] = j;
    }
    if (source[i] >= 0) claimed[source[i]] = true;
  }
  std::size_t matched = 0;
  for (std::uint8_t i = 0; i < c.count; ++i) {
    if (source[i] < 0) continue;
    ++matched;
    c.points[i].normal_impulse = impulses.normal[source[i]];
  }
  if (matched == 0) return 0;
  // the manifold's friction impulse as a world vector, onto this step's basis (the normal turns
  // a little between steps, and the basis with it), and its twist
  const Vec3 friction = double(impulses.friction[0]) * old.tangent[0].cast<double>() +
                        double(impulses.friction[1]) * old.tangent[1].cast<double>();
  c.friction_impulse[0] = float(friction.dot(c.tangent[0].cast<double>()));
  c.friction_impulse[1] = float(friction.dot(c.tangent[1].cast<double>()));
  c.twist_impulse = impulses.twist;
  return matched;
}

ContactPipeline::StoredImpulses ContactPipeline::stored_impulses(std::size_t i) const {
  if (!impulses_in_blocks_) return impulses_[i];
  // contact i's lane of its block
  const std::size_t b = block_of_contact_[i];
  const ContactBlock& block = lanes_->blocks[b];
  const auto& contact = lanes_->rest[b].contact;
  const std::size_t lane =
      std::size_t(std::find(contact.begin(), contact.end(), i) - contact.begin());
  return lane_impulses(block, lane);
}

ContactPipeline::StoredImpulses ContactPipeline::lane_impulses(const ContactBlock& block,
                                                               std::size_t lane) {
  StoredImpulses stored;
  for (int j = 0; j < 4; ++j) stored.normal[j] = block.points[j].normal_impulse[lane];
  stored.friction = {block.friction_impulse[0][lane], block.friction_impulse[1][lane]};
  stored.twist = block.twist_impulse[lane];
  return stored;
}

void ContactPipeline::store_impulses() {
  impulses_in_blocks_ = false;
  impulses_.resize(contacts_.size());
  if (settings_.solver == ContactSolver::Seed) {  // the seed solves the contacts themselves
    for (std::size_t i = 0; i < contacts_.size(); ++i) {
      const ContactConstraint& c = contacts_[i];
      StoredImpulses& stored = impulses_[i];
      for (std::uint8_t j = 0; j < c.count; ++j) stored.normal[j] = c.points[j].normal_impulse;
      stored.friction = c.friction_impulse;
      stored.twist = c.twist_impulse;
    }
    return;
  }
  if (!lanes_) return;
  // a step that may hold its contacts next leaves the impulses in the blocks: such a step reads
  // only those of the contacts it packs again (stored_impulses()), a step that builds them all
  // has them written first (write_impulses()); a settled pyramid-100 wrote its 14,950 in 0.27 ms
  // of a 6.5 ms step on one thread. Not where the restitution pass follows, which changes the
  // blocks' impulses (and a scene with restitution does not hold)
  if (settings_.contact_hold_distance > 0.0 && blocks_follow_contacts_ && !any_restitution_ &&
      !bounces_) {
    impulses_in_blocks_ = true;
    return;
  }
  write_impulses();
}

void ContactPipeline::write_impulses() {
  impulses_in_blocks_ = false;
  impulses_.resize(contacts_.size());
  // each contact is one lane of one block: the blocks write disjoint contacts
  const std::vector<ContactBlock>& blocks = lanes_->blocks;
  const std::vector<ContactBlockRest>& rest = lanes_->rest;
  const std::size_t block_count = blocks.size();
  parallel_for(threads_, block_count, block_count >= 64, [&](std::size_t b) {
    const ContactBlock& block = blocks[b];
    const auto& contact = rest[b].contact;
    for (std::size_t i = 0; i < kBlockLanes; ++i) {
      if (contact[i] != kNoContact) impulses_[contact[i]] = lane_impulses(block, i);
    }
  });
}

}  // namespace RTP_CONTACT_ISA_NAMESPACE
}  // namespace rtp
