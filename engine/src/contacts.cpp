// The contact pipeline's collision half: shapes, bounds, candidate pairs, manifolds, and the
// match with last step's contacts (contacts.h says what each stage does). Over 800 lines because
// the pair cache and the growth bookkeeping serve the one collide_pairs() stage and share its
// private state; split out, they would be its internals in two places.
#include "contacts.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <limits>
#include <stdexcept>

#include "threads.h"

namespace rtp {
inline namespace RTP_CONTACT_ISA_NAMESPACE {

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

namespace {

// the two bodies of a pair in one number, lower id first: sorting by it orders pairs by body
std::uint64_t pair_key(BodyId a, BodyId b) {
  return a < b ? std::uint64_t(a) << 32 | b : std::uint64_t(b) << 32 | a;
}

Pose pose_of(const BodyState& s) { return Pose(s.position, s.orientation); }

// two unit tangents that make a right-handed frame with n, a function of n alone (Catto,
// "Computing a basis", 2014): the same normal gets the same basis every step
// (written in scalars, one square root and one division: Eigen's normalized() on the
// three-vector went through the stack, two stores read back as one, and divided twice)
void tangent_basis(const Vec3& n, Vec3 tangent[2]) {
  if (std::abs(n.x()) >= 0.57735026919) {
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
      // boxes of one size share one hull
      std::uint32_t hull = kNoHull;
      for (const BodyShapeData& other : shapes_)
        if (other.kind == BodyShape::Box && other.shape.half_extents == half)
          hull = other.shape.hull;
      if (hull == kNoHull) {
        hull = std::uint32_t(hulls_.size());
        hulls_.push_back(make_box_hull(half));
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
    broad_phase_->move(data.proxy, box);
  });
  fast_.clear();
  for (std::size_t i = 0; i < shapes_.size(); ++i)
    if (fast_flags_[i]) fast_.push_back({BodyId(i), states[i].position, states[i].orientation});
}

void ContactPipeline::find_pairs() {
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
    // every dynamic body whose bounds reach a plane (its lowest corner along the normal at or
    // below the plane's grown surface, 0.1 mm of slack for the bounds' single precision): a
    // pyramid's 5,050 boxes are 100 that touch the ground and 4,950 the narrow phase need not see
    constexpr double kSlack = 1e-4;
    for (BodyId plane : planes_) {
      const Vec3& n = shapes_[plane].plane_normal;
      const double surface = shapes_[plane].plane_offset + kSlack;
      for (std::size_t i = first_body; i < last_body; ++i) {
        const BodyId body = dynamic_shaped_[i];
        const Aabb& box = bounds_[body];
        double lowest = 0.0;
        for (int k = 0; k < 3; ++k)
          lowest += n[k] * (n[k] >= 0.0 ? double(box.min[k]) : double(box.max[k]));
        if (lowest <= surface) add(pair_key(plane, body));
      }
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
  enum : std::uint8_t { kTouching, kTouchingCached, kMoved, kFoundApart, kStillApart };
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
  // the entries of the next group's pairs (kMotionLanes at a time, motion_in_lanes)
  constexpr std::size_t kCacheAhead = kMotionLanes;
  const std::size_t groups = (n + kMotionLanes - 1) / kMotionLanes;
  // in halves of the pair order, as the contacts are built below and the colours' shares solved:
  // each thread then reads back the manifolds it wrote. Handed out 64 pairs at a time, the two
  // threads wrote each other's cache lines (a pair's outcome is a byte) and read half the
  // manifolds from the other core: at base 100 this loop took 0.85 ms on two threads against
  // 1.15 on one, 0.55 in halves
  // (the counts are the calling thread's: the loop's reduction, or the function's own)
  auto collide_group = [&](std::size_t group, std::size_t& reused, std::size_t& moved) {
    const std::size_t group_first = group * kMotionLanes;
    const std::size_t group_last = std::min(n, group_first + kMotionLanes);
    std::array<std::array<float, 2>, kMotionLanes> motion_of;
    if (cache) motion_in_lanes(group_first, group_last, motion_of);
    for (std::size_t k = group_first; k < group_last; ++k) {
      const BodyId a = BodyId(candidates_[k] >> 32), b = BodyId(candidates_[k] & 0xffffffffu);
      pair_growth_[k] = pair_growth(shapes_[a], shapes_[b]);
      if (cache && k + kCacheAhead < n) {
        // the entries are in no order the hardware prefetcher follows
        const auto* ahead =
            reinterpret_cast<const char*>(&cache_pool_[candidate_slot_[k + kCacheAhead]]);
        for (std::size_t line = 0; line < sizeof(CachedPair); line += 64)
          __builtin_prefetch(ahead + line);
      }
      if (cache && has_entry_[k]) {
        // A pair grown since (a body sped up) spends the growth from the same distance
        const CachedPair& cached = cache_pool_[candidate_slot_[k]];
        const std::array<double, 2> motion = {motion_of[k - group_first][0],
                                               motion_of[k - group_first][1]};
        const double grown = std::max(pair_growth_[k] - double(cached.growth), 0.0);
        if (cached.count == 0 &&
            std::min(motion[0], motion[1]) + grown <= settings_.pair_cache_distance) {
          // the shapes are no closer than when found apart, less the cache distance
          manifolds_[k].count = 0;
          outcome_[k] = kStillApart;
          ++reused;
          continue;
        }
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
      if (!collide(hulls_, grown_a, poses_[a], grown_b, poses_[b], manifold)) manifold.count = 0;
      if (manifold.count == 0) {
        outcome_[k] = kFoundApart;
        if (cache_apart)
          cache_pool_[candidate_slot_[k]] = cache_pair(a, b, pair_growth_[k], nullptr);
        continue;
      }
      outcome_[k] = kTouching;
      // a box pair's face contact (its normal a face's, its points on that face and the other
      // box's surface); edge contacts and the other shapes are computed every step
      bool movable = cache_touching && shapes_[a].kind == BodyShape::Box &&
                     shapes_[b].kind == BodyShape::Box;
      for (std::uint8_t j = 0; j < manifold.count && movable; ++j)
        movable = manifold.points[j].feature.type != ContactType::EdgeEdge;
      if (movable) {
        cache_pool_[candidate_slot_[k]] = cache_pair(a, b, pair_growth_[k], &manifold);
        outcome_[k] = kTouchingCached;
      }
    }
  };
  if (threads_ > 1 && n >= 1024) {
#pragma omp parallel for num_threads(threads_) schedule(static) reduction(+ : reused, moved)
    for (std::size_t group = 0; group < groups; ++group) collide_group(group, reused, moved);
  } else {
    for (std::size_t group = 0; group < groups; ++group) collide_group(group, reused, moved);
  }
  reused_ = reused;
  moved_ = moved;

  // the touching candidates in pair order, each to its place in contacts_; the cached ones'
  // slots kept for the next step (an entry kept holds the pose it was computed at, so that
  // motion adds up), the others' freed
  next_cache_slots_.clear();
  touching_.clear();
  for (std::size_t k = 0; k < n; ++k) {
    const std::uint8_t outcome = outcome_[k];
    if (outcome <= kMoved) touching_.push_back(std::uint32_t(k));
    if (!cache) continue;
    if (outcome == kTouchingCached || outcome == kMoved || outcome == kStillApart ||
        (outcome == kFoundApart && cache_apart))
      next_cache_slots_.push_back({candidates_[k], candidate_slot_[k]});
    else
      free_slots_.push_back(candidate_slot_[k]);
  }
  std::swap(cache_slots_, next_cache_slots_);

  // every contact built and matched with last step's on the threads (each writes its own; last
  // step's is found by key in its sorted list): the same contacts on any number of threads
  std::swap(contacts_, previous_);
  std::swap(impulses_, previous_impulses_);
  std::swap(contact_keys_, previous_keys_);
  const std::size_t m = touching_.size();
  contacts_.resize(m);
  contact_keys_.resize(m);
  contact_class_.resize(m);
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
      // every field written once (assigning ContactConstraint{} first built a zeroed one on
      // the stack and copied it in: a fifth of this loop's time by perf)
      ContactConstraint& c = contacts_[i];
      c.body_a = a;
      c.body_b = b;
      c.friction_impulse = {0.0f, 0.0f};
      c.twist_impulse = 0.0f;
      c.cold = 0;
      // the points past the count are read in lanes (masked by multiplying): zeros, not NaN
      for (std::uint8_t j = manifold.count; j < 4; ++j) c.points[j] = ContactPointConstraint{};
      contact_keys_[i] = c.key();
      c.normal = manifold.normal.cast<float>();
      Vec3 tangent[2];
      tangent_basis(manifold.normal, tangent);
      c.tangent[0] = tangent[0].cast<float>();
      c.tangent[1] = tangent[1].cast<float>();
      // the pair's coefficients (docs/scene-format.md): √(μa μb), max(ea, eb)
      c.friction = float(std::sqrt(shapes_[a].friction * shapes_[b].friction));
      c.restitution = float(std::max(shapes_[a].restitution, shapes_[b].restitution));
      c.count = manifold.count;
      points += c.count;
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
      for (std::uint8_t j = 0; j < manifold.count; ++j) {
        ContactPointConstraint& p = c.points[j];
        // the point between the true surfaces: the manifold's lies between the grown ones;
        // its depth is of the grown shapes, less the growth: the real separation (< 0:
        // penetrating)
        Vec3 point = manifold.points[j].point + shift;
        double separation = growth_a + growth_b - manifold.points[j].depth;
        if (box_on_plane) {
          const double fixed = 0.5 * settings_.speculative_distance;
          const BodyShapeData& on = shapes_[plane];
          const Quat& turn = states[box].orientation;
          const Vec3 local = turn.conjugate() * (manifold.points[j].point - states[box].position);
          const Vec3 half = shapes_[box].shape.half_extents.array() - fixed;
          const Vec3 corner =
              states[box].position +
              turn * Vec3(local.array().sign() * half.array());
          separation = on.plane_normal.dot(corner) - (on.plane_offset - fixed);
          point = corner - 0.5 * separation * on.plane_normal;
        }
        p.anchor_a = (point - states[a].position).cast<float>();
        p.anchor_b = (point - states[b].position).cast<float>();
        p.base_separation = float(separation);
        p.normal_impulse = 0.0f;
        p.feature = manifold.points[j].feature;
        deepest = std::max(deepest, -separation);
      }
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
  int unmatched = 0;
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
    unmatched += source[i] < 0;
  }
  const double match_squared = settings_.match_distance * settings_.match_distance;
  for (std::uint8_t i = 0; i < c.count && unmatched > 0; ++i) {
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

ContactPipeline::CachedPair ContactPipeline::cache_pair(BodyId a, BodyId b, double growth,
                                                        const Manifold* manifold) const {
  const Pose& pa = poses_[a];
  const Pose& pb = poses_[b];
  CachedPair out;
  out.offset_in_a = (pa.rotation.transpose() * (pb.position - pa.position)).cast<float>();
  out.offset_in_b = (pb.rotation.transpose() * (pa.position - pb.position)).cast<float>();
  out.relative_rotation = (pa.rotation.transpose() * pb.rotation).cast<float>();
  out.growth = float(growth);
  if (manifold == nullptr) return out;
  // a face's normal turns with the body whose face it is; a point is the midpoint of the two
  // surface points it joins, which are half its depth either side along the normal
  out.count = manifold->count;
  out.normal_on_b = manifold->points[0].feature.flipped != 0;
  const Pose& holder = out.normal_on_b ? pb : pa;
  out.normal = (holder.rotation.transpose() * manifold->normal).cast<float>();
  for (std::uint8_t j = 0; j < manifold->count; ++j) {
    const ContactPoint& p = manifold->points[j];
    const Vec3 half = 0.5 * p.depth * manifold->normal;
    out.points[j].on_a = (pa.rotation.transpose() * (p.point + half - pa.position)).cast<float>();
    out.points[j].on_b = (pb.rotation.transpose() * (p.point - half - pb.position)).cast<float>();
    out.points[j].feature = p.feature;
  }
  return out;
}

void ContactPipeline::motion_in_lanes(std::size_t first, std::size_t last,
                                      std::array<std::array<float, 2>, kMotionLanes>& out) const {
  // How far b's shape has moved in a's frame since the entry was made: by the offset's change,
  // and by the rotation's change at b's farthest surface point (‖ΔR‖₂ ≤ ‖ΔR‖_F); and a's in b's
  // frame likewise (a plane has no bound of its own: its side is the other's). In single
  // precision, a pair a lane: the rotations and the entries' poses read as records and
  // transposed, the offset between the centres taken in double first (m; each pair's a, b)
  using L = simd::Pack<float, kMotionLanes>;
  using Index = simd::MaskOf<L>;
  constexpr int kEntryFloats = int(sizeof(CachedPair) / sizeof(float));
  static_assert(sizeof(CachedPair) % sizeof(float) == 0 &&
                offsetof(CachedPair, offset_in_b) == 3 * sizeof(float) &&
                offsetof(CachedPair, relative_rotation) == 6 * sizeof(float));
  alignas(64) float offset[3][kMotionLanes] = {}, reach_a[kMotionLanes] = {},
                    reach_b[kMotionLanes] = {};
  Index at_a{}, at_b{}, at_entry{};
  bool any = false;
  for (std::size_t i = 0; i < kMotionLanes; ++i) {
    const std::size_t k = first + i;
    // a lane without an entry reads body 0 and slot 0 (there is one: some lane has an entry)
    at_a[i] = at_b[i] = at_entry[i] = 0;
    if (k >= last || !has_entry_[k]) continue;
    any = true;
    const BodyId a = BodyId(candidates_[k] >> 32), b = BodyId(candidates_[k] & 0xffffffffu);
    const Vec3 d = poses_[b].position - poses_[a].position;
    for (int j = 0; j < 3; ++j) offset[j][i] = float(d[j]);
    reach_a[i] = float(shapes_[a].reach);
    reach_b[i] = float(shapes_[b].reach);
    at_a[i] = std::int32_t(a * kRotationFloats);
    at_b[i] = std::int32_t(b * kRotationFloats);
    at_entry[i] = std::int32_t(candidate_slot_[k]) * kEntryFloats;
  }
  if (!any) return;
  const float* rotations = rotations_.front().data();
  const float* entries = reinterpret_cast<const float*>(cache_pool_.data());
  L a_low[8], a_high[8], b_low[8], b_high[8], e_low[8], e_high[8];
  simd::gather_records(rotations, at_a, a_low);
  simd::gather_records(rotations + 8, at_a, a_high);
  simd::gather_records(rotations, at_b, b_low);
  simd::gather_records(rotations + 8, at_b, b_high);
  simd::gather_records(entries, at_entry, e_low);
  simd::gather_records(entries + 8, at_entry, e_high);
  // R(r, c) of each body row by row; the entry's offsets, then Raᵀ Rb column by column
  auto ra = [&](int r, int c) { return 3 * r + c < 8 ? a_low[3 * r + c] : a_high[0]; };
  auto rb = [&](int r, int c) { return 3 * r + c < 8 ? b_low[3 * r + c] : b_high[0]; };
  auto entry = [&](int f) { return f < 8 ? e_low[f] : e_high[f - 8]; };
  const L d[3] = {simd::load<L>(offset[0]), simd::load<L>(offset[1]), simd::load<L>(offset[2])};
  L turned_squared = simd::splat<L>(0.0f), moved_b_squared = turned_squared,
    moved_a_squared = turned_squared;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const L m = ra(0, i) * rb(0, j) + ra(1, i) * rb(1, j) + ra(2, i) * rb(2, j);
      const L change = m - entry(6 + i + 3 * j);
      turned_squared = turned_squared + change * change;
    }
    // Raᵀ (xb − xa) and Rbᵀ (xa − xb) against the entry's
    const L in_a = ra(0, i) * d[0] + ra(1, i) * d[1] + ra(2, i) * d[2] - entry(i);
    const L in_b = simd::splat<L>(0.0f) - (rb(0, i) * d[0] + rb(1, i) * d[1] + rb(2, i) * d[2]) -
                   entry(3 + i);
    moved_b_squared = moved_b_squared + in_a * in_a;
    moved_a_squared = moved_a_squared + in_b * in_b;
  }
  const L turned = simd::sqrt(turned_squared);
  alignas(64) float moved_a[kMotionLanes], moved_b[kMotionLanes];
  simd::store(moved_a, simd::sqrt(moved_a_squared) + turned * simd::load<L>(reach_a));
  simd::store(moved_b, simd::sqrt(moved_b_squared) + turned * simd::load<L>(reach_b));
  for (std::size_t i = 0; i < kMotionLanes; ++i) out[i] = {moved_a[i], moved_b[i]};
}

void ContactPipeline::move_manifold(const CachedPair& cached, BodyId a, BodyId b, double growth,
                                    Manifold& out) const {
  // Each point's two surface points go with their bodies, and its depth is measured between
  // them along the normal, which goes with its face. A face's point that is a corner of the
  // other box (most of a resting pair's) keeps its exact depth however the boxes slide: the
  // face point stays in the face's plane. A point where an edge crosses the face's side is off
  // by the relative motion, which the reuse distance bounds. The depth is of the shapes grown as
  // when computed; the pair's growth since shifts it, so the separation the contact takes is
  // the geometry's own
  const Pose& pa = poses_[a];
  const Pose& pb = poses_[b];
  const Pose& holder = cached.normal_on_b ? pb : pa;
  out.normal = (holder.rotation * cached.normal.cast<double>()).normalized();
  out.count = cached.count;
  double deepest = -std::numeric_limits<double>::infinity();
  for (std::uint8_t j = 0; j < cached.count; ++j) {
    const Vec3 on_a = pa.position + pa.rotation * cached.points[j].on_a.cast<double>();
    const Vec3 on_b = pb.position + pb.rotation * cached.points[j].on_b.cast<double>();
    ContactPoint& p = out.points[j];
    p.point = 0.5 * (on_a + on_b);
    p.depth = out.normal.dot(on_a - on_b) + (growth - double(cached.growth));
    p.feature = cached.points[j].feature;
    deepest = std::max(deepest, p.depth);
  }
  out.depth = deepest;
  out.axes_tested = 0;
}

double ContactPipeline::pair_growth(const BodyShapeData& a, const BodyShapeData& b) const {
  const auto [growth_a, growth_b] = surface_growth(a, b);
  return growth_a + growth_b;
}

std::pair<double, double> ContactPipeline::surface_growth(const BodyShapeData& a,
                                                          const BodyShapeData& b) const {
  // as grow_pair() places the growth: a pair with a hull keeps the fixed growth on both; two
  // boxes each their own; otherwise both shapes' growth beyond the fixed goes to the one that
  // is not a box
  const double fixed = 0.5 * settings_.speculative_distance;
  if (a.kind == BodyShape::Hull || b.kind == BodyShape::Hull) return {fixed, fixed};
  if (a.kind == BodyShape::Box && b.kind == BodyShape::Box) return {a.growth, b.growth};
  const double extra = a.growth + b.growth - 2.0 * fixed;
  if (a.kind != BodyShape::Box) return {fixed + extra, fixed};
  return {fixed, fixed + extra};
}

void ContactPipeline::grow_pair(const BodyShapeData& a, const BodyShapeData& b, Shape& grown_a,
                                Shape& grown_b) const {
  // Both shapes hold the fixed growth already; the growth beyond it goes where surface_growth()
  // places it, to what the collision function reads as a size: a sphere's radius, a plane's
  // offset, a box's half extents (the box path reads those, the hull paths the fixed hulls)
  const double fixed = 0.5 * settings_.speculative_distance;
  const auto [growth_a, growth_b] = surface_growth(a, b);
  auto widen = [](BodyShape kind, Shape& shape, double extra) {
    if (extra <= 0.0) return;
    if (kind == BodyShape::Sphere) shape.radius += extra;
    else if (kind == BodyShape::Plane) shape.plane_offset += extra;
    else if (kind == BodyShape::Box) shape.half_extents.array() += extra;
  };
  widen(a.kind, grown_a, growth_a - fixed);
  widen(b.kind, grown_b, growth_b - fixed);
}

std::size_t ContactPipeline::sweep_fast_bodies(std::span<BodyState> states) {
  // Conservative sampling of the sweep: the grown shape at poses no further apart than half its
  // thickness covers every point the moving shape passes through (a turn is sampled by its
  // surface's arc, |Δθ| reach), so the first sample that touches a static shape brackets the
  // first touch, and bisection narrows the bracket to a 2⁻¹² share of the step. A body already
  // touching at the step's start is left to its contacts. Dynamic pairs are not swept (both
  // bodies move; they tunnel past each other at such speeds, as docs/solver.md states).
  std::size_t stopped = 0;
  Manifold manifold;
  for (const FastBody& fast : fast_) {
    const BodyShapeData& data = shapes_[fast.id];
    BodyState& end = states[fast.id];
    const Vec3 travel = end.position - fast.position;
    const double turn = fast.orientation.angularDistance(end.orientation);
    const double motion = travel.norm() + turn * data.reach;
    if (!(motion > settings_.motion_margin_share * data.thinnest)) continue;
    auto pose_at = [&](double t) {
      return Pose(fast.position + t * travel, fast.orientation.slerp(t, end.orientation));
    };
    // the swept shape's bounds: the centre's path grown by the farthest surface point
    const double grown_reach = data.reach + 0.5 * settings_.speculative_distance;
    Aabb swept;
    for (int k = 0; k < 3; ++k) {
      // floats rounded outwards by a part in 10⁶: the test must not miss a wall by rounding
      const double low = std::min(fast.position[k], end.position[k]) - grown_reach;
      const double high = std::max(fast.position[k], end.position[k]) + grown_reach;
      swept.min[k] = float(low - 1e-6 * (std::abs(low) + 1.0));
      swept.max[k] = float(high + 1e-6 * (std::abs(high) + 1.0));
    }
    const int samples = int(std::ceil(motion / (0.5 * data.thinnest)));
    double first_touch = 1.0;  // the earliest clear time before a touch, over the static shapes
    bool touched = false;
    for (BodyId other : static_shaped_) {
      const BodyShapeData& wall = shapes_[other];
      if (wall.kind != BodyShape::Plane && !overlaps(swept, bounds_[other])) continue;
      const Pose wall_pose = pose_of(states[other]);
      auto touches = [&](double t) {
        return collide(hulls_, data.shape, pose_at(t), wall.shape, wall_pose, manifold);
      };
      if (touches(0.0)) continue;  // touching at the start: the step's own contact
      for (int k = 1; k <= samples; ++k) {
        const double t = double(k) / samples;
        if (t - 1.0 / samples >= first_touch) break;  // an earlier wall stops it first
        if (!touches(t)) continue;
        double clear = double(k - 1) / samples, hit = t;
        for (int i = 0; i < 12; ++i) {
          const double mid = 0.5 * (clear + hit);
          (touches(mid) ? hit : clear) = mid;
        }
        if (clear < first_touch) first_touch = clear, touched = true;
        break;
      }
    }
    if (!touched) continue;
    end.position = fast.position + first_touch * travel;
    end.orientation = fast.orientation.slerp(first_touch, end.orientation).normalized();
    ++stopped;
  }
  return stopped;
}

std::size_t ContactPipeline::point_count() const { return point_count_; }

double ContactPipeline::deepest_penetration() const { return deepest_; }

}  // namespace RTP_CONTACT_ISA_NAMESPACE
}  // namespace rtp
