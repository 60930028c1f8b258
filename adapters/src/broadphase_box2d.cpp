// Box2D's broad phase (b2BroadPhase over its dynamic tree) on the planar broadphase scene.
// b2BroadPhase::UpdatePairs reports only pairs that involve a box whose fattened bounds moved;
// the persistent pair set is what Box2D's contact manager keeps: pairs are added as reported and
// dropped when their fattened bounds stop overlapping (b2ContactManager::Collide). That
// bookkeeping is done here the same way, without contacts.
#include <box2d/box2d.h>

#include <cstdint>
#include <unordered_set>

#include "physbench/broadphase.h"

namespace physbench {

namespace {

b2AABB planar(const rtp::Aabb& b) {
  b2AABB a;
  a.lowerBound.Set(b.min[0], b.min[1]);
  a.upperBound.Set(b.max[0], b.max[1]);
  return a;
}

class Box2dBroadphase final : public BroadphaseEngine {
 public:
  void build(const std::vector<rtp::Aabb>& boxes) override {
    broadphase_ = std::make_unique<b2BroadPhase>();
    proxies_.clear();
    pairs_.clear();
    keys_.clear();
    for (std::size_t i = 0; i < boxes.size(); ++i)
      proxies_.push_back(broadphase_->CreateProxy(
          planar(boxes[i]), reinterpret_cast<void*>(static_cast<std::uintptr_t>(i))));
    previous_ = boxes;
    broadphase_->UpdatePairs(this);
  }

  std::size_t update(const std::vector<rtp::Aabb>& boxes) override {
    for (std::size_t i = 0; i < boxes.size(); ++i) {
      const b2Vec2 displacement(boxes[i].min[0] - previous_[i].min[0],
                                boxes[i].min[1] - previous_[i].min[1]);
      broadphase_->MoveProxy(proxies_[i], planar(boxes[i]), displacement);
    }
    previous_ = boxes;
    // drop the pairs whose fattened bounds no longer overlap, as the contact manager does
    std::erase_if(pairs_, [&](const rtp::ProxyPair& p) {
      if (broadphase_->TestOverlap(proxies_[p.a], proxies_[p.b])) return false;
      keys_.erase(p.key());
      return true;
    });
    broadphase_->UpdatePairs(this);
    return pairs_.size();
  }

  std::vector<rtp::ProxyPair> pairs() const override { return pairs_; }

  // called by b2BroadPhase::UpdatePairs
  void AddPair(void* user_a, void* user_b) {
    const auto a = std::uint32_t(reinterpret_cast<std::uintptr_t>(user_a));
    const auto b = std::uint32_t(reinterpret_cast<std::uintptr_t>(user_b));
    const rtp::ProxyPair p{std::min(a, b), std::max(a, b)};
    if (keys_.insert(p.key()).second) pairs_.push_back(p);
  }

 private:
  std::unique_ptr<b2BroadPhase> broadphase_;
  std::vector<std::int32_t> proxies_;
  std::vector<rtp::Aabb> previous_;
  std::vector<rtp::ProxyPair> pairs_;
  std::unordered_set<std::uint64_t> keys_;
};

}  // namespace

std::vector<BroadphaseEntry> box2d_broadphases() {
  BroadphaseEntry e;
  e.name = "box2d/dynamic-tree";
  e.engine = "box2d";
  e.version = std::to_string(b2_version.major) + "." + std::to_string(b2_version.minor) + "." +
              std::to_string(b2_version.revision);
  e.settings = {{"broadphase", "b2BroadPhase (dynamic tree), default margin",
                 "Box2D's only broad phase; boxes' x and y bounds"},
                {"pair set", "added from UpdatePairs, dropped when TestOverlap fails",
                 "what b2ContactManager does with the pairs, without contacts"}};
  e.unsupported = [](const BroadphaseScene& s) -> std::optional<std::string> {
    if (!s.planar) return "unsupported: Box2D is a 2D engine (the planar scene runs on it)";
    return std::nullopt;
  };
  e.create = [] { return std::make_unique<Box2dBroadphase>(); };
  return {std::move(e)};
}

}  // namespace physbench
