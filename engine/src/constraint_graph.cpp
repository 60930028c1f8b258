// The constraint graph: the step's contacts in colours, as Box2D v3's constraint graph does — no two
// contacts of a colour share a dynamic body, so a colour's contacts are solved at once, on lanes
// and threads, with the result of solving them one by one — and each colour packed into the
// solver's blocks (docs/solver.md, "The three solvers").
#include <algorithm>
#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>

#if defined(_OPENMP)
#include <omp.h>
#endif

#include "contacts.h"
#include "hash.h"
#include "threads.h"

namespace rtp {
inline namespace RTP_CONTACT_ISA_NAMESPACE {

namespace {

constexpr std::size_t W = kBlockLanes;

}  // namespace

void ContactPipeline::colour_greedily() {
  // Greedy, in pair order: each contact takes a colour neither dynamic body holds. Taking the
  // first such colour, a colour's contacts run across the scene from the low body indices to the
  // high (a pyramid's rows, left to right), and the passes, colour by colour, lean a stack that
  // way: a 5,050-box pyramid swayed toward its low indices and drifted 9–12 mm in 10 s as the
  // settings moved at round-off. So a first pass finds how many colours the first free one
  // needs, and the second starts each contact's search at a colour drawn from a hash of its key
  // among those, wrapping round (beyond them only where none is free): the same number of
  // colours, as evenly filled, and no direction in them (6–7 mm; docs/solver.md, "The lean")
  std::array<std::uint32_t, kColours + 1> counts{};
  std::vector<std::uint8_t>& colour_of = colour_scratch_;
  colour_of.resize(contacts_.size());
  int spread = 0;  // the colours the first pass used
  for (const bool scrambled : {false, true}) {
    body_colours_.assign(bodies_.size(), 0);
    const std::uint64_t in_spread = (std::uint64_t{1} << spread) - 1;  // spread < kColours
    for (std::size_t i = 0; i < contacts_.size(); ++i) {
      const std::uint64_t key = contact_keys_[i];
      const BodyId a = BodyId(key >> 32), b = BodyId(key & 0xffffffffu);
      const bool dynamic_a = masses_[a].inverse_mass > 0.0;
      const bool dynamic_b = masses_[b].inverse_mass > 0.0;
      const std::uint64_t taken =
          (dynamic_a ? body_colours_[a] : 0) | (dynamic_b ? body_colours_[b] : 0);
      int colour = std::countr_one(taken);
      if (scrambled && spread > 1) {
        // a colour to start from, in [0, spread)
        const int first = int(detail::mix64(key + 0x9e3779b97f4a7c15ull) % std::uint64_t(spread));
        const std::uint64_t free = ~taken & in_spread;
        const std::uint64_t from_first = free & (~std::uint64_t{0} << first);
        if (from_first != 0)
          colour = std::countr_zero(from_first);
        else if (free != 0)
          colour = std::countr_zero(free);
      }
      // the last colour is the overflow group and takes anything
      colour = std::min(colour, kColours - 1);
      if (colour < kColours - 1) {
        if (dynamic_a) body_colours_[a] |= std::uint64_t{1} << colour;
        if (dynamic_b) body_colours_[b] |= std::uint64_t{1} << colour;
      }
      if (!scrambled) {
        spread = std::max(spread, std::min(colour + 1, kColours - 1));
        continue;
      }
      colour_of[i] = std::uint8_t(colour | contact_class_[i]);
      ++counts[colour + 1];
    }
  }
  colour_start_.assign(counts.begin(), counts.end());
  for (int k = 0; k < kColours; ++k) colour_start_[k + 1] += colour_start_[k];
  // each colour's contacts in pair order
  std::vector<std::uint32_t>& by_colour = colour_scratch_order_;
  by_colour.resize(contacts_.size());
  std::array<std::uint32_t, kColours> next{};
  for (int k = 0; k < kColours; ++k) next[k] = colour_start_[k];
  for (std::size_t i = 0; i < contacts_.size(); ++i)
    by_colour[next[colour_of[i] & ~(kColdContact | kQuietContact)]++] = std::uint32_t(i);
}

void ContactPipeline::colour_contacts() {
  // each contact's colour, and its class (contact_class_) in the top bits; read from the keys
  // and the classes alone, not the contacts (a 5,050-box pyramid's are 3.4 MB)
  constexpr std::uint8_t kCold = kColdContact, kQuiet = kQuietContact;
  static_assert(kColours <= kQuiet && (kCold & kQuiet) == 0);
  constexpr std::uint8_t kClass = kCold | kQuiet;
  std::vector<std::uint8_t>& colour_of = colour_scratch_;
  // the same touching pairs as last step's (a resting scene's every step), which were coloured
  // then, take the same colours: only the classes are new
  const bool same_pairs = lanes_ && contact_keys_ == previous_keys_;
  if (!same_pairs) colour_greedily();
  // within a colour, the cold contacts (a point that may push with no warm start) first: a block
  // holding one solves its points several times in a row (solve()), and spread by pair order
  // they put one in most blocks. The quiet ones last: a block of them alone has no warm start
  // to apply, and while its points push nothing the solve skips their responses and friction.
  // A colour wide enough for threads is packed in kPackParts contiguous parts of its blocks, the
  // shares two threads solve (for_each_block), on any team: the shares then hold the same bodies
  // from colour to colour in pair order, so a body's lines stay with one core (packed across the
  // whole colour, two threads took 10 % longer a step at base 100). A colour's contacts share no
  // dynamic body, so their order in it changes no result; but which contacts share a block
  // decides whether it takes the isotropic rows (each inverse inertia a multiple of the
  // identity), which round differently from the general ones, so the parts may not follow the
  // team: packed whole on one thread and in halves on two, a colour mixing cubes and flat boxes
  // gave other bits (Contacts.MixedInertiaWideColoursGiveTheSameBitsOnOneAndTwoThreads)
  // (each colour in pair order first, then each part packed from there into colour_order_, by
  // the thread that solves it on a team of two: on one thread this took 0.08 ms of a base-100
  // step)
  const std::vector<std::uint32_t>& by_colour = colour_scratch_order_;
  const std::size_t count = contacts_.size();
  colour_order_.resize(count);
  parallel_region(std::max(1, threads_), count >= 2048, [&] {
    const int size = team_size(), index = team_index();
    if (same_pairs) {
      const auto [first, last] = share_of(count, size, index);
      for (std::size_t i = first; i < last; ++i)
        colour_of[i] = std::uint8_t((colour_of[i] & ~kClass) | contact_class_[i]);
#pragma omp barrier
    }
    for (int k = 0; k < kColours; ++k) {
      const std::size_t first = colour_start_[k], n = colour_start_[k + 1] - first;
      if (k + 1 == kColours) {  // the overflow, solved in order: left in pair order
        if (index == 0)
          std::copy_n(by_colour.begin() + std::ptrdiff_t(first), n,
                      colour_order_.begin() + std::ptrdiff_t(first));
        continue;
      }
      const std::size_t blocks = (n + W - 1) / W;
      const int parts = pack_parts(blocks);
      for (int part = index; part < parts; part += size) {
        const auto [begin, end] = share_of(blocks, parts, part);
        const std::size_t from = first + begin * W, to = first + std::min(end * W, n);
        std::size_t at = from;
        for (const std::uint8_t pass : {kCold, std::uint8_t(0), kQuiet})
          for (std::size_t j = from; j < to; ++j)
            if ((colour_of[by_colour[j]] & kClass) == pass) colour_order_[at++] = by_colour[j];
      }
    }
  });

  // the blocks: each colour's contacts W at a time, the overflow one at a time
  if (!lanes_) lanes_ = std::make_unique<ContactLanes>();
  std::vector<std::uint32_t>& block_start = lanes_->colour_start;
  block_start.assign(kColours + 1, 0);
  for (int k = 0; k < kColours; ++k) {
    const std::size_t n = colour_start_[k + 1] - colour_start_[k];
    block_start[k + 1] = block_start[k] + std::uint32_t(k + 1 < kColours ? (n + W - 1) / W : n);
  }
  lanes_->used_colours.clear();
  for (int k = 0; k < kColours; ++k)
    if (block_start[k + 1] > block_start[k]) lanes_->used_colours.push_back(std::uint8_t(k));
  lanes_->blocks.resize(block_start[kColours]);
  lanes_->rest.resize(block_start[kColours]);
  lanes_->flags.resize(block_start[kColours]);
}

}  // namespace RTP_CONTACT_ISA_NAMESPACE
}  // namespace rtp
