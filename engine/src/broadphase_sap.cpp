// The sweep-and-prune broad phases over three sorted axes: the seed's, with its table counting
// the axes each pair overlaps on, and the incremental one, which adds and removes a pair where a
// min and a max endpoint swap (rtp/broadphase.h).
#include <algorithm>
#include <array>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>

#include "broadphase_internal.h"

namespace rtp::detail {
namespace {

// A set of pairs with O(1) insertion and removal that lists as a dense array.
class PairSet {
 public:
  void add(ProxyPair p) {
    if (index_.try_emplace(p.key(), std::uint32_t(pairs_.size())).second) pairs_.push_back(p);
  }
  void remove(ProxyPair p) {
    const auto found = index_.find(p.key());
    if (found == index_.end()) return;
    const std::uint32_t slot = found->second;
    index_.erase(found);
    if (slot + 1 != pairs_.size()) {
      pairs_[slot] = pairs_.back();
      index_[pairs_[slot].key()] = slot;
    }
    pairs_.pop_back();
  }
  template <class Predicate>
  void remove_if(Predicate dead) {
    std::vector<ProxyPair> doomed;
    for (const ProxyPair& p : pairs_)
      if (dead(p)) doomed.push_back(p);
    for (const ProxyPair& p : doomed) remove(p);
  }
  void clear() {
    pairs_.clear();
    index_.clear();
  }
  const std::vector<ProxyPair>& list() const { return pairs_; }

 private:
  std::vector<ProxyPair> pairs_;
  std::unordered_map<std::uint64_t, std::uint32_t> index_;
};

// one end of a box on one axis, 8 bytes: tag = handle · 2 + (1 for the max end)
struct Endpoint {
  float value;
  std::uint32_t tag;
  ProxyId id() const { return tag >> 1; }
  bool is_max() const { return tag & 1u; }
};
static_assert(sizeof(Endpoint) == 8);

// a min goes before a max of equal value: the sorted order then agrees with closed intervals
bool precedes(const Endpoint& a, const Endpoint& b) {
  return a.value < b.value || (a.value == b.value && !a.is_max() && b.is_max());
}

// Endpoints of every live box on three axes, kept sorted between updates. The insertion sort
// is O(n + swaps), and with coherent motion swaps are few; each swap is reported to on_swap
// (the endpoint moving down, the one it passes).
class SortedAxes : public ProxyStore {
 protected:
  // applies removals and additions; returns true when so many boxes arrived that the axes were
  // sorted from scratch (the caller then rebuilds what it derives from them)
  bool apply_changes() {
    bool rebuilt = false;
    if (!removed_.empty()) {
      for (auto& axis : axes_)
        std::erase_if(axis, [&](const Endpoint& e) { return !alive(e.id()); });
    }
    if (!added_.empty()) {
      // a few arrivals are inserted from the top by the next sort (each costs a pass over the
      // axis); a batch is cheaper sorted from scratch
      rebuilt = added_.size() > axes_[0].size() / 16;
      for (int k = 0; k < 3; ++k)
        for (ProxyId id : added_) {
          if (!alive(id)) continue;  // added and removed before this update
          axes_[k].push_back({boxes_[id].min[k], id << 1});
          axes_[k].push_back({boxes_[id].max[k], id << 1 | 1u});
        }
      added_.clear();
    }
    refresh_values();
    if (rebuilt)
      for (auto& axis : axes_)
        std::sort(axis.begin(), axis.end(), [](const Endpoint& a, const Endpoint& b) {
          return precedes(a, b) || (!precedes(b, a) && a.tag < b.tag);
        });
    return rebuilt;
  }

  void refresh_values() {
    for (int k = 0; k < 3; ++k)
      for (Endpoint& e : axes_[k])
        e.value = e.is_max() ? boxes_[e.id()].max[k] : boxes_[e.id()].min[k];
  }

  template <class OnSwap>
  void insertion_sort(int k, OnSwap on_swap) {
    std::vector<Endpoint>& axis = axes_[k];
    for (std::size_t i = 1; i < axis.size(); ++i) {
      const Endpoint moving = axis[i];
      std::size_t j = i;
      while (j > 0 && precedes(moving, axis[j - 1])) {
        on_swap(moving, axis[j - 1]);
        axis[j] = axis[j - 1];
        --j;
      }
      axis[j] = moving;
    }
  }

  std::array<std::vector<Endpoint>, 3> axes_;
};

// The boxes whose intervals are open while a sorted axis is swept, with each one's place in the
// list so a closing endpoint removes its box in O(1) (swap with the last).
struct OpenList {
  std::vector<ProxyId> ids;
  std::vector<std::uint32_t> slot;  // by handle
};

// calls on_overlap(id, other) once for every pair of boxes whose intervals overlap on this axis
template <class OnOverlap>
void for_each_overlap_on_axis(const std::vector<Endpoint>& axis, std::size_t capacity,
                              OpenList& open, OnOverlap on_overlap) {
  open.ids.clear();
  open.slot.resize(capacity);
  for (const Endpoint& e : axis) {
    const ProxyId id = e.id();
    if (e.is_max()) {  // close
      const std::uint32_t s = open.slot[id];
      open.ids[s] = open.ids.back();
      open.slot[open.ids[s]] = s;
      open.ids.pop_back();
      continue;
    }
    for (ProxyId other : open.ids) on_overlap(id, other);
    open.slot[id] = std::uint32_t(open.ids.size());
    open.ids.push_back(id);
  }
}

// ---------------------------------------------------------------------------------------------
// the seed's sweep and prune: a table counting the axes each pair overlaps on

class SeedSap final : public SortedAxes {
 public:
  ProxyId add(const Aabb& box) override {
    if (capacity() >= kSeedSapMaxProxies && free_.empty())
      throw std::length_error("rtp seed-sap: its pair table takes n²/2 bytes; " +
                              std::to_string(kSeedSapMaxProxies) +
                              " boxes is its limit (use incremental-sap or box-pruning)");
    return allocate(box);
  }
  void move(ProxyId id, const Aabb& box) override { set(id, box); }
  void remove(ProxyId id) override { release(id); }
  const std::vector<ProxyPair>& pairs() const override { return pairs_; }

  void update() override {
    if (!apply_changes())
      for (int k = 0; k < 3; ++k) insertion_sort(k, [](const Endpoint&, const Endpoint&) {});
    recycle_removed();
    pairs_.clear();
    const std::size_t n = capacity();
    table_.resize(n * (n - (n > 0)) / 2);

    // early exit: an axis with no overlapping intervals has no pairs
    for (const auto& axis : axes_) {
      std::size_t open = 0, overlaps_on_axis = 0;
      for (const Endpoint& e : axis) {
        if (e.is_max()) {
          --open;
        } else {
          overlaps_on_axis += open;
          ++open;
        }
      }
      if (overlaps_on_axis == 0) return;
    }
    // count, per pair, the axes its intervals overlap on
    for (const auto& axis : axes_)
      for_each_overlap_on_axis(axis, n, open_, [&](ProxyId id, ProxyId other) {
        ++table_[cell(ordered(id, other), n)];
      });
    // the triangle: pairs counted on all three axes, each cell reset as it is read
    std::size_t c = 0;
    for (std::size_t i = 0; i + 1 < n; ++i)
      for (std::size_t j = i + 1; j < n; ++j, ++c) {
        if (table_[c] == 3) pairs_.push_back({ProxyId(i), ProxyId(j)});
        table_[c] = 0;
      }
  }

 private:
  // row-major upper triangle without the diagonal
  static std::size_t cell(ProxyPair p, std::size_t n) {
    return p.a * (2 * n - p.a - 1) / 2 + (p.b - p.a - 1);
  }

  std::vector<std::uint8_t> table_;
  OpenList open_;
  std::vector<ProxyPair> pairs_;
};

// ---------------------------------------------------------------------------------------------
// incremental sweep and prune: pairs change only where a min and a max endpoint swap

class IncrementalSap final : public SortedAxes {
 public:
  ProxyId add(const Aabb& box) override { return allocate(box); }
  void move(ProxyId id, const Aabb& box) override { set(id, box); }
  void remove(ProxyId id) override { release(id); }
  const std::vector<ProxyPair>& pairs() const override { return pairs_.list(); }

  void update() override {
    if (!removed_.empty())
      pairs_.remove_if([&](ProxyPair p) { return !alive(p.a) || !alive(p.b); });
    if (apply_changes()) {
      pairs_.clear();
      // a sweep of x, testing y and z
      for_each_overlap_on_axis(axes_[0], capacity(), open_, [&](ProxyId id, ProxyId other) {
        // both are open on x: only y and z are left to test
        const Aabb &a = boxes_[id], &b = boxes_[other];
        if (a.min[1] <= b.max[1] && b.min[1] <= a.max[1] && a.min[2] <= b.max[2] &&
            b.min[2] <= a.max[2])
          pairs_.add(ordered(id, other));
      });
    } else {
      // The endpoint moving down passes `other`. A min passing a max starts an overlap on this
      // axis: the pair is added if the boxes now overlap on every axis (their bounds are final,
      // so the test is exact whatever order the axes are sorted in). A max passing a min ends
      // one: the pair goes. Each pair of endpoints swaps at most once per sort.
      for (int k = 0; k < 3; ++k)
        insertion_sort(k, [&](const Endpoint& moving, const Endpoint& other) {
          if (moving.is_max() == other.is_max() || moving.id() == other.id()) return;
          const ProxyPair pair = ordered(moving.id(), other.id());
          if (moving.is_max())
            pairs_.remove(pair);
          else if (overlaps(boxes_[pair.a], boxes_[pair.b]))
            pairs_.add(pair);
        });
    }
    recycle_removed();
  }

 private:
  PairSet pairs_;
  OpenList open_;
};

}  // namespace

std::unique_ptr<BroadPhase> make_seed_sap() { return std::make_unique<SeedSap>(); }
std::unique_ptr<BroadPhase> make_incremental_sap() { return std::make_unique<IncrementalSap>(); }

}  // namespace rtp::detail
