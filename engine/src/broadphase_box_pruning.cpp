// Box pruning (Terdiman, "Box pruning", 2002): the boxes in slabs across y, each slab in x order,
// swept with a vector of boxes tested at a time (rtp/broadphase.h).
#include <algorithm>
#include <bit>
#include <boost/sort/spreadsort/float_sort.hpp>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#if defined(_OPENMP)
#include <omp.h>
#endif

#include "broadphase_internal.h"
#include "simd.h"

namespace rtp::detail {
namespace {

// ---------------------------------------------------------------------------------------------
// box pruning: sort on x every update, sweep, and test y and z for a vector of boxes at a time

class BoxPruning final : public ProxyStore {
 public:
  ProxyId add(const Aabb& box) override { return allocate(box); }
  void move(ProxyId id, const Aabb& box) override { set(id, box); }
  void remove(ProxyId id) override { release(id); }
  const std::vector<ProxyPair>& pairs() const override { return pairs_; }
  void set_threads(int threads) override { threads_ = std::max(1, threads); }

  void update() override {
    // the previous update's slabs, and each slab's order on x, are kept while no box arrives or
    // leaves and the scene stays coherent: each slab is then nearly sorted already
    const bool same_boxes = added_.empty() && removed_.empty();
    added_.clear();
    recycle_removed();
    pairs_.clear();
    if (!same_boxes || !update_slabs()) rebuild_slabs();
    sweep();
  }

 private:
  using Lanes = simd::FloatN;  // as many boxes as the widest register holds
  // a box's min x and handle, 8 bytes: what the sorts move
  struct Keyed {
    float key;
    ProxyId id;
  };
  static_assert(sizeof(Keyed) == 8);
  // the slabs a box's y interval touches: those of its min y and of its max y
  struct SlabRange {
    std::uint16_t home = 0, last = 0;
    bool operator==(const SlabRange&) const = default;
    bool covers(std::size_t slab) const { return home <= slab && slab <= last; }
  };

  // Buckets: slabs across y, each box in every slab its y interval touches, so a sweep on x
  // meets only the boxes near it in y as well. Slabs are three times the mean box height (a box
  // then sits in about 1.33 of them: taller slabs give each sweep more boxes, shorter ones put
  // each box in more slabs; docs/broadphase.md has the measurements) and at most kMaxSlabs. A pair
  // is reported only in the slab of the larger of its two min y — one slab, which both boxes are in
  // — so never twice. The slab of a y value is monotonic in y and clamped to the slabs, so that
  // holds for boxes outside the range the slabs were laid out for, too: a kept layout is never
  // wrong, only slower.
  struct Layout {
    float low_y = 0.0f, high_y = 0.0f;  // the least and the largest min y
    std::size_t slabs = 1;
    float slab_height = 1.0f;
    float per_slab_height = 1.0f;  // its reciprocal: a multiply is monotonic in y as well
  };
  // the layout for a set of boxes, gathered a box at a time
  struct LayoutOfBoxes {
    float low_y = std::numeric_limits<float>::infinity(), high_y = -low_y;
    double total_height = 0.0;
    std::size_t n = 0;
    void add(const Aabb& b) {
      low_y = std::min(low_y, b.min[1]);
      high_y = std::max(high_y, b.min[1]);
      total_height += b.max[1] - b.min[1];
      ++n;
    }
    Layout layout() const {
      if (n == 0) return Layout{};
      Layout layout{low_y, high_y, 1, 1.0f, 1.0f};
      const double mean_height = total_height / double(n);
      const double span = double(high_y) - double(low_y);
      if (mean_height > 0.0)
        layout.slabs =
            std::clamp<std::size_t>(std::size_t(span / (3.0 * mean_height)), 1, kMaxSlabs);
      if (layout.slabs > 1) {
        layout.slab_height = float(span / double(layout.slabs));
        layout.per_slab_height = 1.0f / layout.slab_height;
      }
      return layout;
    }
  };
  // clamped as a float, so no y (far outside the layout, or not a number) converts out of range
  std::size_t slab_of(float y) const {
    if (layout_.slabs == 1) return 0;
    const float last = float(layout_.slabs - 1);
    const float slab = (y - layout_.low_y) * layout_.per_slab_height;
    return std::size_t(std::min(last, std::max(0.0f, slab)));
  }
  SlabRange range_of(const Aabb& b) const {
    return {std::uint16_t(slab_of(b.min[1])), std::uint16_t(slab_of(b.max[1]))};
  }

  // From scratch: every live box ordered on x by spreadsort (Boost's radix hybrid, which sorts
  // floats by their bits), then dealt into its slabs in that order, so each slab is in x order.
  void rebuild_slabs() {
    LayoutOfBoxes layout;
    keyed_.clear();
    for (ProxyId id = 0; id < capacity(); ++id)
      if (alive(id)) {
        layout.add(boxes_[id]);
        keyed_.push_back({boxes_[id].min[0], id});
      }
    layout_ = layout.layout();
    sort_keyed(keyed_);
    members_.resize(layout_.slabs);
    for (auto& m : members_) m.clear();
    ranges_.assign(capacity(), SlabRange{});
    for (const Keyed& k : keyed_) {
      const SlabRange r = range_of(boxes_[k.id]);
      ranges_[k.id] = r;
      for (std::size_t s = r.home; s <= r.last; ++s) members_[s].push_back(k);
    }
    std::size_t entries = 0;
    for (const auto& m : members_) entries += m.size();
    begin_columns(entries);
    for (const auto& m : members_) append_columns(m);
  }

  // While coherent: the kept slabs, each brought back into x order by insertion sort (a slab
  // holds a few hundred boxes, so a box passes few others in it per step: far fewer swaps than
  // one order of every box), with the boxes that left a slab dropped and those that entered it
  // merged in. False when the scene is not coherent enough for that to pay (the caller rebuilds).
  bool update_slabs() {
    if (members_.empty()) return false;
    // one pass over the boxes: each box's slabs in the kept layout (a box entering a slab is an
    // arrival there), and the layout the boxes would be given now
    arrivals_.resize(layout_.slabs);
    for (auto& a : arrivals_) a.clear();
    LayoutOfBoxes boxes_now;
    std::size_t changed = 0;
    const std::size_t most_changed = capacity() / kMaxChangedFraction;
    for (ProxyId id = 0; id < capacity(); ++id) {
      if (!alive(id)) continue;  // a handle freed earlier, not yet reused
      const Aabb& b = boxes_[id];
      boxes_now.add(b);
      const SlabRange r = range_of(b);
      if (r == ranges_[id]) continue;
      for (std::size_t s = r.home; s <= r.last; ++s)
        if (!ranges_[id].covers(s)) arrivals_[s].push_back({b.min[0], id});
      ranges_[id] = r;
      if (++changed > most_changed) return false;  // not coherent: the caller rebuilds
    }
    // the boxes spread or moved by a slab or more, or the slab count would change by a quarter
    const Layout now = boxes_now.layout();
    if (std::abs(now.low_y - layout_.low_y) > layout_.slab_height ||
        std::abs(now.high_y - layout_.high_y) > layout_.slab_height ||
        4 * std::max(now.slabs, layout_.slabs) > 5 * std::min(now.slabs, layout_.slabs))
      return false;
    std::size_t entries = 0;  // at most: the members so far and the arrivals
    for (std::size_t s = 0; s < layout_.slabs; ++s)
      entries += members_[s].size() + arrivals_[s].size();
    begin_columns(entries);
    for (std::size_t s = 0; s < layout_.slabs; ++s) {
      // the members that stay, with their new min x, in last step's order (kept in place by
      // advancing a count)
      std::vector<Keyed>& m = members_[s];
      std::size_t kept = 0;
      for (const Keyed& k : m) {
        const ProxyId id = k.id;
        m[kept] = {boxes_[id].min[0], id};
        kept += ranges_[id].covers(s);
      }
      m.resize(kept);
      insertion_sort_or_resort(m);
      if (!arrivals_[s].empty()) {
        std::vector<Keyed>& arriving = arrivals_[s];
        sort_keyed(arriving);
        keyed_.resize(m.size() + arriving.size());
        std::merge(m.begin(), m.end(), arriving.begin(), arriving.end(), keyed_.begin(),
                   [](const Keyed& a, const Keyed& b) { return a.key < b.key; });
        m.swap(keyed_);
      }
      append_columns(m);  // while the slab's boxes are in the cache
    }
    return true;
  }

  static void sort_keyed(std::vector<Keyed>& keyed) {
    boost::sort::spreadsort::float_sort(
        keyed.begin(), keyed.end(),
        // the key's bits widened to 64: spreadsort sizes its bins in the shift's type, and a
        // range of float bit patterns from a negative to a positive key overflows 32 bits
        [](const Keyed& k, unsigned offset) {
          return std::int64_t{boost::sort::spreadsort::float_mem_cast<float, std::int32_t>(k.key)} >>
                 offset;
        },
        [](const Keyed& a, const Keyed& b) { return a.key < b.key; });
  }
  // insertion sort is O(n + swaps) from a nearly sorted order; it gives up after
  // kMaxSwapsPerBox · n swaps (a scene that is not coherent) for spreadsort
  static void insertion_sort_or_resort(std::vector<Keyed>& keyed) {
    std::size_t swaps = 0;
    const std::size_t budget = kMaxSwapsPerBox * keyed.size();
    for (std::size_t i = 1; i < keyed.size(); ++i) {
      const Keyed moving = keyed[i];
      std::size_t j = i;
      for (; j > 0 && moving.key < keyed[j - 1].key; --j) keyed[j] = keyed[j - 1];
      keyed[j] = moving;
      swaps += i - j;
      if (swaps > budget) {
        sort_keyed(keyed);
        return;
      }
    }
  }

  // Each slab's members in x order as columns, slab after slab, each followed by one vector of
  // boxes starting at +∞ so the sweep needs no scalar tail. begin_columns makes room for that
  // many members in all; append_columns writes the next slab.
  void begin_columns(std::size_t members) {
    const std::size_t total = members + members_.size() * simd::kNativeFloats;
    for (auto* column : {&min_x_, &max_x_, &min_y_, &max_y_, &min_z_, &max_z_, &home_})
      if (column->size() < total) column->resize(total);
    if (ids_.size() < total) ids_.resize(total);
    first_.assign(1, 0);
  }
  void append_columns(const std::vector<Keyed>& members) {
    std::size_t i = first_.back();
    for (const Keyed& k : members) {
      const ProxyId id = k.id;
      const Aabb& b = boxes_[id];
      min_x_[i] = b.min[0];
      max_x_[i] = b.max[0];
      min_y_[i] = b.min[1];
      max_y_[i] = b.max[1];
      min_z_[i] = b.min[2];
      max_z_[i] = b.max[2];
      home_[i] = float(ranges_[id].home);
      ids_[i] = id;
      ++i;
    }
    const std::size_t end = i + simd::kNativeFloats;
    std::fill(min_x_.begin() + std::ptrdiff_t(i), min_x_.begin() + std::ptrdiff_t(end),
              std::numeric_limits<float>::infinity());
    first_.push_back(end);
  }

  // every slab swept; on threads, each takes a run of whole slabs holding about an equal share
  // of the entries (a pyramid's low slabs hold many more boxes than its high ones), into its own
  // list, and the lists are joined in slab order: the same pairs in the same order as on one
  void sweep() {
    const std::size_t slabs = members_.size();
    const std::size_t entries = first_.back();
#if defined(_OPENMP)
    if (threads_ > 1 && slabs > 1 && entries >= kParallelEntries) {
      thread_pairs_.resize(std::size_t(threads_));
#pragma omp parallel num_threads(threads_)
      {
        const std::size_t parts = std::size_t(omp_get_num_threads());
        const std::size_t part = std::size_t(omp_get_thread_num());
        // a slab is this part's when its first entry falls in the part's share of the entries
        auto first_slab = [&](std::size_t k) {
          const std::size_t at = entries * k / parts;
          return std::size_t(std::lower_bound(first_.begin(), first_.end() - 1, at) -
                             first_.begin());
        };
        std::vector<ProxyPair>& out = part == 0 ? pairs_ : thread_pairs_[part];
        out.clear();
        sweep_slabs(first_slab(part), first_slab(part + 1), out);
      }
      for (std::size_t part = 1; part < thread_pairs_.size(); ++part)
        pairs_.insert(pairs_.end(), thread_pairs_[part].begin(), thread_pairs_[part].end());
      return;
    }
#endif
    sweep_slabs(0, slabs, pairs_);
  }

  // in each slab of [from, to), each box against the boxes after it that start before it ends
  // on x
  void sweep_slabs(std::size_t from, std::size_t to, std::vector<ProxyPair>& out) const {
    using simd::at_least, simd::at_most, simd::load_floats, simd::splat_floats;
    for (std::size_t s = from; s < to; ++s) {
      const Lanes this_slab = splat_floats(float(s));
      const std::size_t end = first_[s] + members_[s].size();
      for (std::size_t i = first_[s]; i < end; ++i) {
        const float end_x = max_x_[i], lo_y = min_y_[i], hi_y = max_y_[i], lo_z = min_z_[i],
                    hi_z = max_z_[i], home = home_[i];
        for (std::size_t j = i + 1;; j += simd::kNativeFloats) {
          const simd::MaskN on_x = at_most(load_floats(&min_x_[j]), splat_floats(end_x));
          if (!simd::any_of(on_x)) break;
          const simd::MaskN hit =
              on_x & at_most(load_floats(&min_y_[j]), splat_floats(hi_y)) &
              at_least(load_floats(&max_y_[j]), splat_floats(lo_y)) &
              at_most(load_floats(&min_z_[j]), splat_floats(hi_z)) &
              at_least(load_floats(&max_z_[j]), splat_floats(lo_z)) &
              simd::equal(simd::max(load_floats(&home_[j]), splat_floats(home)), this_slab);
          if (simd::any_of(hit)) {
            // the hits as bits, then one pass per set bit: usually one, and no branch per lane
            for (unsigned bits = simd::lane_bits(hit); bits != 0; bits &= bits - 1)
              out.push_back(ordered(ids_[i], ids_[j + std::size_t(std::countr_zero(bits))]));
          }
          if (!simd::all_of(on_x)) break;  // sorted: the boxes after these start later still
        }
      }
    }
  }

  static constexpr std::size_t kMaxSwapsPerBox = 8;
  // fewer slab entries than this are swept on one thread: below it the team costs more
  static constexpr std::size_t kParallelEntries = 4096;
  int threads_ = 1;
  std::vector<std::vector<ProxyPair>> thread_pairs_;  // the sweep's lists, one a thread
  // more than this fraction (1/k) of the boxes changing slabs in one step: rebuild instead
  static constexpr std::size_t kMaxChangedFraction = 4;
  // at most this many slabs: beyond it the per-slab padding and bookkeeping outweigh the gain
  static constexpr std::size_t kMaxSlabs = 256;
  Layout layout_;
  std::vector<std::vector<Keyed>> members_;   // each slab's boxes with their min x, in x order
  std::vector<SlabRange> ranges_;             // each box's slabs (by handle)
  std::vector<std::vector<Keyed>> arrivals_;  // boxes entering each slab this update
  std::vector<Keyed> keyed_;                  // scratch: one slab (or every box) with its keys
  // the slabs' members as columns, each slab in x order; home = the slab of the box's min y
  // each slab's first entry, and one past the last slab's padding
  std::vector<std::size_t> first_;
  std::vector<float> min_x_, max_x_, min_y_, max_y_, min_z_, max_z_, home_;
  std::vector<ProxyId> ids_;
  std::vector<ProxyPair> pairs_;
};

}  // namespace

std::unique_ptr<BroadPhase> make_box_pruning() { return std::make_unique<BoxPruning>(); }

}  // namespace rtp::detail
