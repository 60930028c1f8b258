// The contact pipeline's collision half: shapes, bounds, candidate pairs and the narrow phase's
// manifolds and contacts (contacts.h says what each stage does). The narrow phase's pair cache
// (pair_cache.cpp), its match with last step's contacts (contact_match.cpp) and the sweep of fast
// bodies (continuous.cpp) are in files of their own.
#include "contacts.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <limits>
#include <stdexcept>

#include "threads.h"

namespace rtp {
inline namespace RTP_CONTACT_ISA_NAMESPACE {

namespace {

// the two bodies of a pair in one number, lower id first: sorting by it orders pairs by body
std::uint64_t pair_key(BodyId a, BodyId b) {
  return a < b ? std::uint64_t(a) << 32 | b : std::uint64_t(b) << 32 | a;
}

// two unit tangents that make a right-handed frame with n, a function of n alone (Catto,
// "Computing a basis", 2014): the same normal gets the same basis every step
// (written in scalars, one square root and one division: Eigen's normalized() on the
// three-vector went through the stack, two stores read back as one, and divided twice)
void tangent_basis(const Vec3& n, Vec3 tangent[2]) {
  // which of the two forms, decided on the normal in single precision, as the solver holds it:
  // its lanes compute the same basis from that normal (contact_solver_internal.h, tangents_of)
  if (std::abs(float(n.x())) >= 0.57735026919f) {
    const double inverse = 1.0 / std::sqrt(n.x() * n.x() + n.y() * n.y());
    tangent[0] = Vec3(n.y() * inverse, -n.x() * inverse, 0.0);
  } else {
    const double inverse = 1.0 / std::sqrt(n.y() * n.y() + n.z() * n.z());
    tangent[0] = Vec3(0.0, n.z() * inverse, -n.y() * inverse);
  }
  tangent[1] = n.cross(tangent[0]);
}

// the vertices of a hull whose every face plane moves out by d: each vertex moves to where its
// faces' offset planes meet (least squares where more than three meet), so the separating axis
// test on the grown hull measures the real hull's face distances plus d exactly
std::vector<Vec3> offset_vertices(const ConvexHull& hull, double d) {
  std::vector<std::vector<Vec3>> normals(hull.vertices.size());
  for (const HullFace& face : hull.faces)
    for (std::uint32_t k = 0; k < face.count; ++k)
      normals[hull.face_vertices[face.first + k]].push_back(face.normal);
  std::vector<Vec3> moved;
  moved.reserve(hull.vertices.size());
  for (std::size_t v = 0; v < hull.vertices.size(); ++v) {
    Eigen::MatrixX3d rows(normals[v].size(), 3);
    for (std::size_t k = 0; k < normals[v].size(); ++k) rows.row(Eigen::Index(k)) = normals[v][k];
    const Eigen::VectorXd offsets = Eigen::VectorXd::Constant(rows.rows(), d);
    moved.push_back(hull.vertices[v] + rows.colPivHouseholderQr().solve(offsets));
  }
  return moved;
}

}  // namespace

ContactPipeline::ContactPipeline(const ContactSettings& settings)
    : settings_(settings),
      threads_(std::max(1, settings.threads)),
      broad_phase_(make_broad_phase(BroadPhaseKind::BoxPruning)) {}

ContactPipeline::~ContactPipeline() = default;

void ContactPipeline::add_body(BodyId id, const ShapeDef& def, double friction,
                               double restitution, bool is_static) {
  if (id != shapes_.size()) throw std::logic_error("rtp: bodies reach the pipeline in order");
  if (!(friction >= 0.0) || !std::isfinite(friction))
    throw std::invalid_argument("rtp: friction must be finite and >= 0");
  if (!(restitution >= 0.0 && restitution <= 1.0))
    throw std::invalid_argument("rtp: restitution must be in [0, 1]");
  // every shape grows by half the speculative distance: two grown shapes touch when the real
  // ones are that distance apart
  const double grow = 0.5 * settings_.speculative_distance;
  BodyShapeData data;
  data.kind = def.kind;
  data.is_static = is_static;
  data.friction = friction;
  data.restitution = restitution;
  switch (def.kind) {
    case BodyShape::None:
      break;
    case BodyShape::Sphere:
      if (!(def.radius > 0.0)) throw std::invalid_argument("rtp: sphere radius must be > 0");
      data.shape = Shape::sphere(def.radius + grow);
      data.reach = def.radius;
      data.thinnest = def.radius;
      break;
    case BodyShape::Box: {
      const Vec3 half = def.half_extents.array() + grow;
      // boxes of one size share one hull, found by its size (a search through every shape made a
      // world of n boxes in n² steps: 6 % of a 1.5 s run of many-pyramids' 10,780). A size that
      // is not finite is never looked up: make_box_hull refuses it
      const std::array<double, 3> size = {half.x(), half.y(), half.z()};
      const auto found = half.allFinite() ? box_hulls_.find(size) : box_hulls_.end();
      std::uint32_t hull = found != box_hulls_.end() ? found->second : kNoHull;
      if (hull == kNoHull) {
        hull = std::uint32_t(hulls_.size());
        hulls_.push_back(make_box_hull(half));
        box_hulls_.emplace(size, hull);
      }
      data.shape = Shape::box(hull, half);
      data.reach = def.half_extents.norm();
      data.thinnest = def.half_extents.minCoeff();
      break;
    }
    case BodyShape::Hull:
      data.shape = Shape::convex(std::uint32_t(hulls_.size()));
      hulls_.push_back(
          make_convex_hull(offset_vertices(make_convex_hull(def.hull_points), grow)));
      for (const Vec3& v : hulls_.back().vertices) data.reach = std::max(data.reach, v.norm());
      break;
    case BodyShape::Plane:
      if (!is_static) throw std::invalid_argument("rtp: a plane must be static");
      data.shape = Shape::plane(Vec3::UnitY(), grow);
      data.reach = std::numeric_limits<double>::infinity();  // unbounded
      break;
  }
  if (def.kind == BodyShape::Plane) {
    planes_.push_back(id);
  } else if (def.kind != BodyShape::None) {
    data.proxy = broad_phase_->add(Aabb{});
    if (data.proxy >= proxy_body_.size()) {
      proxy_body_.resize(data.proxy + 1);
      proxy_static_.resize(data.proxy + 1);
    }
    proxy_body_[data.proxy] = id;
    proxy_static_[data.proxy] = is_static;
    if (!is_static) dynamic_shaped_.push_back(id);
  }
  if (is_static && def.kind != BodyShape::None) static_shaped_.push_back(id);
  shapes_.push_back(data);
  bounds_.emplace_back();
  // a box no bounds lie inside, so the first step grows it (and a new plane looks for pairs)
  constexpr float kInf = std::numeric_limits<float>::infinity();
  broad_bounds_.push_back(Aabb{{kInf, kInf, kInf}, {-kInf, -kInf, -kInf}});
  boxes_moved_ = true;
  bodies_.emplace_back();
  masses_.emplace_back();
}

void ContactPipeline::update_bounds(std::span<const BodyState> states, double dt) {
  // A body grows by half the speculative distance and by how far its surface can move this step
  // (|v| + |ω| reach) dt, up to a share of its own thickness: a box falling 7 cm a step is met by
  // the ground in the step it arrives, not found 5 cm deep in the next. (The growth is the same
  // on every side: grown by much more than its size, a box's least-penetration axis against a thin
  // wall can be a side one, and its speculative points push the wrong way; a faster body
  // tunnels, and the tunnelling scenes report it.) Hulls keep the fixed growth (their hull is
  // grown once, at creation).
  const double fixed = 0.5 * settings_.speculative_distance;
  // each body on the pipeline's threads (each writes its own shape data and its own box in the
  // broad phase), then the fast ones gathered in body order
  const std::ptrdiff_t n = std::ptrdiff_t(shapes_.size());
  fast_flags_.assign(shapes_.size(), 0);
  const float margin = float(settings_.bounds_margin);
  std::atomic<bool> moved{false};
  parallel_for(threads_, n, n >= 2048, [&](std::ptrdiff_t i) {
    BodyShapeData& data = shapes_[i];
    const BodyState& s = states[i];
    const SolverBody& body = bodies_[i];
    data.growth = fixed;
    if (!data.is_static && (data.kind == BodyShape::Box || data.kind == BodyShape::Sphere)) {
      const double motion =
          (double(body.linear_velocity.norm()) + double(body.angular_velocity.norm()) * data.reach) *
          dt;
      const double most = settings_.motion_margin_share * data.thinnest;
      data.growth += std::min(motion, most);
      fast_flags_[i] = motion > most;
    }
    const double extra = data.growth - fixed;
    Aabb box;
    switch (data.kind) {
      case BodyShape::None:
        return;
      case BodyShape::Plane:
        data.plane_normal = s.orientation * data.shape.plane_normal;
        data.plane_offset = data.shape.plane_offset + data.plane_normal.dot(s.position);
        return;
      case BodyShape::Sphere:
        box = bounds_of_sphere(s.position, data.shape.radius + extra);
        break;
      case BodyShape::Box:
        box = bounds_of_box(data.shape.half_extents.array() + extra, s.position, s.orientation);
        break;
      case BodyShape::Hull:
        box = bounds_of_points(hull_of(data.shape, hulls_).vertices, s.position, s.orientation);
        break;
    }
    bounds_[i] = box;
    // the broad phase's box, grown again where the bounds left it
    Aabb& held = broad_bounds_[i];
    if (margin > 0.0f && contains(held, box)) return;
    for (int k = 0; k < 3; ++k) {
      held.min[k] = box.min[k] - margin;
      held.max[k] = box.max[k] + margin;
    }
    broad_phase_->move(data.proxy, held);
    moved.store(true, std::memory_order_relaxed);
  });
  if (moved.load(std::memory_order_relaxed)) boxes_moved_ = true;
  fast_.clear();
  for (std::size_t i = 0; i < shapes_.size(); ++i)
    if (fast_flags_[i]) fast_.push_back({BodyId(i), states[i].position, states[i].orientation});
}

bool ContactPipeline::reaches_plane(BodyId plane, const Aabb& box) const {
  // the box's lowest corner along the normal at or below the plane's grown surface, with 0.1 mm
  // of slack for the bounds' single precision
  constexpr double kSlack = 1e-4;
  const Vec3& n = shapes_[plane].plane_normal;
  double lowest = 0.0;
  for (int k = 0; k < 3; ++k)
    lowest += n[k] * (n[k] >= 0.0 ? double(box.min[k]) : double(box.max[k]));
  return lowest <= shapes_[plane].plane_offset + kSlack;
}

bool ContactPipeline::bounds_meet(BodyId a, BodyId b) const {
  if (shapes_[a].kind == BodyShape::Plane) return reaches_plane(a, bounds_[b]);
  if (shapes_[b].kind == BodyShape::Plane) return reaches_plane(b, bounds_[a]);
  return overlaps(bounds_[a], bounds_[b]);
}

void ContactPipeline::find_pairs() {
  // no body's bounds left the box the broad phase holds: the boxes, and so the pairs, are last
  // step's (a settled pyramid-100's sweep and keys took 0.27 ms of its 6.5 a step on one thread)
  pairs_kept_ = !boxes_moved_;
  if (pairs_kept_) return;
  boxes_moved_ = false;
  broad_phase_->set_threads(threads_);
  broad_phase_->update();
  const std::vector<ProxyPair>& found = broad_phase_->pairs();
  const std::size_t bodies = shapes_.size();
  // Each pair's key, by pair: the order the contacts are solved in, whatever order the broad
  // phase found them in, and the order the match with last step's contacts walks. A counting
  // sort on the first body (a few pairs each), then each body's pairs by the second: a third of
  // the time a radix sort of the keys took. On the pipeline's threads, each keys and counts its
  // share of the found pairs, then writes them where the counts put them (each body's bucket
  // holds the parts' keys in part order) and sorts its share of the buckets: the same keys in
  // the same order on any number of threads. (Serial, this took 0.13 ms of a base-100 step,
  // about 0.16 on two threads, where the keys came from the other core's sweep.)
  const int parts = threads_ > 1 && found.size() >= 2048 ? threads_ : 1;
  if (part_keys_.size() < std::size_t(parts)) {
    part_keys_.resize(std::size_t(parts));
    part_counts_.resize(std::size_t(parts));
  }
  bucket_start_.resize(bodies + 1);
  parallel_region(parts, parts > 1, [&] {
    const int size = team_size(), part = team_index();
    // the thread's keys, written through a pointer: the vectors' headers sit side by side in
    // part_keys_, and two threads pushing back there wrote one cache line (twice as slow)
    const auto [first, last] = share_of(found.size(), size, part);
    const auto [first_body, last_body] = share_of(dynamic_shaped_.size(), size, part);
    std::vector<std::uint64_t>& key_list = part_keys_[std::size_t(part)];
    const std::size_t most = (last - first) + planes_.size() * (last_body - first_body);
    if (key_list.size() < most) key_list.resize(most);  // never shrunk: no fill a step
    std::uint64_t* const keys = key_list.data();
    std::size_t key_count = 0;
    std::vector<std::uint32_t>& count_list = part_counts_[std::size_t(part)];
    count_list.assign(bodies, 0);
    std::uint32_t* const count = count_list.data();
    auto add = [&](std::uint64_t key) {
      keys[key_count++] = key;
      ++count[key >> 32];
    };
    for (std::size_t i = first; i < last; ++i) {
      const ProxyPair& pair = found[i];
      if (proxy_static_[pair.a] && proxy_static_[pair.b]) continue;
      add(pair_key(proxy_body_[pair.a], proxy_body_[pair.b]));
    }
    // every dynamic body whose box reaches a plane: a pyramid's 5,050 boxes are 100 that touch
    // the ground and 4,950 the narrow phase need not see
    for (BodyId plane : planes_)
      for (std::size_t i = first_body; i < last_body; ++i) {
        const BodyId body = dynamic_shaped_[i];
        if (reaches_plane(plane, broad_bounds_[body])) add(pair_key(plane, body));
      }
#pragma omp barrier
#pragma omp single
    {
      // each body's bucket, and in it each part's first place (the counts become places)
      std::uint32_t at = 0;
      for (std::size_t i = 0; i < bodies; ++i) {
        bucket_start_[i] = at;
        for (int p = 0; p < size; ++p) {
          std::uint32_t& place = part_counts_[std::size_t(p)][i];
          const std::uint32_t n = place;
          place = at;
          at += n;
        }
      }
      bucket_start_[bodies] = at;
      sorted_candidates_.resize(at);
    }  // (a barrier)
    for (std::size_t k = 0; k < key_count; ++k)
      sorted_candidates_[count[keys[k] >> 32]++] = keys[k];
#pragma omp barrier
    const auto [first_bucket, last_bucket] = share_of(bodies, size, part);
    for (std::size_t i = first_bucket; i < last_bucket; ++i) {
      const auto from = sorted_candidates_.begin() + std::ptrdiff_t(bucket_start_[i]);
      const auto to = sorted_candidates_.begin() + std::ptrdiff_t(bucket_start_[i + 1]);
      if (to - from <= 16) {
        for (auto k = from + (from != to); k < to; ++k)  // insertion: a few keys a body
          for (auto j = k; j > from && *j < *(j - 1); --j) std::iter_swap(j, j - 1);
      } else {
        std::sort(from, to);
      }
    }
  });
  std::swap(candidates_, sorted_candidates_);
}

void ContactPipeline::collide_pairs(std::span<const BodyState> states, double dt,
                                    const Vec3& gravity) {
  // every candidate through the collision table, on the pipeline's threads (each writes its own
  // manifold), then the touching ones in pair order into contacts matched with last step's
  const std::size_t n = candidates_.size();
  if (manifolds_.size() < n) {
    manifolds_.resize(n);
    pair_growth_.resize(n);
  }
  // each body's pose (its rotation matrix) once a step, not once for each of its pairs
  // (and the rotation in single precision, as a record the pair cache's test reads in lanes)
  poses_.resize(states.size());
  rotations_.resize(states.size());
  parallel_for(threads_, states.size(), states.size() >= 2048, [&](std::size_t i) {
    if (shapes_[i].kind == BodyShape::None) return;
    poses_[i] = pose_of(states[i]);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) rotations_[i][3 * r + c] = float(poses_[i].rotation(r, c));
  });
  // each candidate's slot in the pair cache: last step's entry for the pair, or a free one for
  // an entry made this step (both lists sorted by key); last step's pairs that are candidates no
  // more free theirs
  const bool cache_apart = settings_.pair_cache_distance > 0.0;
  const bool cache_touching = settings_.manifold_reuse_distance > 0.0;
  const bool cache = cache_apart || cache_touching;
  // (kHeld: a touching pair of a step that holds its contacts, hold_contacts())
  // (kBoundsApart: a candidate by the broad phase's boxes whose bounds do not meet this step)
  enum : std::uint8_t {
    kTouching, kTouchingCached, kMoved, kHeld, kFoundApart, kStillApart, kBoundsApart
  };
  // held contacts (contacts.h): the candidates last step's (each candidate's outcome_ is then
  // still last step's as it is read, and touching_ last step's touching ones), the blocks
  // packed or held last step, each point's separation in them computed from the bodies' final
  // poses, no restitution to bounce with
  const bool soft = settings_.solver == ContactSolver::SoftStep;
  const bool hold = settings_.contact_hold_distance > 0.0 && cache_touching &&
                    settings_.warm_start && lanes_ && blocks_follow_contacts_ &&
                    !separations_stale_ && !any_restitution_ && !contacts_.empty();
  // (find_pairs() leaves last step's candidates in sorted_candidates_, swapped out)
  held_ = hold && poses_packed_ && outcome_.size() == n &&
          (pairs_kept_ || candidates_ == sorted_candidates_);
  const std::size_t m_held = held_ ? contacts_.size() : 0;
  if (held_) {
    // which touching pairs moved past the hold distance since their contacts were packed; each
    // block with such a lane is packed again, every lane of it
    contact_refresh_.assign(m_held, 0);
    parallel_for(threads_, (m_held + kMotionLanes - 1) / kMotionLanes, m_held >= 1024,
                 [&](std::size_t g) {
                   std::array<std::array<float, 2>, kMotionLanes> motion;
                   const std::size_t first = g * kMotionLanes;
                   const std::size_t last = std::min(m_held, first + kMotionLanes);
                   held_motion_in_lanes(first, last, motion);
                   for (std::size_t i = 0; i < last - first; ++i)
                     contact_refresh_[first + i] = std::max(motion[i][0], motion[i][1]) >
                                                   settings_.contact_hold_distance;
                 });
    block_refresh_.assign(lanes_->blocks.size(), 0);
    for (std::size_t i = 0; i < m_held; ++i)
      if (contact_refresh_[i]) block_refresh_[block_of_contact_[i]] = 1;
    refreshed_.clear();
    for (std::size_t i = 0; i < m_held; ++i) {
      contact_refresh_[i] = block_refresh_[block_of_contact_[i]];
      if (contact_refresh_[i]) refreshed_.push_back(std::uint32_t(i));
    }
    held_count_ = m_held - refreshed_.size();
  }
  outcome_.resize(n);
  if (cache) {
    candidate_slot_.resize(n);
    has_entry_.assign(n, 0);
    std::size_t j = 0;
    for (std::size_t k = 0; k < n; ++k) {
      for (; j < cache_slots_.size() && cache_slots_[j].key < candidates_[k]; ++j)
        free_slots_.push_back(cache_slots_[j].slot);
      if (j < cache_slots_.size() && cache_slots_[j].key == candidates_[k]) {
        candidate_slot_[k] = cache_slots_[j++].slot;
        has_entry_[k] = 1;
      } else if (!free_slots_.empty()) {
        candidate_slot_[k] = free_slots_.back();
        free_slots_.pop_back();
      } else {
        candidate_slot_[k] = std::uint32_t(cache_pool_.size());
        cache_pool_.emplace_back();
      }
    }
    for (; j < cache_slots_.size(); ++j) free_slots_.push_back(cache_slots_[j].slot);
  }
  std::size_t reused = 0, moved = 0;
  // the candidates tested, in pair order: every one, or where the step holds those apart last
  // step and the touching ones whose blocks are packed again (the others are held), each with
  // whether it touched last step
  auto visit_all = [&] {
    visit_.resize(n);
    for (std::size_t k = 0; k < n; ++k) visit_[k] = std::uint32_t(k);
  };
  if (held_) {
    visit_.clear();
    visit_touched_.clear();
    std::size_t contact = 0;  // last step's touching candidates are its contacts, in order
    for (std::size_t k = 0; k < n; ++k) {
      const bool touched = outcome_[k] <= kHeld;
      if (touched && !contact_refresh_[contact++]) {
        outcome_[k] = kHeld;
        continue;
      }
      visit_.push_back(std::uint32_t(k));
      visit_touched_.push_back(touched);
    }
    held_ = contact == m_held;
  }
  if (!held_) visit_all();
  // the entries of the next group's pairs (kMotionLanes at a time, motion_in_lanes)
  constexpr std::size_t kCacheAhead = kMotionLanes;
  // in halves of the pair order, as the contacts are built below and the colours' shares solved:
  // each thread then reads back the manifolds it wrote. Handed out 64 pairs at a time, the two
  // threads wrote each other's cache lines (a pair's outcome is a byte) and read half the
  // manifolds from the other core: at base 100 this loop took 0.85 ms on two threads against
  // 1.15 on one, 0.55 in halves
  // (the counts are the calling thread's: the loop's reduction, or the function's own)
  auto collide_group = [&](std::size_t group, std::size_t& reused, std::size_t& moved) {
    const std::size_t visits = visit_.size();
    const std::size_t group_first = group * kMotionLanes;
    const std::size_t group_last = std::min(visits, group_first + kMotionLanes);
    std::array<std::array<float, 2>, kMotionLanes> motion_of;
    if (cache) motion_in_lanes(&visit_[group_first], group_last - group_first, motion_of);
    for (std::size_t at = group_first; at < group_last; ++at) {
      const std::size_t k = visit_[at];
      const BodyId a = BodyId(candidates_[k] >> 32), b = BodyId(candidates_[k] & 0xffffffffu);
      pair_growth_[k] = pair_growth(shapes_[a], shapes_[b]);
      if (cache && at + kCacheAhead < visits) {
        // the entries are in no order the hardware prefetcher follows
        const auto* ahead =
            reinterpret_cast<const char*>(&cache_pool_[candidate_slot_[visit_[at + kCacheAhead]]]);
        for (std::size_t line = 0; line < sizeof(CachedPair); line += 64)
          __builtin_prefetch(ahead + line);
      }
      // the broad phase's boxes meet, this step's bounds do not: apart, untested and with no
      // entry, as where the broad phase looked for pairs with the bounds themselves
      if (!bounds_meet(a, b)) {
        manifolds_[k].count = 0;
        outcome_[k] = kBoundsApart;
        continue;
      }
      if (cache && has_entry_[k]) {
        // A pair grown since (a body sped up) spends the growth from the same distance
        const CachedPair& cached = cache_pool_[candidate_slot_[k]];
        const std::array<double, 2> motion = {motion_of[at - group_first][0],
                                               motion_of[at - group_first][1]};
        const double grown = std::max(pair_growth_[k] - double(cached.growth), 0.0);
        if (cached.count == 0 &&
            std::min(motion[0], motion[1]) + grown <= settings_.pair_cache_distance) {
          // the shapes are no closer than when found apart, less the cache distance
          manifolds_[k].count = 0;
          outcome_[k] = kStillApart;
          ++reused;
          continue;
        }
        // (a box on a plane: both the box's motion in the plane's frame, motion_in_lanes)
        if (cached.count != 0 &&
            std::max(motion[0], motion[1]) + grown <= settings_.manifold_reuse_distance) {
          move_manifold(cached, a, b, pair_growth_[k], manifolds_[k]);
          outcome_[k] = kMoved;
          ++moved;
          continue;
        }
      }
      Shape grown_a = shapes_[a].shape, grown_b = shapes_[b].shape;
      grow_pair(shapes_[a], shapes_[b], grown_a, grown_b);
      Manifold& manifold = manifolds_[k];
      // a box pair by this copy's own test, the hot one (collide()'s table holds the library's,
      // at the baseline: docs/solver.md, "One binary, the widest passes the core has")
      manifold.axes_tested = 0;
      const bool boxes = grown_a.kind == ShapeKind::Box && grown_b.kind == ShapeKind::Box;
      const bool touching =
          boxes ? box_pairs::collide_boxes(hulls_, grown_a, poses_[a], grown_b, poses_[b], manifold)
                : collide(hulls_, grown_a, poses_[a], grown_b, poses_[b], manifold);
      if (!touching) manifold.count = 0;
      if (manifold.count == 0) {
        outcome_[k] = kFoundApart;
        if (cache_apart)
          cache_pair(a, b, pair_growth_[k], nullptr, cache_pool_[candidate_slot_[k]]);
        continue;
      }
      outcome_[k] = kTouching;
      // a box pair's face contact (its normal a face's, its points on that face and the other
      // box's surface), or a box on a plane (its points the box's corners); edge contacts and
      // the other shapes are computed every step
      auto box_or_plane = [&](BodyId i) {
        return shapes_[i].kind == BodyShape::Box || shapes_[i].kind == BodyShape::Plane;
      };
      // (two planes never collide: planes are static)
      bool movable = cache_touching && box_or_plane(a) && box_or_plane(b);
      for (std::uint8_t j = 0; j < manifold.count && movable; ++j)
        movable = manifold.points[j].feature.type != ContactType::EdgeEdge;
      if (movable) {
        cache_pair(a, b, pair_growth_[k], &manifold, cache_pool_[candidate_slot_[k]]);
        outcome_[k] = kTouchingCached;
      }
    }
  };
  auto collide_all = [&] {
    reused = moved = 0;
    const std::size_t groups = (visit_.size() + kMotionLanes - 1) / kMotionLanes;
    if (threads_ > 1 && n >= 1024) {
#pragma omp parallel for num_threads(threads_) schedule(static) reduction(+ : reused, moved)
      for (std::size_t group = 0; group < groups; ++group) collide_group(group, reused, moved);
    } else {
      for (std::size_t group = 0; group < groups; ++group) collide_group(group, reused, moved);
    }
  };
  collide_all();
  double held_deepest = 0.0;
  if (held_) {
    // a pair apart last step touches, or one touching is apart: the blocks' contacts change, and
    // the step builds them after all (every pair again: a pair's test gives the same outcome
    // twice); or a contact is deep enough to recover from, which moves the poses by them all
    bool changed = false;
    for (std::size_t at = 0; at < visit_.size() && !changed; ++at)
      changed = (outcome_[visit_[at]] <= kHeld) != (visit_touched_[at] != 0);
    if (!changed) {
      held_deepest = hold_contacts(dt, gravity);
      // the contacts packed again, built aside (last step's stay for their impulses, and for
      // the build of every contact should the step not hold after all), on the threads
      const std::size_t r = refreshed_.size();
      refreshed_contacts_.resize(r);
      double deepest = 0.0;
#pragma omp parallel for num_threads(threads_) schedule(static) reduction(max : deepest) \
    if (threads_ > 1 && r >= 64)
      for (std::size_t j = 0; j < r; ++j) {
        const std::size_t k = touching_[refreshed_[j]];
        deepest = std::max(deepest, build_contact(manifolds_[k], BodyId(candidates_[k] >> 32),
                                                  BodyId(candidates_[k] & 0xffffffffu), states,
                                                  refreshed_contacts_[j]));
      }
      held_deepest = std::max(held_deepest, deepest);
    }
    if (changed || (soft && held_deepest > settings_.max_push_speed * dt)) {
      held_ = false;
      visit_all();
      collide_all();
    }
  }
  reused_ = reused;
  moved_ = moved;

  // the touching candidates in pair order, each to its place in contacts_; the cached ones'
  // slots kept for the next step (an entry kept holds the pose it was computed at, so that
  // motion adds up), the others' freed
  // (written through pointers, sized for every candidate first: pushed back, the loop reloaded
  // the vectors' ends at every pair; serial, this loop and the slots' above took about 2 % of a
  // two-thread step at pyramid-100)
  touching_.resize(n);
  next_cache_slots_.resize(cache ? n : 0);
  std::uint32_t* touching = touching_.data();
  CacheSlot* kept = next_cache_slots_.data();
  std::size_t touching_count = 0, kept_count = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const std::uint8_t outcome = outcome_[k];
    touching[touching_count] = std::uint32_t(k);
    touching_count += outcome <= kHeld;
    if (!cache) continue;
    if (outcome == kTouchingCached || outcome == kMoved || outcome == kStillApart ||
        (outcome == kHeld && has_entry_[k]) || (outcome == kFoundApart && cache_apart))
      kept[kept_count++] = {candidates_[k], candidate_slot_[k]};
    else
      free_slots_.push_back(candidate_slot_[k]);
  }
  touching_.resize(touching_count);
  next_cache_slots_.resize(kept_count);
  std::swap(cache_slots_, next_cache_slots_);
  // holding, the contacts stay, each of a block packed again built again over its record of
  // last step, which it is matched with (hold_contacts() carried the others' separations on)
  if (held_) {
    // (the counts as sums of changes, each a thread's, from last step's)
    std::ptrdiff_t points = 0, matched = 0;
    const std::size_t r = refreshed_.size();
    // a contact's impulses read from its lane touch seven lines of its block: where many are
    // packed again (a settling pile), the blocks are written out in order first
    if (impulses_in_blocks_ && 8 * r > m_held) write_impulses();
#pragma omp parallel for num_threads(threads_) schedule(static) reduction(+ : points, matched) \
    if (threads_ > 1 && r >= 64)
    for (std::size_t j = 0; j < r; ++j) {
      const std::size_t i = refreshed_[j], k = touching_[i];
      const BodyId a = BodyId(candidates_[k] >> 32), b = BodyId(candidates_[k] & 0xffffffffu);
      ContactConstraint& c = contacts_[i];
      const ContactConstraint last = c;
      c = refreshed_contacts_[j];
      record_pose(a, b, packed_poses_[i].data());
      const std::ptrdiff_t carried = std::ptrdiff_t(carry_impulses(last, stored_impulses(i), c));
      c.cold = cold_points(c, dt, gravity);
      points += std::ptrdiff_t(c.count) - std::ptrdiff_t(last.count);
      matched += carried - std::ptrdiff_t(last.count);
    }
    deepest_ = held_deepest;
    const std::ptrdiff_t before = std::ptrdiff_t(point_count_);  // every point matched, held
    point_count_ = std::size_t(before + points);
    matched_ = std::size_t(before + matched);
    return;
  }
  if (impulses_in_blocks_) write_impulses();  // (before the blocks stop following contacts_)
  blocks_follow_contacts_ = false;
  poses_packed_ = hold;

  // every contact built and matched with last step's on the threads (each writes its own; last
  // step's is found by key in its sorted list): the same contacts on any number of threads
  std::swap(contacts_, previous_);
  std::swap(impulses_, previous_impulses_);
  std::swap(contact_keys_, previous_keys_);
  const std::size_t m = touching_.size();
  contacts_.resize(m);
  contact_keys_.resize(m);
  contact_class_.resize(m);
  if (hold) packed_poses_.resize(m);
  double deepest = 0.0;
  std::size_t matched = 0, points = 0;
  // in chunks, each of which finds its first contact's place among last step's keys by a search
  // and walks on from there: both lists are in key order, and a search a contact cost about
  // fourteen probes each
  constexpr std::size_t kChunk = 256;
  const std::size_t chunks = (m + kChunk - 1) / kChunk;
  // (the totals are the calling thread's: the loop's reduction, or the function's own)
  auto build_chunk = [&](std::size_t chunk, double& deepest, std::size_t& matched,
                         std::size_t& points) {
    const std::size_t first = chunk * kChunk, last = std::min(m, first + kChunk);
    std::size_t old = std::size_t(std::lower_bound(previous_keys_.begin(), previous_keys_.end(),
                                                   candidates_[touching_[first]]) -
                                  previous_keys_.begin());
    for (std::size_t i = first; i < last; ++i) {
      const std::size_t k = touching_[i];
      const Manifold& manifold = manifolds_[k];
      const BodyId a = BodyId(candidates_[k] >> 32), b = BodyId(candidates_[k] & 0xffffffffu);
      ContactConstraint& c = contacts_[i];
      if (hold) record_pose(a, b, packed_poses_[i].data());
      deepest = std::max(deepest, build_contact(manifold, a, b, states, c));
      contact_keys_[i] = c.key();
      points += c.count;
      // the same pair last step: carry each point's impulses by feature id (warm starting);
      // then which points start cold
      while (old < previous_keys_.size() && previous_keys_[old] < c.key()) ++old;
      if (settings_.warm_start && old < previous_keys_.size() && previous_keys_[old] == c.key())
        matched += carry_impulses(previous_[old], previous_impulses_[old], c);
      c.cold = cold_points(c, dt, gravity);
      bool quiet = c.cold == 0 && c.friction_impulse[0] == 0.0f &&
                   c.friction_impulse[1] == 0.0f && c.twist_impulse == 0.0f;
      for (std::uint8_t j = 0; j < c.count && quiet; ++j)
        quiet = c.points[j].normal_impulse == 0.0f;
      contact_class_[i] = c.cold != 0 ? kColdContact : quiet ? kQuietContact : 0;
    }
  };
  if (threads_ > 1 && m >= 1024) {
#pragma omp parallel for num_threads(threads_) schedule(static) reduction(max : deepest) \
    reduction(+ : matched, points)
    for (std::size_t chunk = 0; chunk < chunks; ++chunk)
      build_chunk(chunk, deepest, matched, points);
  } else {
    for (std::size_t chunk = 0; chunk < chunks; ++chunk)
      build_chunk(chunk, deepest, matched, points);
  }
  deepest_ = deepest;
  matched_ = matched;
  point_count_ = points;
}

double ContactPipeline::build_contact(const Manifold& manifold, BodyId a, BodyId b,
                                      std::span<const BodyState> states,
                                      ContactConstraint& c) const {
  // a touching pair's contact from its manifold, its impulses zero and no point cold yet (the
  // match with last step's and cold_points() follow); returns its deepest overlap (m)
  double deepest = 0.0;
  // every field written once (assigning ContactConstraint{} first built a zeroed one on
  // the stack and copied it in: about a quarter of this loop's samples by perf)
  c.body_a = a;
  c.body_b = b;
  c.friction_impulse = {0.0f, 0.0f};
  c.twist_impulse = 0.0f;
  c.cold = 0;
  // the points past the count are read in lanes (masked by multiplying): zeros, not NaN
  for (std::uint8_t j = manifold.count; j < 4; ++j) c.points[j] = ContactPointConstraint{};
  c.normal = manifold.normal.cast<float>();
  Vec3 tangent[2];
  tangent_basis(manifold.normal, tangent);
  c.tangent[0] = tangent[0].cast<float>();
  c.tangent[1] = tangent[1].cast<float>();
  // the pair's coefficients (docs/scene-format.md): √(μa μb), max(ea, eb)
  c.friction = float(std::sqrt(shapes_[a].friction * shapes_[b].friction));
  c.restitution = float(std::max(shapes_[a].restitution, shapes_[b].restitution));
  c.count = manifold.count;
  // a grown surface lies its growth beyond the true one along the normal (a's towards b, b's
  // towards a), so the midpoint of the true surfaces is the manifold's point moved by half
  // the difference: a sphere that rolls fast on a plane (the whole motion bound on the
  // plane's side) would otherwise take friction up to 4 cm inside itself and roll slow
  const auto [growth_a, growth_b] = surface_growth(shapes_[a], shapes_[b]);
  const Vec3 shift = 0.5 * (growth_b - growth_a) * manifold.normal;
  // a box against a plane: each point a corner of the box, which grows by its half extents,
  // so that its grown corner lies half the speculative distance beyond the true one along
  // each of the box's axes, not along n: the true corner, its true height and the point
  // below it (a door leaning 0.2 rad on its edge, pivoting 1 cm beyond it and held 2 mm up,
  // fell 3 % slow)
  const BodyId box = shapes_[a].kind == BodyShape::Box ? a : b;
  const BodyId plane = box == a ? b : a;
  const bool box_on_plane =
      shapes_[box].kind == BodyShape::Box && shapes_[plane].kind == BodyShape::Plane;
  const bool two_boxes = shapes_[a].kind == BodyShape::Box && shapes_[b].kind == BodyShape::Box;
  // the corner of box `of` nearest `near` (a point of its grown corner), grown by `growth` beyond
  // the true one along each of its axes (0: the true corner); the shape holds the fixed growth,
  // the pair's may be more (surface_growth())
  const double fixed = 0.5 * settings_.speculative_distance;
  auto corner_of = [&](BodyId of, const Vec3& near, double growth) {
    const Quat& turn = states[of].orientation;
    const Vec3 sign = (turn.conjugate() * (near - states[of].position)).array().sign();
    const Vec3 half = shapes_[of].shape.half_extents.array() - fixed + growth;
    return Vec3(states[of].position + turn * Vec3(sign.array() * half.array()));
  };
  for (std::uint8_t j = 0; j < manifold.count; ++j) {
    ContactPointConstraint& p = c.points[j];
    // the point between the true surfaces: the manifold's lies between the grown ones;
    // its depth is of the grown shapes, less the growth: the real separation (< 0:
    // penetrating)
    const ContactPoint& found = manifold.points[j];
    Vec3 point = found.point + shift;
    double separation = growth_a + growth_b - found.depth;
    if (box_on_plane) {
      const BodyShapeData& on = shapes_[plane];
      const Vec3 corner = corner_of(box, found.point, 0.0);
      separation = on.plane_normal.dot(corner) - (on.plane_offset - fixed);
      point = corner - 0.5 * separation * on.plane_normal;
    } else if (two_boxes && found.feature.type == ContactType::FaceVertex) {
      // a corner of one box below the other's face: the grown corner lies the growth beyond
      // the true one along each of its box's axes, so up to √3 times it along n where the box
      // is turned (a box leaning 40° on a wall rested 4 mm off it); the true corner, its
      // height over the reference face (a face: grown by its growth along n exactly; the
      // grown corner's height over the grown face is the manifold's, −depth), and the point
      // midway
      const bool incident_a = found.feature.flipped != 0;
      const BodyId incident = incident_a ? a : b;
      const double growth = incident_a ? growth_a : growth_b;
      const double reference_growth = incident_a ? growth_b : growth_a;
      const Vec3 corner = corner_of(incident, found.point, 0.0);
      const double along = manifold.normal.dot(corner - corner_of(incident, found.point, growth));
      separation = -found.depth + reference_growth + (incident_a ? -along : along);
      point = corner + (incident_a ? 0.5 : -0.5) * separation * manifold.normal;
    }
    p.anchor_a = (point - states[a].position).cast<float>();
    p.anchor_b = (point - states[b].position).cast<float>();
    p.base_separation = float(separation);
    p.normal_impulse = 0.0f;
    p.feature = manifold.points[j].feature;
    deepest = std::max(deepest, -separation);
  }
  return deepest;
}

std::size_t ContactPipeline::point_count() const { return point_count_; }

double ContactPipeline::deepest_penetration() const { return deepest_; }

}  // namespace RTP_CONTACT_ISA_NAMESPACE
}  // namespace rtp
