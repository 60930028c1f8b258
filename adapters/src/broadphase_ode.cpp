// ODE's broad phases on the broadphase scene: dSweepAndPruneSpace and dHashSpace holding one
// body-less box geom per box; dSpaceCollide reports the pairs whose bounds overlap, and nothing
// else runs (no dCollide, no contacts).
#include <ode/ode.h>

#include <cstdint>

#include "physbench/broadphase.h"

namespace physbench {

namespace {

// ODE's initialisation is counted: this one is the broad phases' own
struct OdeBroadphaseLibrary {
  OdeBroadphaseLibrary() { dInitODE2(0); }
  ~OdeBroadphaseLibrary() { dCloseODE(); }
};

enum class OdeKind { SweepAndPrune, Hash };

class OdeBroadphase final : public BroadphaseEngine {
 public:
  explicit OdeBroadphase(OdeKind kind) : kind_(kind) { static OdeBroadphaseLibrary library; }
  ~OdeBroadphase() override { reset(); }

  void build(const std::vector<rtp::Aabb>& boxes) override {
    reset();
    space_ = kind_ == OdeKind::SweepAndPrune ? dSweepAndPruneSpaceCreate(nullptr, dSAP_AXES_XYZ)
                                             : dHashSpaceCreate(nullptr);
    for (std::size_t i = 0; i < boxes.size(); ++i) {
      const rtp::Aabb& b = boxes[i];
      const dGeomID geom =
          dCreateBox(space_, b.max[0] - b.min[0], b.max[1] - b.min[1], b.max[2] - b.min[2]);
      dGeomSetData(geom, reinterpret_cast<void*>(static_cast<std::uintptr_t>(i)));
      geoms_.push_back(geom);
    }
    update(boxes);
  }

  std::size_t update(const std::vector<rtp::Aabb>& boxes) override {
    // the scene's boxes are axis-aligned and keep their size: a box geom at the centre has
    // exactly these bounds
    for (std::size_t i = 0; i < boxes.size(); ++i) {
      const rtp::Aabb& b = boxes[i];
      dGeomSetPosition(geoms_[i], 0.5 * (double(b.min[0]) + b.max[0]),
                       0.5 * (double(b.min[1]) + b.max[1]), 0.5 * (double(b.min[2]) + b.max[2]));
    }
    pairs_.clear();
    dSpaceCollide(space_, this, &OdeBroadphase::near_callback);
    return pairs_.size();
  }

  std::vector<rtp::ProxyPair> pairs() const override { return pairs_; }

 private:
  static void near_callback(void* data, dGeomID o1, dGeomID o2) {
    auto* self = static_cast<OdeBroadphase*>(data);
    const auto a = std::uint32_t(reinterpret_cast<std::uintptr_t>(dGeomGetData(o1)));
    const auto b = std::uint32_t(reinterpret_cast<std::uintptr_t>(dGeomGetData(o2)));
    self->pairs_.push_back({std::min(a, b), std::max(a, b)});
  }
  void reset() {
    if (space_) dSpaceDestroy(space_);  // destroys its geoms (cleanup mode on by default)
    space_ = nullptr;
    geoms_.clear();
  }

  OdeKind kind_;
  dSpaceID space_ = nullptr;
  std::vector<dGeomID> geoms_;
  std::vector<rtp::ProxyPair> pairs_;
};

BroadphaseEntry ode_entry(OdeKind kind, std::string name, Setting space) {
  BroadphaseEntry e;
  e.name = "ode/" + name;
  e.engine = "ode";
  e.version = std::string(PHYSBENCH_ODE_VERSION) + " (" + dGetConfiguration() + ")";
  e.settings = {std::move(space),
                {"geoms", "one body-less dBox per box, positioned each frame",
                 "only the broad phase runs: dSpaceCollide's callback records the pair"}};
  e.unsupported = [](const BroadphaseScene&) { return std::optional<std::string>(); };
  e.create = [kind] { return std::make_unique<OdeBroadphase>(kind); };
  return e;
}

}  // namespace

std::vector<BroadphaseEntry> ode_broadphases() {
  return {
      ode_entry(OdeKind::SweepAndPrune, "sap",
                {"space", "dSweepAndPruneSpace, axes XYZ", "ODE's sweep and prune"}),
      ode_entry(OdeKind::Hash, "hash",
                {"space", "dHashSpace, default levels (2⁻³ … 2¹⁰ m cells)", "ODE's hashed grid"})};
}

}  // namespace physbench
