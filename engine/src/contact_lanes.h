// The contact solver's lanes: the contacts of one colour packed kBlockLanes manifolds to a block,
// one a lane, in single precision (contact_prepare.cpp packs them, contact_solver.cpp solves them;
// docs/solver.md has the layout).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "simd.h"

// The copies of the contact pipeline a build carries, one per instruction set (contact_stages.h),
// each in a namespace of its own, named by CMake: a build for one set has the one, isa_native
#ifndef RTP_CONTACT_ISA_NAMESPACE
#define RTP_CONTACT_ISA_NAMESPACE isa_native
#define RTP_CONTACT_ISA_NAME "native"
#endif

namespace rtp {
inline namespace RTP_CONTACT_ISA_NAMESPACE {

// lanes per block: the widest float register (16 with AVX-512, 8 with AVX, 4 on the x86-64
// baseline's SSE2). Eight lanes on SSE2, a block in two 4-lane halves, took its 16 registers'
// worth twice over and spilled: the baseline build's base-100 step 23.3 -> 14.1 ms at four
// (docs/solver.md, "Cost"); the lane count changes no result
inline constexpr std::size_t kBlockLanes = simd::kNativeFloats;
using Lane = simd::Pack<float, kBlockLanes>;
using LaneMask = simd::MaskOf<Lane>;


// one block: kBlockLanes manifolds of one colour, one a lane, what every pass reads (docs/solver.md
// gives the layout's bytes per point); what only some passes read is in its ContactBlockRest
struct ContactBlock {
  std::array<std::uint32_t, kBlockLanes> body_a, body_b;  // an empty lane holds the body at rest
  Lane normal[3];
  // the tangents t0, t1 as one lane (tangents_of, contact_solver_internal.h): the narrow phase's
  // basis from the normal, t0 = s (n_y, −n_x, 0) where s > 0, else −s (0, n_z, −n_y), and
  // t1 = n × t0; 0 in an empty lane
  Lane tangent_scale;
  // (each lane's bodies' inverse masses and inertias' xx are read with their velocities, from
  // their records: SolverBody)
  // friction at the centre of the manifold's points: its anchors from each body, as coordinates
  // along tangent[0], tangent[1] and the normal; the accumulated impulses, the effective masses
  // along the tangents and about the normal, and the mean distance of the points from it (the
  // twist's lever)
  Lane centre_a[3], centre_b[3];
  Lane friction_impulse[2], twist_impulse;
  Lane friction, tangent_mass[2], twist_mass, twist_arm;
  struct Point {
    // the point from a's centre of mass in the manifold's frame: its coordinates along
    // tangent[0], tangent[1] and the normal (m). The point is the same for both bodies, so from
    // b's centre it is this plus centre_b − centre_a (FrameOffset); the rows are computed from
    // these as read
    Lane anchor[3];
    Lane normal_impulse;
    Lane separation;   // as the bodies last moved: the base (ContactBlockRest), plus their motion
                       // along n since the step's start (m); computed again once they move
    Lane normal_mass;  // 1 / the velocity change per unit impulse (kg); 0 for an empty point
  } points[4];
};
// 44 floats a lane: 20 for the manifold, 6 for each of four points (176 bytes a manifold; the soft
// step's stiffness is chosen in the solve, by whether a body is static). A point's anchors as two
// world vectors were 9 a point, the tangents 6 lanes, the bodies' masses 4 and the fresh lanes 1:
// 66 a lane (docs/solver.md, "Precision and layout")
static_assert(sizeof(ContactBlock) == 44 * sizeof(float) * kBlockLanes);

// the rest of a block: what the passes read only now and then (a substep's first separations,
// a non-isotropic block's inertia, a fresh block's lanes, restitution), and what prepare() and
// store_impulses() read
struct ContactBlockRest {
  std::array<std::uint32_t, kBlockLanes> contact;  // index into contacts_, or kNoContact
  Lane inverse_inertia_a[5], inverse_inertia_b[5];  // yy zz xy xz yz
  Lane restitution;
  // a point without a warm start, or hitting: the manifold is solved locally (read where the
  // block's flags say some lane is)
  LaneMask fresh;
  struct Point {
    Lane base_separation;     // at the step's start, less n·(b's anchor − a's) (m)
    Lane max_normal_impulse;  // the largest this step (N s; kept where some lane bounces)
    Lane approach_velocity;   // relative normal velocity at impact (m/s), < 0 closing
  } points[4];
};
static_assert(sizeof(ContactBlockRest) == 25 * sizeof(float) * kBlockLanes);
inline constexpr std::uint32_t kNoContact = ~std::uint32_t{0};

struct ContactLanes {
  std::vector<ContactBlock> blocks;
  std::vector<ContactBlockRest> rest;  // one a block
  std::vector<std::uint32_t> colour_start;  // colour k: blocks[start[k], start[k + 1])
  // the colours that hold a block, in order: a pass visits these (a small scene's two or three
  // of the 64, whose walk took 16 % of a four-box scene's step by `perf`)
  std::vector<std::uint8_t> used_colours;
  // per block, what a pass asks before it reads the block (kIsotropicBlock, kFreshBlock,
  // kBouncingBlock): a byte, where the lanes behind the last two are a cache line each
  std::vector<std::uint8_t> flags;
};
// every lane's two bodies have an inverse inertia c·1 (cubes, spheres, static bodies): the solve
// applies it as a number, not a matrix
inline constexpr std::uint8_t kIsotropicBlock = 1;
// some lane is fresh (ContactBlockRest::fresh): the solve runs the block's points several times
inline constexpr std::uint8_t kFreshBlock = 2;
// some lane's restitution is above zero: the solve keeps each point's largest impulse
inline constexpr std::uint8_t kBouncingBlock = 4;

}  // namespace RTP_CONTACT_ISA_NAMESPACE
}  // namespace rtp
