#include "physbench/broadphase.h"

#include <algorithm>
#include <cmath>

namespace physbench {

std::string name_of(BroadphaseMotion motion) {
  switch (motion) {
    case BroadphaseMotion::Coherent:
      return "coherent";
    case BroadphaseMotion::Reshuffled:
      return "reshuffled";
    case BroadphaseMotion::Line:
      return "line";
    case BroadphaseMotion::AllOverlapping:
      return "all-overlapping";
  }
  return "?";
}

std::optional<BroadphaseMotion> broadphase_motion_named(const std::string& name) {
  for (BroadphaseMotion m : {BroadphaseMotion::Coherent, BroadphaseMotion::Reshuffled,
                             BroadphaseMotion::Line, BroadphaseMotion::AllOverlapping})
    if (name_of(m) == name) return m;
  return std::nullopt;
}

namespace {

// a unit box (the scene's only size) about a centre
rtp::Aabb unit_box(float x, float y, float z) {
  return {{x - 0.5f, y - 0.5f, z - 0.5f}, {x + 0.5f, y + 0.5f, z + 0.5f}};
}

}  // namespace

BroadphaseFrames::BroadphaseFrames(const BroadphaseScene& scene)
    : scene_(scene), random_(scene.seed) {
  const double n = double(std::max<std::size_t>(scene.count, 1));
  switch (scene.motion) {
    case BroadphaseMotion::Coherent:
    case BroadphaseMotion::Reshuffled:
      // unit boxes overlap when their centres are within 1 on every axis: with centres uniform
      // over a side W that is (2/W)^d of the other boxes, so W = 2 (n / overlap)^(1/d)
      side_ = 2.0 * std::pow(n / scene.mean_overlap, scene.planar ? 0.5 : 1.0 / 3.0);
      break;
    case BroadphaseMotion::Line:
      side_ = 0.5 * n;  // centres half a box apart: each overlaps two neighbours on each side
      break;
    case BroadphaseMotion::AllOverlapping:
      side_ = 0.5;  // centres within half a box of each other on every axis
      break;
  }
  boxes_.resize(scene.count);
  velocity_.resize(scene.count);
  std::uniform_real_distribution<float> step(-float(scene.speed), float(scene.speed));
  for (auto& v : velocity_) {
    v = {step(random_), step(random_), scene.planar ? 0.0f : step(random_)};
    if (scene.motion == BroadphaseMotion::Line) v[1] = v[2] = 0.0f;
  }
  place_all();
}

void BroadphaseFrames::place_all() {
  std::uniform_real_distribution<float> along(0.0f, float(side_));
  for (std::size_t i = 0; i < boxes_.size(); ++i) {
    if (scene_.motion == BroadphaseMotion::Line) {
      boxes_[i] = unit_box(0.5f * float(i), 0.0f, 0.0f);
      continue;
    }
    const float x = along(random_), y = along(random_), z = scene_.planar ? 0.0f : along(random_);
    boxes_[i] = unit_box(x, y, z);
  }
}

void BroadphaseFrames::advance() {
  if (scene_.motion == BroadphaseMotion::Reshuffled) {
    place_all();
    return;
  }
  // every centre moves by its velocity and reflects off the walls of [0, side]
  const float side = float(side_);
  for (std::size_t i = 0; i < boxes_.size(); ++i) {
    rtp::Aabb& b = boxes_[i];
    for (int k = 0; k < 3; ++k) {
      float c = 0.5f * (b.min[k] + b.max[k]) + velocity_[i][k];
      if (c < 0.0f || c > side) {
        c = c < 0.0f ? -c : 2.0f * side - c;
        velocity_[i][k] = -velocity_[i][k];
      }
      b.min[k] = c - 0.5f;
      b.max[k] = c + 0.5f;
    }
  }
}

std::vector<rtp::ProxyPair> exact_pairs(const std::vector<rtp::Aabb>& boxes) {
  std::vector<std::uint32_t> order(boxes.size());
  for (std::uint32_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(),
            [&](std::uint32_t a, std::uint32_t b) { return boxes[a].min[0] < boxes[b].min[0]; });
  std::vector<rtp::ProxyPair> pairs;
  for (std::size_t i = 0; i < order.size(); ++i)
    for (std::size_t j = i + 1;
         j < order.size() && boxes[order[j]].min[0] <= boxes[order[i]].max[0]; ++j)
      if (rtp::overlaps(boxes[order[i]], boxes[order[j]]))
        pairs.push_back({std::min(order[i], order[j]), std::max(order[i], order[j])});
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

PairAgreement compare_pairs(std::vector<rtp::ProxyPair> reported,
                            const std::vector<rtp::ProxyPair>& exact) {
  std::sort(reported.begin(), reported.end());
  PairAgreement agreement;
  agreement.exact = exact.size();
  agreement.reported = reported.size();
  std::vector<rtp::ProxyPair> difference;
  std::set_difference(exact.begin(), exact.end(), reported.begin(), reported.end(),
                      std::back_inserter(difference));
  agreement.missing = difference.size();
  difference.clear();
  std::set_difference(reported.begin(), reported.end(), exact.begin(), exact.end(),
                      std::back_inserter(difference));
  agreement.extra = difference.size();  // duplicates in `reported` count as extra too
  return agreement;
}

// ---------------------------------------------------------------------------------------------
// rtp's variants

namespace {

class RtpBroadphase final : public BroadphaseEngine {
 public:
  explicit RtpBroadphase(rtp::BroadPhaseKind kind) : kind_(kind) {}
  void build(const std::vector<rtp::Aabb>& boxes) override {
    phase_ = rtp::make_broad_phase(kind_);
    for (const rtp::Aabb& b : boxes) phase_->add(b);  // handles are 0 … n−1, the box indices
    phase_->update();
  }
  std::size_t update(const std::vector<rtp::Aabb>& boxes) override {
    for (std::size_t i = 0; i < boxes.size(); ++i) phase_->move(rtp::ProxyId(i), boxes[i]);
    phase_->update();
    return phase_->pairs().size();
  }
  std::vector<rtp::ProxyPair> pairs() const override { return phase_->pairs(); }

 private:
  rtp::BroadPhaseKind kind_;
  std::unique_ptr<rtp::BroadPhase> phase_;
};

}  // namespace

std::vector<BroadphaseEntry> rtp_broadphases() {
  std::vector<BroadphaseEntry> entries;
  for (rtp::BroadPhaseKind kind :
       {rtp::BroadPhaseKind::SeedSap, rtp::BroadPhaseKind::IncrementalSap,
        rtp::BroadPhaseKind::BoxPruning}) {
    BroadphaseEntry e;
    e.name = "rtp/" + std::string(rtp::name_of(kind));
    e.engine = "rtp";
    e.version = "this build";
    e.settings = {{"bounds", "exact", "no fattening: the pair set is exact"}};
    if (kind == rtp::BroadPhaseKind::SeedSap)
      e.unsupported = [](const BroadphaseScene& s) -> std::optional<std::string> {
        if (s.count > rtp::kSeedSapMaxProxies)
          return "unsupported: the seed's pair table takes n²/2 bytes (" +
                 std::to_string(s.count * (s.count - 1) / 2) + " at this count)";
        return std::nullopt;
      };
    else
      e.unsupported = [](const BroadphaseScene&) { return std::optional<std::string>(); };
    e.create = [kind] { return std::make_unique<RtpBroadphase>(kind); };
    entries.push_back(std::move(e));
  }
  return entries;
}

// engines this build leaves out have no broad phases
#ifndef PHYSBENCH_HAVE_BULLET
std::vector<BroadphaseEntry> bullet_broadphases() { return {}; }
#endif
#ifndef PHYSBENCH_HAVE_ODE
std::vector<BroadphaseEntry> ode_broadphases() { return {}; }
#endif
#ifndef PHYSBENCH_HAVE_BOX2D
std::vector<BroadphaseEntry> box2d_broadphases() { return {}; }
#endif

std::vector<BroadphaseEntry> broadphase_engines() {
  std::vector<BroadphaseEntry> all;
  for (auto list :
       {rtp_broadphases(), bullet_broadphases(), ode_broadphases(), box2d_broadphases()})
    for (auto& e : list) all.push_back(std::move(e));
  return all;
}

}  // namespace physbench
