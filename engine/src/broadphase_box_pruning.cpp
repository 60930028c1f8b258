// Box pruning (Terdiman, "Box pruning", 2002): the boxes in slabs across y or z, each slab in x
// order, swept with a vector of boxes tested at a time (rtp/broadphase.h).
#include <algorithm>
#include <array>
#include <bit>
#include <boost/sort/spreadsort/float_sort.hpp>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "broadphase_internal.h"
#include "simd.h"
#include "threads.h"

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
    const bool kept = same_boxes && find_arrivals();
    if (!kept) rebuild_slabs();
    // on threads, each a run of whole slabs holding about an equal share of the entries (a
    // pyramid's low slabs hold many more boxes than its high ones): kept slabs sorted and
    // written as columns, then swept, each thread into a list of its own, the lists joined in
    // slab order: the same columns, and the same pairs in the same order, as on one thread
    const std::size_t slabs = members_.size();
    slab_entries_.resize(slabs + 1);
    slab_entries_[0] = 0;
    for (std::size_t k = 0; k < slabs; ++k)
      slab_entries_[k + 1] =
          slab_entries_[k] + members_[k].size() + (kept ? arrivals_[k].size() : 0);
    const std::size_t entries = slab_entries_[slabs];
    const int threads = threads_ > 1 && slabs > 1 && entries >= kParallelEntries ? threads_ : 1;
    thread_pairs_.resize(std::size_t(threads));
    // (emptied here: a team OpenMP gives fewer threads than asked leaves some unwritten)
    for (std::vector<ProxyPair>& list : thread_pairs_) list.clear();
    scratch_.resize(std::size_t(threads));
    parallel_region(threads, threads > 1, [&] {
      const int parts = team_size(), part = team_index();
      // the part's slabs: those whose first entry falls in its share of the entries
      auto first_slab = [&](const std::vector<std::size_t>& starts, int k) {
        const std::size_t at = starts.back() * std::size_t(k) / std::size_t(parts);
        return std::size_t(std::lower_bound(starts.begin(), starts.end() - 1, at) -
                           starts.begin());
      };
      if (kept) {
        const std::size_t from = first_slab(slab_entries_, part);
        const std::size_t to = first_slab(slab_entries_, part + 1);
        for (std::size_t k = from; k < to; ++k) sort_slab(k, scratch_[std::size_t(part)]);
#pragma omp barrier
#pragma omp single
        place_columns();  // (a barrier)
        for (std::size_t k = from; k < to; ++k) write_columns(k);
#pragma omp barrier
      }
      // (the columns by value, and a list on the thread's own stack: pushing into the members
      // (pairs_ beside the columns' headers, the threads' lists side by side) had the threads
      // write the cache lines the other read at every pair: at pyramid-100 the two threads'
      // sweep took 590 perf samples where one thread's whole update took 376)
      const Columns columns = this->columns();
      std::vector<ProxyPair> out;
      std::vector<ProxyPair>& list = part == 0 ? pairs_ : thread_pairs_[std::size_t(part)];
      out.swap(list);  // (its capacity kept)
      out.clear();
      sweep_slabs(columns, first_slab(first_, part), first_slab(first_, part + 1), out);
      out.swap(list);
    });
    for (std::size_t part = 1; part < std::size_t(threads); ++part)
      pairs_.insert(pairs_.end(), thread_pairs_[part].begin(), thread_pairs_[part].end());
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

  // Buckets: slabs across y or z (the slab axis), each box in every slab its interval along that
  // axis touches, so a sweep on x meets only the boxes near it along the axis as well. Slabs are
  // three times the mean box extent along the axis (a box then sits in about 1.33 of them:
  // thicker slabs give each sweep more boxes, thinner ones put each box in more slabs;
  // docs/broadphase.md has the measurements) and at most kMaxSlabs. The axis is the one of y and
  // z that gives more slabs: y for a stack or a pyramid, z for a world wide in x and z and low in
  // y (196 pyramids of ten rows on a 154 m square: three slabs across y, each sweep on x meeting
  // the fourteen pyramids that share its x; fifty across z). A pair is reported only in the slab
  // of the larger of its two mins along the axis — one slab, which both boxes are in — so never
  // twice. The slab of a coordinate is monotonic in it and clamped to the slabs, so that holds
  // for boxes outside the range the slabs were laid out for, too: a kept layout is never wrong,
  // only slower.
  struct Layout {
    int axis = 1;                     // 1: y, 2: z
    float low = 0.0f, high = 0.0f;    // the least and the largest min along the axis
    std::size_t slabs = 1;
    float slab_height = 1.0f;
    float per_slab_height = 1.0f;  // its reciprocal: a multiply is monotonic as well
  };
  static constexpr float kInfinity = std::numeric_limits<float>::infinity();
  // the layouts for a set of boxes along y and along z, gathered a box at a time (entry 0, x,
  // unused)
  struct LayoutOfBoxes {
    std::array<float, 3> low{kInfinity, kInfinity, kInfinity};
    std::array<float, 3> high{-kInfinity, -kInfinity, -kInfinity};
    std::array<double, 3> total_height{};
    std::size_t n = 0;
    void add(const Aabb& b) {
      for (int k = 1; k < 3; ++k) {
        low[k] = std::min(low[k], b.min[k]);
        high[k] = std::max(high[k], b.min[k]);
        total_height[k] += b.max[k] - b.min[k];
      }
      ++n;
    }
    Layout layout(int axis) const {
      if (n == 0) return Layout{axis};
      Layout layout{axis, low[axis], high[axis], 1, 1.0f, 1.0f};
      const double mean_height = total_height[axis] / double(n);
      const double span = double(high[axis]) - double(low[axis]);
      if (mean_height > 0.0)
        layout.slabs =
            std::clamp<std::size_t>(std::size_t(span / (3.0 * mean_height)), 1, kMaxSlabs);
      if (layout.slabs > 1) {
        layout.slab_height = float(span / double(layout.slabs));
        layout.per_slab_height = 1.0f / layout.slab_height;
      }
      return layout;
    }
    // the axis of more slabs, y where they tie
    Layout best() const {
      const Layout y = layout(1), z = layout(2);
      return z.slabs > y.slabs ? z : y;
    }
  };
  // clamped as a float, so no coordinate (far outside the layout, or not a number) converts out
  // of range
  std::size_t slab_of(float at) const {
    if (layout_.slabs == 1) return 0;
    const float last = float(layout_.slabs - 1);
    const float slab = (at - layout_.low) * layout_.per_slab_height;
    return std::size_t(std::min(last, std::max(0.0f, slab)));
  }
  SlabRange range_of(const Aabb& b) const {
    return {std::uint16_t(slab_of(b.min[layout_.axis])),
            std::uint16_t(slab_of(b.max[layout_.axis]))};
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
    layout_ = layout.best();
    sort_keyed(keyed_);
    members_.resize(layout_.slabs);
    for (auto& m : members_) m.clear();
    ranges_.assign(capacity(), SlabRange{});
    for (const Keyed& k : keyed_) {
      const SlabRange r = range_of(boxes_[k.id]);
      ranges_[k.id] = r;
      for (std::size_t s = r.home; s <= r.last; ++s) members_[s].push_back(k);
    }
    place_columns();
    for (std::size_t k = 0; k < members_.size(); ++k) write_columns(k);
  }

  // While coherent: the kept slabs, each brought back into x order by insertion sort (a slab
  // holds a few hundred boxes, so a box passes few others in it per step: far fewer swaps than
  // one order of every box), with the boxes that left a slab dropped and those that entered it
  // merged in. find_arrivals() finds which boxes enter which slabs, or false when the scene is
  // not coherent enough for that to pay (the caller rebuilds); sort_slab() then brings one slab
  // back into order.
  bool find_arrivals() {
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
    // the boxes spread or moved by a slab or more, or the slab count would change by a quarter,
    // or the other axis would now give a quarter more slabs than this one
    const Layout now = boxes_now.layout(layout_.axis);
    const Layout other = boxes_now.layout(3 - layout_.axis);
    return !(std::abs(now.low - layout_.low) > layout_.slab_height ||
             std::abs(now.high - layout_.high) > layout_.slab_height ||
             4 * std::max(now.slabs, layout_.slabs) > 5 * std::min(now.slabs, layout_.slabs) ||
             4 * other.slabs > 5 * now.slabs);
  }
  // slab s's members that stay, with their new min x, in last step's order (kept in place by
  // advancing a count), sorted, and the arrivals merged in (`scratch`: the calling thread's)
  void sort_slab(std::size_t s, std::vector<Keyed>& scratch) {
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
      scratch.resize(m.size() + arriving.size());
      std::merge(m.begin(), m.end(), arriving.begin(), arriving.end(), scratch.begin(),
                 [](const Keyed& a, const Keyed& b) { return a.key < b.key; });
      m.swap(scratch);
    }
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
  // boxes starting at +∞ so the sweep needs no scalar tail. place_columns() gives each slab its
  // first entry from the members' counts, write_columns() writes one slab there.
  void place_columns() {
    first_.resize(members_.size() + 1);
    first_[0] = 0;
    for (std::size_t s = 0; s < members_.size(); ++s)
      first_[s + 1] = first_[s] + members_[s].size() + simd::kNativeFloats;
    const std::size_t total = first_.back();
    for (auto* column : {&min_x_, &max_x_, &min_y_, &max_y_, &min_z_, &max_z_, &home_})
      if (column->size() < total) column->resize(total);
    if (ids_.size() < total) ids_.resize(total);
  }
  void write_columns(std::size_t s) {
    std::size_t i = first_[s];
    for (const Keyed& k : members_[s]) {
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
    std::fill(min_x_.begin() + std::ptrdiff_t(i), min_x_.begin() + std::ptrdiff_t(first_[s + 1]),
              std::numeric_limits<float>::infinity());
  }

  // the slabs' columns as the sweep reads them
  struct Columns {
    const std::size_t* first;  // each slab's first entry, and one past its padding
    const float *min_x, *max_x, *min_y, *max_y, *min_z, *max_z, *home;
    const ProxyId* ids;
  };
  Columns columns() const {
    return {first_.data(), min_x_.data(), max_x_.data(), min_y_.data(), max_y_.data(),
            min_z_.data(), max_z_.data(), home_.data(),  ids_.data()};
  }

  // in each slab of [from, to), each box against the boxes after it that start before it ends
  // on x
  // (the columns by value: the thread's own copy, which no push can alias)
  static void sweep_slabs(const Columns c, std::size_t from, std::size_t to,
                          std::vector<ProxyPair>& out) {
    using simd::at_least, simd::at_most, simd::load_floats, simd::splat_floats;
    for (std::size_t s = from; s < to; ++s) {
      const Lanes this_slab = splat_floats(float(s));
      const std::size_t end = c.first[s + 1] - simd::kNativeFloats;
      for (std::size_t i = c.first[s]; i < end; ++i) {
        const float end_x = c.max_x[i], lo_y = c.min_y[i], hi_y = c.max_y[i], lo_z = c.min_z[i],
                    hi_z = c.max_z[i], home = c.home[i];
        for (std::size_t j = i + 1;; j += simd::kNativeFloats) {
          const simd::MaskN on_x = at_most(load_floats(&c.min_x[j]), splat_floats(end_x));
          if (!simd::any_of(on_x)) break;
          const simd::MaskN hit =
              on_x & at_most(load_floats(&c.min_y[j]), splat_floats(hi_y)) &
              at_least(load_floats(&c.max_y[j]), splat_floats(lo_y)) &
              at_most(load_floats(&c.min_z[j]), splat_floats(hi_z)) &
              at_least(load_floats(&c.max_z[j]), splat_floats(lo_z)) &
              simd::equal(simd::max(load_floats(&c.home[j]), splat_floats(home)), this_slab);
          if (simd::any_of(hit)) {
            // the hits as bits, then one pass per set bit: usually one, and no branch per lane
            for (unsigned bits = simd::lane_bits(hit); bits != 0; bits &= bits - 1)
              out.push_back(ordered(c.ids[i], c.ids[j + std::size_t(std::countr_zero(bits))]));
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
  std::vector<Keyed> keyed_;                  // scratch: every box with its keys (a rebuild)
  // the slabs' members as columns, each slab in x order; home = the slab of the box's min along
  // the slab axis
  // each slab's first entry, and one past the last slab's padding
  std::vector<std::size_t> first_;
  std::vector<std::size_t> slab_entries_;  // each slab's first entry at most, as update() shares
  std::vector<std::vector<Keyed>> scratch_;  // a merge's scratch, one a thread
  std::vector<float> min_x_, max_x_, min_y_, max_y_, min_z_, max_z_, home_;
  std::vector<ProxyId> ids_;
  std::vector<ProxyPair> pairs_;
};

}  // namespace

std::unique_ptr<BroadPhase> make_box_pruning() { return std::make_unique<BoxPruning>(); }

}  // namespace rtp::detail
