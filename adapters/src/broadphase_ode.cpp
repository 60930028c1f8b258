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
    if (kind_ == OdeKind::Hash) dHashSpaceSetLevels(space_, -1, 2);  // see the settings table
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

// one update of the hash space (levels −1 … 2) takes 1.06 s at 5·10⁴ boxes here (3.75 s at 10⁵):
// beyond this the benchmark's budget goes to the broad phases that scale
constexpr std::size_t kHashLimit = 10000;

BroadphaseEntry ode_entry(OdeKind kind, std::string name, Setting space,
                          std::size_t limit = SIZE_MAX) {
  BroadphaseEntry e;
  e.name = "ode/" + name;
  e.engine = "ode";
  e.version = std::string(PHYSBENCH_ODE_VERSION) + " (" + dGetConfiguration() + ")";
  e.settings = {std::move(space),
                {"geoms", "one body-less dBox per box, positioned each frame",
                 "only the broad phase runs: dSpaceCollide's callback records the pair"}};
  e.unsupported = [limit](const BroadphaseScene& s) -> std::optional<std::string> {
    if (s.count > limit)
      return "not run above " + std::to_string(limit) +
             " boxes: one update takes seconds there (1.06 s at 5·10⁴ measured here)";
    return std::nullopt;
  };
  e.create = [kind] { return std::make_unique<OdeBroadphase>(kind); };
  return e;
}

}  // namespace

std::vector<BroadphaseEntry> ode_broadphases() {
  return {ode_entry(OdeKind::SweepAndPrune, "sap",
                    {"space", "dSweepAndPruneSpace, axes XYZ", "ODE's sweep and prune"}),
          ode_entry(OdeKind::Hash, "hash",
                    {"space", "dHashSpace, levels −1 … 2 (cells of 0.5 … 4 m)",
                     "cells sized to the scene's unit boxes, as ODE's manual advises; the default "
                     "levels (−3 … 10) were 4x slower at 10⁴ boxes"},
                    kHashLimit)};
}

}  // namespace physbench
