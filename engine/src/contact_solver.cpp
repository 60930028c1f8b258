// The contact pipeline's solver half: warm start, the velocity solves, the substeps' velocity
// bookkeeping and restitution (docs/solver.md has the method,
// its sources and what was measured). The per-step constants the passes read (the bodies'
// records, the blocks and their effective masses) are in contact_prepare.cpp, the lane helpers
// both use in contact_solver_internal.h, the colouring in constraint_graph.cpp, the seed's solver
// in seed_solver.cpp, the impulses kept for the next step in contact_match.cpp.
//
// Every solver here works on velocities at the contact points, v_rel = (v_b + ω_b × r_b) −
// (v_a + ω_a × r_a), and applies impulses P at the anchors: v_a −= P / m_a, ω_a −= I_a⁻¹ (r_a × P),
// and the opposite on b (Catto, "Fast and Simple Physics using Sequential Impulses", GDC 2006).
// The anchors are fixed for the step; the separation of a point is tracked through the substeps
// from the bodies' motion since the step's start (Catto, Solver2D, 2024: "relative position").
//
// The soft step and sequential impulse run on lanes: the contacts of one colour (no two share a
// dynamic body) are packed W to a block, one manifold a lane, in single precision, and each
// operation of the solve runs on the W manifolds of a block at once (Box2D v3's wide solver,
// b2FloatW, does the same with its graph colours). A block's bodies are read from the body
// array (as records, transposed) and written back once per block and pass. Since a colour's
// contacts are independent, the lane count, the thread count and which block a contact lands in
// change no result. The colour past the last (contacts that found no free colour) holds one
// contact a block and is solved in order.
#include <algorithm>
#include <atomic>
#include <array>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <numbers>

#if defined(_OPENMP)
#include <omp.h>
#endif

#include "contact_solver_internal.h"
#include "contacts.h"
#include "threads.h"

namespace rtp {
inline namespace RTP_CONTACT_ISA_NAMESPACE {

namespace {

// v turned by the inverse of the unit quaternion (x, y, z, w): Rᵀ v
V3 rotate_back(const V3& q, Lane w, const V3& v) {
  const V3 t = splat(2.0f) * cross(v, q);  // 2 (v × q) = 2 ((−q) × v)
  return v + w * t - cross(q, t);           // v + w t + (−q) × t
}
#if defined(__AVX512F__)
V3 gather3(const float* base, LaneIndex index) {
  return {simd::gather<Lane>(base, index), simd::gather<Lane>(base + 1, index),
          simd::gather<Lane>(base + 2, index)};
}
#endif

// The normal rows of an isotropic block, in the manifold's frame (n, t0, t1 with t0 × t1 = n). A
// point's row reads the velocities only as the centres' relative speed along n, u = n·(v_b − v_a),
// and the angular velocities' tangent components: w·(r × n) = β (w·t0) − α (w·t1), with α = r·t0
// and β = r·t1. An impulse λ along n changes those by numbers: u by (m_a⁻¹ + m_b⁻¹) λ, and with
// an inverse inertia c·1, w_a's components by −c_a λ (β_a, −α_a) and w_b's by c_b λ (β_b, −α_b)
// (r × n = β t0 − α t1). Five lanes then carry the four rows where twelve did, and each row's
// speed and response are a few multiply-adds. The friction at the centre and the twist go the
// same way (BlockFrame: the centres kept in the frame by prepare()), and the velocities are
// written back once, after them all. The same sums as in world axes, in another order (results
// move at round-off).
struct FrameRow {
  Lane alpha_a, beta_a, alpha_b, beta_b;

  // the anchors are kept in the frame (ContactBlock::Point::anchor): α and β are read, b's
  // the offset added
  FrameRow(const ContactBlock::Point& p, const FrameOffset& offset)
      : alpha_a(p.anchor[0]),
        beta_a(p.anchor[1]),
        alpha_b(p.anchor[0] + offset.d[0]),
        beta_b(p.anchor[1] + offset.d[1]) {}
};
struct BlockFrame {
  Lane u, pa, qa, pb, qb;        // n·(v_b − v_a); w_a·t0, w_a·t1; w_b·t0, w_b·t1
  Lane sa, sb;                   // w_a·n, w_b·n: the friction's and twist's (no normal row's)
  Lane pa0, qa0, pb0, qb0, sa0, sb0;  // the components as read
  Lane total;                    // Σλ along n, for the linear velocities
  Lane friction0, friction1;     // the friction impulse applied along t0, t1
  Lane inverse_mass_sum;

  BlockFrame(const LanePair& pair, const V3& n, const V3& t0, const V3& t1)
      : u(dot(n, pair.vb - pair.va)),
        pa(dot(pair.wa, t0)),
        qa(dot(pair.wa, t1)),
        pb(dot(pair.wb, t0)),
        qb(dot(pair.wb, t1)),
        sa(dot(pair.wa, n)),
        sb(dot(pair.wb, n)),
        pa0(pa),
        qa0(qa),
        pb0(pb),
        qb0(qb),
        sa0(sa),
        sb0(sb),
        total(splat(0.0f)),
        friction0(splat(0.0f)),
        friction1(splat(0.0f)),
        inverse_mass_sum(pair.inverse_mass_a + pair.inverse_mass_b) {}
  Lane normal_velocity(const FrameRow& row) const {
    return u + (row.beta_b * pb - row.alpha_b * qb) - (row.beta_a * pa - row.alpha_a * qa);
  }
  void apply(const BlockInertia& m, const FrameRow& row, Lane impulse) {
    u = u + inverse_mass_sum * impulse;
    total = total + impulse;
    const Lane turn_a = m.a[0] * impulse, turn_b = m.b[0] * impulse;
    pa = pa - turn_a * row.beta_a;
    qa = qa + turn_a * row.alpha_a;
    pb = pb + turn_b * row.beta_b;
    qb = qb - turn_b * row.alpha_b;
  }
  // The relative velocity at the centres (α, β, γ in the frame, from each body) along t0 and
  // t1, the centres' own relative velocity along them given (the normal rows leave it as read):
  // (w × r)·t0 = γ (w·t1) − β (w·n), (w × r)·t1 = α (w·n) − γ (w·t0)
  Lane tangent_velocity0(Lane linear, const Lane (&ca)[3], const Lane (&cb)[3]) const {
    return linear + (cb[2] * qb - cb[1] * sb) - (ca[2] * qa - ca[1] * sa);
  }
  Lane tangent_velocity1(Lane linear, const Lane (&ca)[3], const Lane (&cb)[3]) const {
    return linear + (cb[0] * sb - cb[2] * pb) - (ca[0] * sa - ca[2] * pa);
  }
  // the friction impulse P = f0 t0 + f1 t1 on b at its centre, −P on a at its: r × P is
  // f0 (γ t1 − β n) + f1 (α n − γ t0)
  void apply_friction(const BlockInertia& m, const Lane (&ca)[3], const Lane (&cb)[3], Lane f0,
                      Lane f1) {
    friction0 = friction0 + f0;
    friction1 = friction1 + f1;
    const Lane ia = m.a[0], ib = m.b[0];
    pa = pa + ia * (ca[2] * f1);
    qa = qa - ia * (ca[2] * f0);
    sa = sa - ia * (ca[0] * f1 - ca[1] * f0);
    pb = pb - ib * (cb[2] * f1);
    qb = qb + ib * (cb[2] * f0);
    sb = sb + ib * (cb[0] * f1 - cb[1] * f0);
  }
  void apply_twist(const BlockInertia& m, Lane impulse) {
    sa = sa - m.a[0] * impulse;
    sb = sb + m.b[0] * impulse;
  }
  // the rows' impulses on the velocities themselves
  void store(LanePair& pair, const V3& n, const V3& t0, const V3& t1) const {
    const V3 impulse = total * n + friction0 * t0 + friction1 * t1;
    pair.va = pair.va - pair.inverse_mass_a * impulse;
    pair.vb = pair.vb + pair.inverse_mass_b * impulse;
    pair.wa = pair.wa + ((pa - pa0) * t0 + (qa - qa0) * t1 + (sa - sa0) * n);
    pair.wb = pair.wb + ((pb - pb0) * t0 + (qb - qb0) * t1 + (sb - sb0) * n);
  }
};

// a vector's world coordinates from its coordinates along t0, t1 and n (a manifold's frame)
V3 in_world(const Lane (&v)[3], const V3& n, const V3& t0, const V3& t1) {
  return v[0] * t0 + v[1] * t1 + v[2] * n;
}

// how far each lane's bodies have moved along its normal since the step's start, as what the
// points need: s = s₀' + n·(Δx_b − Δx_a) + (ΔR_bᵀ n)·r_b − (ΔR_aᵀ n)·r_a, the two turned normals
// once per manifold rather than two rotations per point. The anchors are in the manifold's frame,
// b's a's plus the offset d, so with the turned normals in the frame too (T_a, T_b) a point's is
// s₀' + [n·(Δx_b − Δx_a) + T_b·d] + (T_b − T_a)·r_a: one number and one vector a manifold
struct NormalMotion {
  Lane shift;  // n·(Δx_b − Δx_a) + T_b·d
  Lane turn[3];  // T_b − T_a

  NormalMotion(const std::vector<SolverBody>& bodies, const ContactBlock& block,
               const FrameOffset& offset) {
    const float* base = reinterpret_cast<const float*>(bodies.data());
    const LaneIndex a = body_offsets(block.body_a), b = body_offsets(block.body_b);
#if defined(__AVX512F__)
    // a float at a time: with AVX-512's gathers, faster than the records (docs/solver.md)
    const V3 dpa = gather3(base + kDeltaPosition, a), dpb = gather3(base + kDeltaPosition, b);
    const V3 qa = gather3(base + kDeltaRotation, a), qb = gather3(base + kDeltaRotation, b);
    const Lane wa = simd::gather<Lane>(base + kDeltaRotation + 3, a);
    const Lane wb = simd::gather<Lane>(base + kDeltaRotation + 3, b);
#else
    // each body's floats 8–15 (Δx, padding, Δq as x, y, z, w) as records transposed (AVX2 has
    // no fast gather: the fourteen gathers were a tenth of the kernel on a Zen 3)
    static_assert(kDeltaPosition == 8 && kDeltaRotation == 12);
    Lane high[8];
    simd::gather_records(base + 8, a, high);
    const V3 dpa = {high[0], high[1], high[2]}, qa = {high[4], high[5], high[6]};
    const Lane wa = high[7];
    simd::gather_records(base + 8, b, high);
    const V3 dpb = {high[0], high[1], high[2]}, qb = {high[4], high[5], high[6]};
    const Lane wb = high[7];
#endif
    // the frame rebuilt here, not passed in from the pass: passed, the pass's tangents went
    // through the stack, 22 M more instructions and 76 M more reads and writes over pyramid-100's
    // first 12 steps (cachegrind, the x86-64-v3 copy)
    const V3 n = load3(block.normal);
    const Tangents tangents = tangents_of(block, n);
    const V3 &t0 = tangents.t0, &t1 = tangents.t1;
    const V3 turned_a = rotate_back(qa, wa, n), turned_b = rotate_back(qb, wb, n);
    const V3 b_frame{dot(turned_b, t0), dot(turned_b, t1), dot(turned_b, n)};
    const V3 turned = turned_b - turned_a;
    shift = dot(n, dpb - dpa) + dot(b_frame, V3{offset.d[0], offset.d[1], offset.d[2]});
    turn[0] = dot(turned, t0), turn[1] = dot(turned, t1), turn[2] = dot(turned, n);
  }
  Lane separation(const ContactBlock::Point& p, Lane base_separation) const {
    return base_separation + shift +
           (turn[0] * p.anchor[0] + turn[1] * p.anchor[1] + turn[2] * p.anchor[2]);
  }
};

// a soft constraint of the given stiffness (Hz) and damping ratio, for a solve of step h, as
// three numbers: the bias per metre of penetration (1/s), the share of the effective mass used,
// and the share of the accumulated impulse taken back each solve: an implicit spring–damper in
// impulse form (Catto, "Soft Constraints", GDC 2011, and Solver2D, 2024; ODE's ERP/CFM are the
// same pair of numbers)
struct Softness {
  double bias_rate, mass_scale, impulse_scale;
};

Softness make_soft(double hertz, double damping_ratio, double h) {
  if (hertz == 0.0) return {0.0, 1.0, 0.0};
  const double omega = 2.0 * std::numbers::pi * hertz;
  const double a1 = 2.0 * damping_ratio + h * omega;
  const double a2 = h * omega * a1;
  const double a3 = 1.0 / (1.0 + a2);
  return {omega / a1, a2 * a3, a3};
}

}  // namespace

namespace {
ContactStages* make_pipeline(const ContactSettings& settings) {
  return new ContactPipeline(settings);
}
}  // namespace

// this copy of the pipeline, for contact_isa() (contact_dispatch.cpp): in a build that carries
// several, the one name CMake leaves global in each copy's object
#ifndef RTP_CONTACT_ISA_ENTRY
#define RTP_CONTACT_ISA_ENTRY rtp_contact_isa_native
#endif
extern "C" const ContactIsa* RTP_CONTACT_ISA_ENTRY() {
  static const ContactIsa isa{RTP_CONTACT_ISA_NAME, simd::kInstructionSet, W, &make_pipeline,
                              kContactInterfaceLayout};
  return &isa;
}

namespace {
// The next block's cache lines, asked for a few at a time while this one is solved: a pass
// streams the blocks in order, and at a large pyramid they come from L3, whose latency the kernel
// otherwise waits on (docs/solver.md, "Cost"). Asked for all at once, the 45 lines a block fill
// the core's line-fill buffers and the prefetches stall the kernel behind them.
class Prefetch {
 public:
  explicit Prefetch(const ContactBlock* next) : next_(reinterpret_cast<const char*>(next)) {}
  // the next `lines` lines of the block; nothing past its end, or without a next block
  void ahead(std::size_t lines) {
    if (!next_) return;
    const std::size_t end = std::min(line_ + lines, kLines);
    simd::prefetch(next_ + line_ * 64, (end - line_) * 64);
    line_ = end;
  }
  void rest() { ahead(kLines); }
  // for a pass that reads only some of a block: the next block's lines that hold what `bytes`
  // from `field`, a member of `current`, hold in it; then done(), so that rest() asks for no more
  void same(const ContactBlock& current, const void* field, std::size_t bytes) {
    if (!next_) return;
    simd::prefetch(next_ + (static_cast<const char*>(field) -
                            reinterpret_cast<const char*>(&current)),
                   bytes);
  }
  void done() { next_ = nullptr; }

 private:
  static constexpr std::size_t kLines = sizeof(ContactBlock) / 64;
  const char* next_;
  std::size_t line_ = 0;
};
}  // namespace


template <class Kernel>
void ContactPipeline::for_each_block(Kernel&& kernel, bool backwards) {
  std::vector<ContactBlock>& blocks = lanes_->blocks;
  const std::vector<std::uint32_t>& start = lanes_->colour_start;
  constexpr std::size_t parallel_blocks = kParallelColour / W;
  // the k-th colour visited, of those that hold a block: in reverse on a backward pass (a
  // colour's own blocks are independent, so they go forwards either way, each prefetching the
  // next)
  const std::vector<std::uint8_t>& used = lanes_->used_colours;
  const int colours = int(used.size());
  auto colour = [&](int k) { return int(used[std::size_t(backwards ? colours - 1 - k : k)]); };
  auto wide = [&](int k) {
    const int c = colour(k);
    return c + 1 < kColours && start[c + 1] - start[c] >= parallel_blocks;
  };
  std::vector<ContactBlockRest>& rest = lanes_->rest;
  auto run_block = [&](std::size_t i, std::size_t end) {
    Prefetch ahead(i + 1 < end ? &blocks[i + 1] : nullptr);
    kernel(blocks[i], rest[i], ahead);
    ahead.rest();
  };
  auto run_colour = [&](int k) {
    const int c = colour(k);
    for (std::size_t i = start[c]; i < start[c + 1]; ++i) run_block(i, start[c + 1]);
  };
  // threads only when some colour is wide enough to share: each colour ends in a barrier, and
  // a barrier among threads that have nothing to share costs more than the colour
  bool any_wide = false;
  for (int k = 0; k < colours && !any_wide; ++k) any_wide = wide(k);
  if (threads_ <= 1 || !any_wide) {
    for (int k = 0; k < colours; ++k) run_colour(k);
    return;
  }
  // the visit: each wide colour, and each run of narrow ones (with the overflow), on one
  // thread; a barrier between two of them, none after the last (the region's end is one)
  struct Visit {
    int first, last;  // the k-th colours visited, [first, last)
    bool wide;
  };
  std::array<Visit, kColours> visits;
  int visit_count = 0;
  for (int k = 0; k < colours;) {
    if (wide(k)) {
      visits[std::size_t(visit_count++)] = {k, k + 1, true};
      ++k;
      continue;
    }
    int end = k;
    while (end < colours && !wide(end)) ++end;
    visits[std::size_t(visit_count++)] = {k, end, false};
    k = end;
  }
  SpinBarrier barrier;
#pragma omp parallel num_threads(threads_)
  {
    const int size = team_size(), index = team_index();
    for (int v = 0; v < visit_count; ++v) {
      const Visit& visit = visits[std::size_t(v)];
      if (v > 0) barrier.wait(size);
      if (visit.wide) {
        // each thread its share of the colour's blocks, the share the colouring packed for it
        const int c = colour(visit.first);
        const auto [begin, end] = share_of(start[c + 1] - start[c], size, index);
        for (std::size_t i = start[c] + begin; i < start[c] + end; ++i)
          run_block(i, start[c] + end);
      } else if (index == 0) {
        for (int j = visit.first; j < visit.last; ++j) run_colour(j);
      }
    }
  }
}

// the soft step's contact stiffness for a solve of step h, as lanes: between two dynamic bodies,
// and against a static one
struct SoftLanes {
  Lane bias_rate[2], mass_scale[2], impulse_scale[2];
};
SoftLanes soft_lanes(const ContactSettings& settings, double h) {
  // stiffer than a quarter of the solve's rate a soft contact is no longer stable (Box2D's cap);
  // a contact with a static body is twice as stiff, since only one body moves, within the same
  // cap (past it, a 10:1 stack on the ground jitters and walks 2 cm in 10 s)
  const double cap = 0.25 / h;
  SoftLanes lanes;
  for (int against_static = 0; against_static < 2; ++against_static) {
    const Softness soft = make_soft(std::min((1 + against_static) * settings.contact_hertz, cap),
                                    settings.damping_ratio, h);
    lanes.bias_rate[against_static] = splat(float(soft.bias_rate));
    lanes.mass_scale[against_static] = splat(float(soft.mass_scale));
    lanes.impulse_scale[against_static] = splat(float(soft.impulse_scale));
  }
  return lanes;
}

void ContactPipeline::warm_start(bool first_substep) {
  const std::ptrdiff_t n = std::ptrdiff_t(bodies_.size());
  substep_start_.resize(bodies_.size());
  substep_change_.resize(bodies_.size());
  if (!first_substep) {
    parallel_for(threads_, n, n >= 2048, [&](std::ptrdiff_t i) {
      SolverBody& body = bodies_[i];
      substep_start_[i].linear = body.linear_velocity;
      substep_start_[i].angular = body.angular_velocity;
      body.linear_velocity += substep_change_[i].linear;
      body.angular_velocity += substep_change_[i].angular;
    });
    return;
  }
  parallel_for(threads_, n, n >= 2048, [&](std::ptrdiff_t i) {
    substep_start_[i] = {bodies_[i].linear_velocity, bodies_[i].angular_velocity,
                         masses_[i].inverse_mass > 0.0 ? 1.0f : 0.0f};
  });
  for_each_block([&](const ContactBlock& c, const ContactBlockRest& r, Prefetch& ahead) {
    // the warm start reads 31 of a block's 45 lanes (the bodies, the directions, the friction's
    // centre and impulses, each point's anchor and normal impulse): only those of
    // the next block are asked for, since at a large pyramid this pass waits on memory more
    // than it computes
    ahead.same(c, &c, offsetof(ContactBlock, friction));
    for (const ContactBlock::Point& p : c.points) ahead.same(c, &p.anchor, 4 * sizeof(Lane));
    ahead.done();
    // a block without an impulse to apply (its contacts all carried none: the colouring packs
    // such contacts together) leaves the velocities as they are
    const Lane zero = splat(0.0f);
    LaneMask any = (c.friction_impulse[0] != zero) | (c.friction_impulse[1] != zero) |
                   (c.twist_impulse != zero);
    for (const ContactBlock::Point& p : c.points) any |= p.normal_impulse != zero;
    if (!simd::any_of(any)) return;
    LanePair pair(bodies_, c);
    const V3 n = load3(c.normal);
    const Tangents tangents = tangents_of(c, n);
    const V3 &t0 = tangents.t0, &t1 = tangents.t1;
    // (the whole matrix even on an isotropic block: the same numbers, and the same round-off)
    const BlockInertia m = inertia_of<false>(pair, r);
    const V3 to_b = in_world(FrameOffset(c).d, n, t0, t1);
    for (const ContactBlock::Point& p : c.points) {
      const V3 ra = in_world(p.anchor, n, t0, t1);
      pair.apply(m, ra, ra + to_b, p.normal_impulse * n);
    }
    pair.apply(m, in_world(c.centre_a, n, t0, t1), in_world(c.centre_b, n, t0, t1),
               c.friction_impulse[0] * t0 + c.friction_impulse[1] * t1);
    pair.apply_twist(m, n, c.twist_impulse);
    pair.store(bodies_);
  });
}

void ContactPipeline::end_substep() {
  const std::ptrdiff_t n = std::ptrdiff_t(bodies_.size());
  parallel_for(threads_, n, n >= 2048, [&](std::ptrdiff_t i) {
    substep_change_[i].linear = bodies_[i].linear_velocity - substep_start_[i].linear;
    substep_change_[i].angular = bodies_[i].angular_velocity - substep_start_[i].angular;
  });
}

void ContactPipeline::next_substep(const Eigen::Vector3f& kick) {
  const std::ptrdiff_t n = std::ptrdiff_t(bodies_.size());
  parallel_for(threads_, n, n >= 2048, [&](std::ptrdiff_t i) {
    SolverBody& body = bodies_[i];
    Velocities& start = substep_start_[i];
    const Eigen::Vector3f linear_change = body.linear_velocity - start.linear;
    const Eigen::Vector3f angular_change = body.angular_velocity - start.angular;
    if (start.dynamic != 0.0f) body.linear_velocity += kick;
    start.linear = body.linear_velocity;
    start.angular = body.angular_velocity;
    body.linear_velocity += linear_change;
    body.angular_velocity += angular_change;
  });
}

bool ContactPipeline::solve(double h, bool bias, bool backwards, double tolerance) {
  const float inverse_h = float(1.0 / h);
  const bool soft = settings_.solver == ContactSolver::SoftStep;
  // sequential impulse: the Baumgarte bias removes this fraction of the penetration past the
  // slop in one step (Catto GDC 2006)
  const Lane baumgarte_rate = splat(float(settings_.baumgarte / h));
  const Lane slop = splat(float(settings_.linear_slop));
  const Lane max_push = splat(float(settings_.max_push_speed));
  const Lane zero = splat(0.0f), one = splat(1.0f);
  // a point's normal velocity changes by applied / normal_mass: past the tolerance where
  // |applied| > tolerance · normal_mass (an empty point's mass is 0, and it applies nothing)
  const Lane tolerance_lane = splat(float(tolerance));
  // the soft step's stiffness, chosen in each lane by whether a body is static (soft_lanes)
  const SoftLanes stiffness = soft_lanes(settings_, h);
  std::atomic<bool> moved{false};
  // each point's separation from the bodies' motion, once after they moved (a substep's biased
  // solve and its relax passes read the same positions), stored in the block for the passes
  // after: the motion's 14 gathers a block and two rotations are then once a substep, not once
  // a pass
  const bool refresh = separations_stale_;
  separations_stale_ = false;
  // the pass's rows, known before its blocks, each kind its own kernel: a relax pass computes no
  // soft scales, a soft one picks its stiffness once a block, and only a relax pass with a
  // tolerance tracks the velocities' change
  enum class Rows { kSoft, kBaumgarte, kRelax, kRelaxTracked };
  auto solve_block = [&]<bool kIsotropic, Rows kRows>(ContactBlock& c, ContactBlockRest& r,
                                                       Prefetch& ahead, std::uint8_t flags) {
    LanePair pair(bodies_, c);
    const BlockInertia m = inertia_of<kIsotropic>(pair, r);
    // the soft step's stiffness of each lane, by whether a body is static (soft_lanes)
    [[maybe_unused]] Lane soft_bias_rate, soft_mass_scale, soft_impulse_scale;
    if constexpr (kRows == Rows::kSoft) {
      const LaneMask against_static =
          (pair.inverse_mass_a == zero) | (pair.inverse_mass_b == zero);
      soft_bias_rate =
          simd::select(against_static, stiffness.bias_rate[1], stiffness.bias_rate[0]);
      soft_mass_scale =
          simd::select(against_static, stiffness.mass_scale[1], stiffness.mass_scale[0]);
      soft_impulse_scale =
          simd::select(against_static, stiffness.impulse_scale[1], stiffness.impulse_scale[0]);
    }
    LaneMask changed = zero != zero;
    bool wrote = false;  // whether any lane's velocities changed
    const V3 n = load3(c.normal);
    const Tangents tangents = tangents_of(c, n);
    const V3 &t0 = tangents.t0, &t1 = tangents.t1;
    const FrameOffset offset(c);
    ahead.ahead(16);
    if (refresh) {
      const NormalMotion motion(bodies_, c, offset);
      for (int j = 0; j < 4; ++j)
        c.points[j].separation = motion.separation(c.points[j], r.points[j].base_separation);
    }

    // the largest impulse of each point this step, which only restitution reads: kept where
    // some lane bounces
    const bool any_bounce = (flags & kBouncingBlock) != 0;
    // non-penetration: the normal impulse accumulates and stays ≥ 0 (Catto GDC 2006). A
    // manifold with no warm start (a new contact, an impact) runs its points several times in a
    // row: one pass over a face's four points lands the whole impulse on the first and spins the
    // body, where the converged answer pushes all four alike
    const int rounds = (flags & kFreshBlock) != 0 ? settings_.local_iterations : 1;
    // an isotropic block's rows in the manifold's frame (BlockFrame), written back after them
    [[maybe_unused]] auto frame = [&] {
      if constexpr (kIsotropic)
        return BlockFrame(pair, n, t0, t1);
      else
        return 0;
    }();
    LaneMask pushed = zero != zero;
    // the lanes where a point pushes out at max_push_speed: deep in an overlap (boxes spawned
    // into each other), whose normal impulse is mostly push-out (below)
    [[maybe_unused]] LaneMask pushing_out = zero != zero;
    // a round over the four points: the first on every lane, each later one on the fresh lanes
    // alone (`active`); the first is a kernel of its own, without the select on its chain
    auto point_rows = [&]<bool kEveryLane>([[maybe_unused]] LaneMask active) {
      for (int j = 0; j < 4; ++j) {
        ContactBlock::Point& p = c.points[j];
        ahead.ahead(16);
        const Lane s = p.separation;
        const auto row = [&] {
          if constexpr (kIsotropic)
            return FrameRow(p, offset);
          else
            return NormalRow(p, t0, t1, offset);
        }();
        const Lane vn = [&] {
          if constexpr (kIsotropic)
            return frame.normal_velocity(row);
          else
            return pair.normal_velocity(n, row);
        }();
        const LaneMask apart = s > zero;
        // speculative: the bodies may close the gap in this step, no more
        const Lane closing = s * inverse_h;
        Lane impulse;
        if constexpr (kRows == Rows::kSoft) {
          // touching, a soft push out: a share of the effective mass, and of the accumulated
          // impulse taken back; apart, only the gap's closing is allowed (speculative)
          const Lane push = soft_bias_rate * s;
          const Lane velocity_bias = simd::select(apart, closing, simd::max(push, zero - max_push));
          pushing_out |= push < zero - max_push;
          impulse = zero - p.normal_mass * simd::select(apart, one, soft_mass_scale) *
                               (vn + velocity_bias) -
                    simd::select(apart, zero, soft_impulse_scale) * p.normal_impulse;
        } else if constexpr (kRows == Rows::kBaumgarte) {
          const Lane velocity_bias = simd::select(
              apart, closing, zero - baumgarte_rate * simd::max(zero - s - slop, zero));
          impulse = zero - p.normal_mass * (vn + velocity_bias);
        } else {
          // no bias: only a gap's closing is allowed, no push out
          impulse = zero - p.normal_mass * (vn + simd::select(apart, closing, zero));
        }
        const Lane clamped = simd::max(p.normal_impulse + impulse, zero);
        Lane accumulated = clamped;
        if constexpr (!kEveryLane) accumulated = simd::select(active, clamped, p.normal_impulse);
        const Lane applied = accumulated - p.normal_impulse;
        p.normal_impulse = accumulated;
        if (any_bounce)
          r.points[j].max_normal_impulse = simd::max(r.points[j].max_normal_impulse, applied);
        if constexpr (kRows == Rows::kRelaxTracked)
          changed |= simd::max(applied, zero - applied) > tolerance_lane * p.normal_mass;
        if constexpr (kIsotropic) {
          // a few multiply-adds: applied whatever the lanes hold
          frame.apply(m, row, applied);
          pushed |= applied != zero;
        } else {
          // a point that applies nothing in any lane leaves the velocities as they are: its
          // response is not computed
          const LaneMask pushes = applied != zero;
          if (simd::any_of(pushes)) {
            pair.apply_normal(m, row, n, applied);
            wrote = true;
          }
        }
      }
    };
    point_rows.template operator()<true>(LaneMask{});
    for (int round = 1; round < rounds; ++round) point_rows.template operator()<false>(r.fresh);
    if constexpr (kIsotropic) wrote = simd::any_of(pushed);
    // Coulomb friction at the manifold's centre: the friction impulse accumulates on the two
    // tangents and its length stays within μ times the manifold's normal impulse (the friction
    // cone as a circle); about the normal, the twist stays within that times the points' mean
    // distance from the centre
    ahead.ahead(17);
    {
      const Lane total = c.points[0].normal_impulse + c.points[1].normal_impulse +
                         c.points[2].normal_impulse + c.points[3].normal_impulse;
      const Lane old0 = c.friction_impulse[0], old1 = c.friction_impulse[1];
      const Lane old_twist = c.twist_impulse;
      // no normal impulse and no friction impulse in any lane: the cone is a point, and the
      // friction impulse stays zero
      if (simd::any_of((total != zero) | (old0 != zero) | (old1 != zero) |
                       (old_twist != zero))) {
        // a lane pushing out at the cap takes no friction in the biased solve: bounded by the
        // push-out's impulse, friction held a heap's bottom box at the ground while its
        // neighbours pushed its sides, and turned it deeper into the box above (overlap-heap's
        // deepest overlap 0.70 → 0.62 m; docs/solver.md, "Not while recovering"); the relax
        // passes that follow, with no push-out, give it its friction back
        Lane limit = c.friction * total;
        if constexpr (kRows == Rows::kSoft) limit = simd::select(pushing_out, zero, limit);
        Lane f0, f1;
        if constexpr (kIsotropic) {
          const V3 linear = pair.vb - pair.va;
          f0 = old0 - c.tangent_mass[0] *
                          frame.tangent_velocity0(dot(t0, linear), c.centre_a, c.centre_b);
          f1 = old1 - c.tangent_mass[1] *
                          frame.tangent_velocity1(dot(t1, linear), c.centre_a, c.centre_b);
        } else {
          const V3 dv = pair.relative_velocity(in_world(c.centre_a, n, t0, t1),
                                               in_world(c.centre_b, n, t0, t1));
          f0 = old0 - c.tangent_mass[0] * dot(t0, dv);
          f1 = old1 - c.tangent_mass[1] * dot(t1, dv);
        }
        const Lane length_squared = f0 * f0 + f1 * f1;
        // (where the limit is zero the cone is a point: an impulse whose square underflows to
        // zero is outside it too)
        const LaneMask outside = (length_squared > limit * limit) | (limit == zero);
        if (simd::any_of(outside)) {
          const Lane scale =
              simd::select(outside, limit / simd::sqrt(simd::max(length_squared, splat(1e-30f))),
                           one);
          f0 = f0 * scale;
          f1 = f1 * scale;
        }
        c.friction_impulse[0] = f0;
        c.friction_impulse[1] = f1;
        const Lane twist_limit = limit * c.twist_arm;
        if constexpr (kIsotropic) {
          frame.apply_friction(m, c.centre_a, c.centre_b, f0 - old0, f1 - old1);
          const Lane twist = simd::max(
              simd::min(old_twist - c.twist_mass * (frame.sb - frame.sa), twist_limit),
              zero - twist_limit);
          c.twist_impulse = twist;
          frame.apply_twist(m, twist - old_twist);
        } else {
          pair.apply(m, in_world(c.centre_a, n, t0, t1),
                     in_world(c.centre_b, n, t0, t1), (f0 - old0) * t0 + (f1 - old1) * t1);
          const Lane twist = simd::max(
              simd::min(old_twist - c.twist_mass * dot(n, pair.wb - pair.wa), twist_limit),
              zero - twist_limit);
          c.twist_impulse = twist;
          pair.apply_twist(m, n, twist - old_twist);
        }
        wrote = true;
      }
    }
    if constexpr (kIsotropic)
      if (wrote) frame.store(pair, n, t0, t1);
    if (wrote) pair.store(bodies_);
    // written once a pass at most: the biased passes (no tolerance) and a settling pass would
    // otherwise have both threads write the flag's cache line after every block
    if (tolerance > 0.0 && simd::any_of(changed) && !moved.load(std::memory_order_relaxed))
      moved.store(true, std::memory_order_relaxed);
  };
  const ContactBlock* const first_block = lanes_->blocks.data();
  const std::uint8_t* const flags = lanes_->flags.data();
  auto pass = [&]<Rows kRows>() {
    for_each_block(
        [&](ContactBlock& c, ContactBlockRest& r, Prefetch& ahead) {
          const std::uint8_t block_flags = flags[&c - first_block];
          if (block_flags & kIsotropicBlock)
            solve_block.template operator()<true, kRows>(c, r, ahead, block_flags);
          else
            solve_block.template operator()<false, kRows>(c, r, ahead, block_flags);
        },
        backwards);
  };
  if (bias && soft)
    pass.template operator()<Rows::kSoft>();
  else if (bias)
    pass.template operator()<Rows::kBaumgarte>();
  else if (tolerance > 0.0)
    pass.template operator()<Rows::kRelaxTracked>();
  else
    pass.template operator()<Rows::kRelax>();
  return !moved.load(std::memory_order_relaxed);
}

void ContactPipeline::restitution() {
  // Newton's law of restitution on every point that pushed this step, at once: the relative
  // normal velocity leaves at least −e times the approach speed (prepare()), or 0 where the
  // approach is slower than the threshold, with the step's accumulated impulse kept ≥ 0. Solved
  // to convergence, the answer conserves energy at e = 1 for any set of simultaneous contacts:
  // the kinetic energy changes by ½ Σ λᵢ (vᵢ⁺ + vᵢ⁻), and each term is zero (λᵢ = 0, or
  // vᵢ⁺ = −vᵢ⁻). A row of touching balls, one struck, then leaves as the row moving together
  // and the striker rebounding (the simultaneous answer), with momentum and energy kept.
  // Points that did not bounce take part, so that a bounce cannot push its body into a
  // neighbour; passes run until no point's velocity changes by the tolerance, at most
  // restitution_iterations of them (Box2D v3's pass, one over the bouncing points alone, left
  // the points behind them out)
  if (!bounces_) return;
  const Lane threshold = splat(float(-settings_.restitution_threshold));
  const Lane zero = splat(0.0f);
  const Lane tolerance = splat(float(settings_.restitution_tolerance));
  const Lane half_step = splat(float(0.5 * restitution_step_));
  const bool after_motion = settings_.solver == ContactSolver::SoftStep;
  const ContactBlock* const first_block = lanes_->blocks.data();
  for (int iteration = 0; iteration < settings_.restitution_iterations; ++iteration) {
    std::atomic<bool> moved{false};
    for_each_block([&](ContactBlock& c, const ContactBlockRest& r, Prefetch&) {
      if ((lanes_->flags[std::size_t(&c - first_block)] & kBouncingBlock) == 0) return;
      LanePair pair(bodies_, c);
      const V3 n = load3(c.normal);
      const Tangents tangents = tangents_of(c, n);
      const V3 &t0 = tangents.t0, &t1 = tangents.t1;
      const FrameOffset offset(c);
      const BlockInertia m = inertia_of<false>(pair, r);
      // the relative acceleration gravity gives along n (b's less a's: a static body has none)
      const Lane gravity_along = dot(n, V3{splat(float(gravity_.x())), splat(float(gravity_.y())),
                                           splat(float(gravity_.z()))});
      const Lane acceleration = simd::select(pair.inverse_mass_b > zero, gravity_along, zero) -
                                simd::select(pair.inverse_mass_a > zero, gravity_along, zero);
      LaneMask changed = zero != zero;
      bool wrote = false;
      // each manifold's points several times in a row, as for a fresh contact in solve()
      for (int round = 0; round < settings_.local_iterations; ++round)
        for (int j = 0; j < 4; ++j) {
          ContactBlock::Point& p = c.points[j];
          const ContactBlockRest::Point& q = r.points[j];
          const LaneMask pushed = (q.max_normal_impulse > zero) & (r.restitution > zero);
          if (!simd::any_of(pushed)) continue;
          // the speed it leaves the surface at, e times the approach u, then as free flight
          // carries it to its separation s, w² = e² u² + 2 a s, as a solve's velocity: half a
          // step behind the positions, w − a h/2, after the soft step's motion; sequential
          // impulse moves the bodies after this, by a step of the velocity it sets, and
          // w + a h/2 then leaves the energy at the positions at the end as it was at impact
          // (e = 1: a box bounces to its height however far from the surface the step began)
          const Lane separation = simd::max(p.separation, zero);
          const Lane leave = r.restitution * q.approach_velocity;
          const Lane leaving = simd::sqrt(
              simd::max(leave * leave + splat(2.0f) * acceleration * separation, zero));
          const Lane lag = half_step * acceleration;
          const Lane target = simd::select(q.approach_velocity < threshold,
                                           after_motion ? leaving - lag : leaving + lag, zero);
          const NormalRow row(p, t0, t1, offset);
          const Lane vn = pair.normal_velocity(n, row);
          const Lane impulse = zero - p.normal_mass * (vn - target);
          const Lane accumulated =
              simd::select(pushed, simd::max(p.normal_impulse + impulse, zero), p.normal_impulse);
          const Lane applied = accumulated - p.normal_impulse;
          changed |= simd::max(applied, zero - applied) > tolerance * p.normal_mass;
          if (!simd::any_of(applied != zero)) continue;
          pair.apply_normal(m, row, n, applied);
          p.normal_impulse = accumulated;
          wrote = true;
        }
      if (wrote) pair.store(bodies_);
      if (simd::any_of(changed) && !moved.load(std::memory_order_relaxed))
        moved.store(true, std::memory_order_relaxed);
    });
    if (!moved.load(std::memory_order_relaxed)) break;
  }
}

}  // namespace RTP_CONTACT_ISA_NAMESPACE
}  // namespace rtp
