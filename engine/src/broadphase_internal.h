// What rtp's broad phases share: boxes by handle with the changes since the last update
// (ProxyStore), the ordered pair, and a factory per variant. broadphase.cpp has the bounds, the
// brute-force reference and make_broad_phase; broadphase_sap.cpp the seed's sweep and prune and the
// incremental one, over sorted axes; broadphase_box_pruning.cpp box pruning. The design is in
// rtp/broadphase.h.
#pragma once

#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "rtp/broadphase.h"

namespace rtp::detail {

inline ProxyPair ordered(ProxyId a, ProxyId b) { return a < b ? ProxyPair{a, b} : ProxyPair{b, a}; }

// Boxes by handle: bounds, whether live, and the handles free for reuse. Changes are recorded
// here and applied by the variant's update().
class ProxyStore : public BroadPhase {
 public:
  ProxyId allocate(const Aabb& box) {
    ProxyId id;
    if (!free_.empty()) {
      id = free_.back();
      free_.pop_back();
      boxes_[id] = box;
      alive_[id] = 1;
    } else {
      id = ProxyId(boxes_.size());
      boxes_.push_back(box);
      alive_.push_back(1);
    }
    added_.push_back(id);
    return id;
  }
  void set(ProxyId id, const Aabb& box) {
    check(id);
    boxes_[id] = box;
  }
  void release(ProxyId id) {
    check(id);
    alive_[id] = 0;
    removed_.push_back(id);
  }
  bool alive(ProxyId id) const { return alive_[id] != 0; }
  const Aabb& box(ProxyId id) const { return boxes_[id]; }
  std::size_t capacity() const { return boxes_.size(); }

 protected:
  void check(ProxyId id) const {
    if (id >= boxes_.size() || !alive_[id])
      throw std::out_of_range("rtp broad phase: no live box with handle " + std::to_string(id));
  }
  // handles of boxes removed since the last update become reusable only after it, so a pair
  // with a removed box is never confused with its successor
  void recycle_removed() {
    free_.insert(free_.end(), removed_.begin(), removed_.end());
    removed_.clear();
  }

  std::vector<Aabb> boxes_;
  std::vector<std::uint8_t> alive_;
  std::vector<ProxyId> free_, added_, removed_;
};

std::unique_ptr<BroadPhase> make_seed_sap();
std::unique_ptr<BroadPhase> make_incremental_sap();
std::unique_ptr<BroadPhase> make_box_pruning();

}  // namespace rtp::detail
