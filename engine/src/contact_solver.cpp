// The contact pipeline's solver half: per-step constants, warm start, the velocity solves,
// restitution (docs/solver.md has the method, its sources and what was measured).
//
// Every solver here works on velocities at the contact points, v_rel = (v_b + ω_b × r_b) −
// (v_a + ω_a × r_a), and applies impulses P at the anchors: v_a −= P / m_a, ω_a −= I_a⁻¹ (r_a × P),
// and the opposite on b (Catto, "Fast and Simple Physics using Sequential Impulses", GDC 2006).
// The anchors are fixed for the step; the separation of a point is tracked through the substeps
// from the bodies' motion since the step's start (Catto, Solver2D, 2024: "relative position").
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <numbers>

#include "contacts.h"

namespace rtp {

namespace {

// the velocity state of the two bodies of a contact, loaded once per contact
struct PairState {
  SolverBody& a;
  SolverBody& b;
  double inverse_mass_a, inverse_mass_b;

  // the relative velocity of the point along a row's direction d:
  // d·(v_b − v_a) + ω_b·(r_b × d) − ω_a·(r_a × d)
  double velocity(const ContactRow& row, const Vec3& d) const {
    return d.dot(b.linear_velocity - a.linear_velocity) + b.angular_velocity.dot(row.angular_b) -
           a.angular_velocity.dot(row.angular_a);
  }
  // an impulse λ along d on b at its anchor, and its opposite on a
  // (a static body is never written: colours share static bodies, and their threads may not
  // write the same memory)
  void apply(const ContactRow& row, const Vec3& d, double impulse) {
    if (inverse_mass_a > 0.0) {
      a.linear_velocity -= (inverse_mass_a * impulse) * d;
      a.angular_velocity -= impulse * row.response_a;
    }
    if (inverse_mass_b > 0.0) {
      b.linear_velocity += (inverse_mass_b * impulse) * d;
      b.angular_velocity += impulse * row.response_b;
    }
  }
};

// how far a contact's bodies have moved along its normal since the step's start, as what the
// points need: s = s₀' + n·(Δx_b − Δx_a) + (ΔR_bᵀ n)·r_b − (ΔR_aᵀ n)·r_a, the two turned normals
// computed once per contact rather than two rotations per point
struct NormalMotion {
  double translation;  // n·(Δx_b − Δx_a) (m)
  Vec3 turned_a, turned_b;  // ΔR_aᵀ n, ΔR_bᵀ n

  NormalMotion(const PairState& pair, const Vec3& normal)
      : translation(normal.dot(pair.b.delta_position - pair.a.delta_position)),
        turned_a(pair.a.delta_rotation.transpose() * normal),
        turned_b(pair.b.delta_rotation.transpose() * normal) {}
  // the point's separation now: at the step's start plus the bodies' motion since (m)
  double separation(const ContactPointConstraint& p) const {
    return p.base_separation + translation + turned_b.dot(p.anchor_b) - turned_a.dot(p.anchor_a);
  }
};

PairState pair_of(std::vector<SolverBody>& bodies, const std::vector<SolverMass>& masses,
                  const ContactConstraint& c) {
  return {bodies[c.body_a], bodies[c.body_b], masses[c.body_a].inverse_mass,
          masses[c.body_b].inverse_mass};
}

// a row's angular parts and effective mass along d at the point's anchors
void make_row(ContactRow& row, const ContactPointConstraint& p, const Vec3& d,
              const SolverMass& mass_a, const SolverMass& mass_b) {
  row.angular_a = p.anchor_a.cross(d);
  row.angular_b = p.anchor_b.cross(d);
  row.response_a = mass_a.inverse_inertia * row.angular_a;
  row.response_b = mass_b.inverse_inertia * row.angular_b;
  const double k = mass_a.inverse_mass + mass_b.inverse_mass + row.angular_a.dot(row.response_a) +
                   row.angular_b.dot(row.response_b);
  row.mass = k > 0.0 ? 1.0 / k : 0.0;
}

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

// a colour's contacts go to threads only past this many: below it the barrier costs more
constexpr std::size_t kParallelColour = 256;
// colours beyond the 63rd are one last group, solved on one thread
constexpr int kColours = 64;

void ContactPipeline::colour_contacts() {
  // greedy, in pair order: each contact takes the first colour neither dynamic body holds
  body_colours_.assign(bodies_.size(), 0);
  std::array<std::uint32_t, kColours + 1> counts{};
  std::vector<std::uint8_t>& colour_of = colour_scratch_;
  colour_of.resize(contacts_.size());
  for (std::size_t i = 0; i < contacts_.size(); ++i) {
    const ContactConstraint& c = contacts_[i];
    const bool dynamic_a = masses_[c.body_a].inverse_mass > 0.0;
    const bool dynamic_b = masses_[c.body_b].inverse_mass > 0.0;
    const std::uint64_t taken = (dynamic_a ? body_colours_[c.body_a] : 0) |
                                (dynamic_b ? body_colours_[c.body_b] : 0);
    // the last colour is the overflow group and takes anything
    const int colour = std::min(std::countr_one(taken), kColours - 1);
    if (colour < kColours - 1) {
      if (dynamic_a) body_colours_[c.body_a] |= std::uint64_t{1} << colour;
      if (dynamic_b) body_colours_[c.body_b] |= std::uint64_t{1} << colour;
    }
    colour_of[i] = std::uint8_t(colour);
    ++counts[colour + 1];
  }
  colour_start_.assign(counts.begin(), counts.end());
  for (int k = 0; k < kColours; ++k) colour_start_[k + 1] += colour_start_[k];
  colour_order_.resize(contacts_.size());
  std::array<std::uint32_t, kColours> next{};
  for (int k = 0; k < kColours; ++k) next[k] = colour_start_[k];
  for (std::size_t i = 0; i < contacts_.size(); ++i)
    colour_order_[next[colour_of[i]]++] = std::uint32_t(i);
}

template <class Solve>
void ContactPipeline::for_each_contact(Solve&& solve) {
  const int threads = settings_.threads;
  const std::size_t overflow = colour_start_[kColours - 1];
  if (threads <= 1 || contacts_.size() < kParallelColour) {
    for (std::uint32_t index : colour_order_) solve(contacts_[index]);
    return;
  }
#pragma omp parallel num_threads(threads)
  {
    for (int k = 0; k + 1 < kColours; ++k) {
      const std::size_t begin = colour_start_[k], end = colour_start_[k + 1];
      if (end - begin < kParallelColour) {
#pragma omp single
        for (std::size_t i = begin; i < end; ++i) solve(contacts_[colour_order_[i]]);
      } else {
#pragma omp for schedule(static)
        for (std::size_t i = begin; i < end; ++i) solve(contacts_[colour_order_[i]]);
      }
    }
#pragma omp single
    for (std::size_t i = overflow; i < colour_order_.size(); ++i)
      solve(contacts_[colour_order_[i]]);
  }
}

void ContactPipeline::load_bodies(std::span<const BodyState> states,
                                  std::span<const BodyMass> masses) {
  for (std::size_t i = 0; i < states.size(); ++i) {
    SolverBody& body = bodies_[i];
    SolverMass& mass = masses_[i];
    mass.inverse_mass = masses[i].inverse_mass;
    body.delta_position.setZero();
    body.delta_rotation.setIdentity();
    if (mass.inverse_mass == 0.0) {
      mass.inverse_inertia.setZero();
      body.linear_velocity.setZero();
      body.angular_velocity.setZero();
      continue;
    }
    mass.inverse_inertia =
        world_inverse_inertia(states[i].orientation, masses[i].inverse_inertia_body);
    body.linear_velocity = states[i].linear_momentum * mass.inverse_mass;
    body.angular_velocity = mass.inverse_inertia * states[i].angular_momentum;
  }
}

void ContactPipeline::prepare(double dt, const Vec3& gravity) {
  const double h = settings_.solver == ContactSolver::SoftStep
                       ? dt / std::max(1, settings_.substeps)
                       : dt;
  // stiffer than a quarter of the solve's rate a soft contact is no longer stable (Box2D's cap);
  // a contact with a static body is twice as stiff, since only one body moves, within the same
  // cap (past it, a 10:1 stack on the ground jitters and walks 2 cm in 10 s)
  const double cap = 0.25 / h;
  const Softness dynamic_soft =
      make_soft(std::min(settings_.contact_hertz, cap), settings_.damping_ratio, h);
  const Softness static_soft =
      make_soft(std::min(2.0 * settings_.contact_hertz, cap), settings_.damping_ratio, h);
  colour_contacts();
  for_each_contact([&](ContactConstraint& c) {
    const SolverMass& mass_a = masses_[c.body_a];
    const SolverMass& mass_b = masses_[c.body_b];
    const PairState pair = pair_of(bodies_, masses_, c);
    const bool against_static = mass_a.inverse_mass == 0.0 || mass_b.inverse_mass == 0.0;
    const Softness& soft = against_static ? static_soft : dynamic_soft;
    c.bias_rate = soft.bias_rate;
    c.mass_scale = soft.mass_scale;
    c.impulse_scale = soft.impulse_scale;
    c.converged = false;
    c.fresh = false;
    for (std::uint8_t i = 0; i < c.count; ++i) {
      ContactPointConstraint& p = c.points[i];
      make_row(p.normal, p, c.normal, mass_a, mass_b);
      make_row(p.tangent[0], p, c.tangent[0], mass_a, mass_b);
      make_row(p.tangent[1], p, c.tangent[1], mass_a, mass_b);
      const double separation = p.base_separation;
      // the separation is tracked from here: s = base + n·(motion of b's anchor − a's)
      p.base_separation -= c.normal.dot(p.anchor_b - p.anchor_a);
      p.max_normal_impulse = 0.0;
      p.approach_velocity = pair.velocity(p.normal, c.normal);
      // a point still apart hits, if it hits this step, at the speed free flight gives it over
      // the gap: v² = v₀² − 2 a s₀ with a the relative acceleration gravity gives along n (the
      // speed the solve sees is one a speculative push has already slowed)
      p.starts_apart = separation > 0.0;
      if (p.starts_apart) {
        const Vec3 gravity_a = mass_a.inverse_mass > 0.0 ? gravity : Vec3::Zero();
        const Vec3 gravity_b = mass_b.inverse_mass > 0.0 ? gravity : Vec3::Zero();
        const double acceleration = c.normal.dot(gravity_b - gravity_a);
        const double squared =
            p.approach_velocity * p.approach_velocity - 2.0 * acceleration * separation;
        p.approach_velocity = -std::sqrt(std::max(squared, 0.0));
      }
      // no warm start, or an approach fast enough to bounce: the manifold is solved locally
      if (p.normal.impulse == 0.0 || p.approach_velocity < -settings_.restitution_threshold)
        c.fresh = true;
    }
  });
}

void ContactPipeline::warm_start() {
  for_each_contact([&](const ContactConstraint& c) {
    PairState pair = pair_of(bodies_, masses_, c);
    for (std::uint8_t i = 0; i < c.count; ++i) {
      const ContactPointConstraint& p = c.points[i];
      pair.apply(p.normal, c.normal, p.normal.impulse);
      pair.apply(p.tangent[0], c.tangent[0], p.tangent[0].impulse);
      pair.apply(p.tangent[1], c.tangent[1], p.tangent[1].impulse);
    }
  });
}

void ContactPipeline::solve(double h, bool bias) {
  const double inverse_h = 1.0 / h;
  const bool soft = settings_.solver == ContactSolver::SoftStep;
  // sequential impulse: the Baumgarte bias removes this fraction of the penetration past the
  // slop in one step (Catto GDC 2006)
  const double baumgarte_rate = settings_.baumgarte * inverse_h;
  for_each_contact([&](ContactConstraint& c) {
    PairState pair = pair_of(bodies_, masses_, c);
    // non-penetration: the normal impulse accumulates and stays ≥ 0 (Catto GDC 2006). A
    // manifold with no warm start (a new contact, an impact) runs its points several times in a
    // row: one pass over a face's four points lands the whole impulse on the first and spins the
    // body, where the converged answer pushes all four alike
    // the approach speed restitution reverses, for points that started the step touching: each
    // one's last before it first pushed, all read before this manifold pushes at all (read one
    // by one, the points after the first would see the first's push, and bounce unequally)
    for (std::uint8_t i = 0; i < c.count; ++i)
      if (c.points[i].max_normal_impulse == 0.0 && !c.points[i].starts_apart)
        c.points[i].approach_velocity = pair.velocity(c.points[i].normal, c.normal);
    const NormalMotion motion(pair, c.normal);
    const int rounds = c.fresh ? settings_.local_iterations : 1;
    for (int k = 0; k < rounds * c.count; ++k) {
      ContactPointConstraint& p = c.points[k % c.count];
      const double s = motion.separation(p);
      const double vn = pair.velocity(p.normal, c.normal);
      double velocity_bias = 0.0, mass_scale = 1.0, impulse_scale = 0.0;
      if (s > 0.0) {
        // speculative: the bodies may close the gap in this step, no more
        velocity_bias = s * inverse_h;
      } else if (bias && soft) {
        velocity_bias = std::max(c.bias_rate * s, -settings_.max_push_speed);
        mass_scale = c.mass_scale;
        impulse_scale = c.impulse_scale;
      } else if (bias) {
        velocity_bias = -baumgarte_rate * std::max(-s - settings_.linear_slop, 0.0);
      }
      const double impulse =
          -p.normal.mass * mass_scale * (vn + velocity_bias) - impulse_scale * p.normal.impulse;
      const double accumulated = std::max(p.normal.impulse + impulse, 0.0);
      const double applied = accumulated - p.normal.impulse;
      p.normal.impulse = accumulated;
      p.max_normal_impulse = std::max(p.max_normal_impulse, applied);
      pair.apply(p.normal, c.normal, applied);
    }
    // Coulomb friction: the friction impulse accumulates on the two tangents and its length
    // stays within μ times the normal impulse (the friction cone as a circle)
    for (std::uint8_t i = 0; i < c.count; ++i) {
      ContactPointConstraint& p = c.points[i];
      const double limit = c.friction * p.normal.impulse;
      const double old0 = p.tangent[0].impulse, old1 = p.tangent[1].impulse;
      double t0 = old0 - p.tangent[0].mass * pair.velocity(p.tangent[0], c.tangent[0]);
      double t1 = old1 - p.tangent[1].mass * pair.velocity(p.tangent[1], c.tangent[1]);
      const double length_squared = t0 * t0 + t1 * t1;
      if (length_squared > limit * limit) {
        const double scale = limit / std::sqrt(length_squared);
        t0 *= scale;
        t1 *= scale;
      }
      p.tangent[0].impulse = t0;
      p.tangent[1].impulse = t1;
      pair.apply(p.tangent[0], c.tangent[0], t0 - old0);
      pair.apply(p.tangent[1], c.tangent[1], t1 - old1);
    }
  });
}

void ContactPipeline::restitution() {
  const double threshold = settings_.restitution_threshold;
  for (int iteration = 0; iteration < settings_.restitution_iterations; ++iteration)
    for_each_contact([&](ContactConstraint& c) {
      if (c.restitution == 0.0) return;
      PairState pair = pair_of(bodies_, masses_, c);
      // each manifold's points several times in a row, as for a fresh contact in solve()
      for (int k = 0; k < settings_.local_iterations * c.count; ++k) {
        ContactPointConstraint& p = c.points[k % c.count];
        // only points that pushed this step, and hit faster than the threshold: a resting
        // contact does not bounce
        if (p.approach_velocity > -threshold || p.max_normal_impulse == 0.0) continue;
        const double vn = pair.velocity(p.normal, c.normal);
        const double impulse = -p.normal.mass * (vn + c.restitution * p.approach_velocity);
        const double accumulated = std::max(p.normal.impulse + impulse, 0.0);
        pair.apply(p.normal, c.normal, accumulated - p.normal.impulse);
        p.normal.impulse = accumulated;
      }
    });
}

void ContactPipeline::solve_seed(double dt) {
  // The seed's lab 5 as it is written: each iteration applies at every penetrating point the
  // impulse magnitude j = (−(1 + e) v_n + β/dt · max(depth − slop, 0)) / (n·K n) when it is
  // positive (Hecker, "Physics, Part 3: Collision Response", 1997; the penetration "penalty"
  // impulse), and a friction impulse against the sliding velocity up to μ j. Nothing
  // accumulates and nothing is carried to the next step: this is the weakness the seed admits.
  const double penalty_rate = settings_.baumgarte / dt;
  // a pair has converged when no impulse of an iteration changes a velocity by 10 µm/s
  const double converged_velocity = 1e-5;
  for (int iteration = 0; iteration < settings_.velocity_iterations; ++iteration) {
    bool any = false;
    for (std::uint32_t index : colour_order_) {
      ContactConstraint& c = contacts_[index];
      if (c.converged) continue;
      PairState pair = pair_of(bodies_, masses_, c);
      const SolverMass& mass_a = masses_[c.body_a];
      const SolverMass& mass_b = masses_[c.body_b];
      double largest_change = 0.0;
      for (std::uint8_t i = 0; i < c.count; ++i) {
        const ContactPointConstraint& p = c.points[i];
        const double depth = -(p.base_separation + c.normal.dot(p.anchor_b - p.anchor_a));
        // the seed's narrow phase reports touching shapes only: no speculative points
        if (depth < 0.0) continue;
        const double vn = pair.velocity(p.normal, c.normal);
        const double j =
            p.normal.mass * (-(1.0 + c.restitution) * vn +
                             penalty_rate * std::max(depth - settings_.linear_slop, 0.0));
        if (j <= 0.0) continue;
        pair.apply(p.normal, c.normal, j);
        largest_change = std::max(largest_change, j / std::max(p.normal.mass, 1e-300));
        // friction against the sliding velocity, at most μ j
        const double v0 = pair.velocity(p.tangent[0], c.tangent[0]);
        const double v1 = pair.velocity(p.tangent[1], c.tangent[1]);
        const double speed = std::sqrt(v0 * v0 + v1 * v1);
        if (speed > 0.0) {
          const Vec3 direction = (v0 * c.tangent[0] + v1 * c.tangent[1]) / speed;
          ContactRow row;
          make_row(row, p, direction, mass_a, mass_b);
          pair.apply(row, direction, -std::min(speed * row.mass, c.friction * j));
        }
      }
      if (largest_change < converged_velocity) c.converged = true;
      any = true;
    }
    if (!any) break;
  }
}

}  // namespace rtp
