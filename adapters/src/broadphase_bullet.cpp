// Bullet's broad phases on the broadphase scene: btDbvtBroadphase (its default) and
// bt32BitAxisSweep3 with and without its ray-cast accelerator, each with proxies only — no
// collision objects, no narrow phase.
#include <btBulletCollisionCommon.h>

#include <cstdint>

#include "bullet_version.h"
#include "physbench/broadphase.h"

namespace physbench {

namespace {

btVector3 lower(const rtp::Aabb& b) { return btVector3(b.min[0], b.min[1], b.min[2]); }
btVector3 upper(const rtp::Aabb& b) { return btVector3(b.max[0], b.max[1], b.max[2]); }

enum class BulletKind { Dbvt, Sweep, SweepWithAccelerator };

class BulletBroadphase final : public BroadphaseEngine {
 public:
  explicit BulletBroadphase(BulletKind kind)
      : kind_(kind), dispatcher_(std::make_unique<btCollisionDispatcher>(&configuration_)) {}

  ~BulletBroadphase() override { reset(); }

  void build(const std::vector<rtp::Aabb>& boxes) override {
    reset();
    if (kind_ == BulletKind::Dbvt) {
      broadphase_ = std::make_unique<btDbvtBroadphase>();
    } else {
      // the sweep quantises into a fixed world box: the scene's boxes with a margin, and
      // handles for exactly this many boxes (the default reserves 1.5 million)
      btVector3 lo(BT_LARGE_FLOAT, BT_LARGE_FLOAT, BT_LARGE_FLOAT), hi = -lo;
      for (const rtp::Aabb& b : boxes) {
        lo.setMin(lower(b));
        hi.setMax(upper(b));
      }
      const btVector3 margin(2, 2, 2);
      broadphase_ = std::make_unique<bt32BitAxisSweep3>(
          lo - margin, hi + margin, unsigned(boxes.size() + 1), nullptr,
          kind_ == BulletKind::Sweep /* disableRaycastAccelerator */);
    }
    for (std::size_t i = 0; i < boxes.size(); ++i)
      proxies_.push_back(broadphase_->createProxy(
          lower(boxes[i]), upper(boxes[i]), BOX_SHAPE_PROXYTYPE,
          reinterpret_cast<void*>(static_cast<std::uintptr_t>(i)), 1, -1, dispatcher_.get()));
    broadphase_->calculateOverlappingPairs(dispatcher_.get());
  }

  std::size_t update(const std::vector<rtp::Aabb>& boxes) override {
    for (std::size_t i = 0; i < boxes.size(); ++i)
      broadphase_->setAabb(proxies_[i], lower(boxes[i]), upper(boxes[i]), dispatcher_.get());
    broadphase_->calculateOverlappingPairs(dispatcher_.get());
    return std::size_t(broadphase_->getOverlappingPairCache()->getNumOverlappingPairs());
  }

  std::vector<rtp::ProxyPair> pairs() const override {
    btOverlappingPairCache* cache = broadphase_->getOverlappingPairCache();
    const btBroadphasePair* array = cache->getOverlappingPairArrayPtr();
    std::vector<rtp::ProxyPair> out;
    for (int p = 0; p < cache->getNumOverlappingPairs(); ++p) {
      const auto a =
          std::uint32_t(reinterpret_cast<std::uintptr_t>(array[p].m_pProxy0->m_clientObject));
      const auto b =
          std::uint32_t(reinterpret_cast<std::uintptr_t>(array[p].m_pProxy1->m_clientObject));
      out.push_back({std::min(a, b), std::max(a, b)});
    }
    return out;
  }

 private:
  // Bullet's broad phases leave their proxies to the caller (btCollisionWorld destroys them)
  void reset() {
    for (btBroadphaseProxy* proxy : proxies_) broadphase_->destroyProxy(proxy, dispatcher_.get());
    proxies_.clear();
    broadphase_.reset();
  }

  BulletKind kind_;
  btDefaultCollisionConfiguration configuration_;
  std::unique_ptr<btCollisionDispatcher> dispatcher_;
  std::unique_ptr<btBroadphaseInterface> broadphase_;
  std::vector<btBroadphaseProxy*> proxies_;
};

BroadphaseEntry bullet_entry(BulletKind kind, std::string name, std::vector<Setting> settings,
                             std::size_t max_count, std::string why_limited) {
  BroadphaseEntry e;
  e.name = "bullet/" + name;
  e.engine = "bullet";
  e.version = bullet_version("float");
  settings.push_back({"proxies", "createProxy per box, group 1, mask −1; no collision objects",
                      "only the broad phase runs"});
  e.settings = std::move(settings);
  e.unsupported = [max_count, why_limited](const BroadphaseScene& s) -> std::optional<std::string> {
    if (s.count > max_count)
      return "unsupported at " + std::to_string(s.count) + " boxes: " + why_limited;
    return std::nullopt;
  };
  e.create = [kind] { return std::make_unique<BulletBroadphase>(kind); };
  return e;
}

}  // namespace

std::vector<BroadphaseEntry> bullet_broadphases() {
  // the sweep inserts each proxy by walking its sorted axes: building 50k boxes takes about a
  // minute here, longer than the benchmark's budget for one case
  const std::string slow_build = "inserting each box walks the sorted axes (O(n) per insert)";
  return {
      bullet_entry(BulletKind::Dbvt, "dbvt",
                   {{"broadphase", "btDbvtBroadphase", "Bullet's default"}}, SIZE_MAX, ""),
      bullet_entry(BulletKind::Sweep, "axis-sweep-32",
                   {{"broadphase", "bt32BitAxisSweep3, ray-cast accelerator off",
                     "the sweep alone; world box = the scene's bounds + 2 m, handles = box count"}},
                   20000, slow_build),
      bullet_entry(BulletKind::SweepWithAccelerator, "axis-sweep-32-raycast",
                   {{"broadphase", "bt32BitAxisSweep3, ray-cast accelerator on (its default)",
                     "world box = the scene's bounds + 2 m, handles = box count"}},
                   20000, slow_build),
  };
}

}  // namespace physbench
