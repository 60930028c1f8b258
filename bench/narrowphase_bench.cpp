// The narrow phase on every engine (docs/narrowphase.md): nanoseconds per pair over a set of
// random pose pairs, rtp against Bullet's box-box detector and GJK/EPA on the same pairs in the
// same run, and lab 4.1's closest point on a triangle against Bullet's. Each peer's row carries
// how rtp agrees with it on that set (the validation tests hold the same comparison to zero
// unexplained disagreements).
//
//   build/bench/bench/narrowphase_bench --benchmark_out=narrowphase.json
//   --benchmark_out_format=json build/bench/bench/narrowphase_bench
//   --benchmark_filter='box-box/touching'
#include <benchmark/benchmark.h>
#include <physbench/narrowphase.h>

#include "paired.h"

#include <algorithm>
#include <chrono>
#include <map>
#include <numeric>
#include <random>
#include <sstream>

namespace {

using physbench::NarrowphaseRegime;
using physbench::NarrowphaseSet;
using physbench::NarrowphaseShapes;

// pairs per set: enough to mix every configuration, few enough to stay in the L2 cache with
// their shapes
constexpr std::size_t kPairs = 1024;
constexpr std::size_t kTriangleQueries = 4096;

// Each pass over a set (of pairs, or of triangle queries) visits it in a fresh order, one of
// kOrders permutations in turn: in the same order every pass, this core's branch predictor learns
// the set's outcomes (1,024 pairs, pass after pass), which no broad phase's pair list would let
// it do. Measured that way, rtp's box–box touching pairs took 62 ns and Bullet's separated pairs
// 40 ns; in a fresh order, 113 and 68 ns (docs/narrowphase.md).
constexpr std::size_t kOrders = 16;
const std::vector<std::vector<std::uint32_t>>& orders_of(std::size_t count) {
  static std::map<std::size_t, std::vector<std::vector<std::uint32_t>>> orders;
  auto it = orders.find(count);
  if (it == orders.end()) {
    std::mt19937_64 random(2027);
    std::vector<std::vector<std::uint32_t>> permutations(kOrders,
                                                         std::vector<std::uint32_t>(count));
    for (auto& order : permutations) {
      std::iota(order.begin(), order.end(), 0u);
      std::shuffle(order.begin(), order.end(), random);
    }
    it = orders.emplace(count, std::move(permutations)).first;
  }
  return it->second;
}

// the sets, built once each (a 32-vertex hull set takes a fraction of a second)
const NarrowphaseSet& set_of(NarrowphaseShapes shapes, NarrowphaseRegime regime) {
  static std::map<std::pair<NarrowphaseShapes, NarrowphaseRegime>, NarrowphaseSet> sets;
  auto it = sets.find({shapes, regime});
  if (it == sets.end())
    it = sets.emplace(std::pair{shapes, regime},
                      physbench::make_narrowphase_set(shapes, regime, kPairs, 2026))
             .first;
  return it->second;
}

void Pairs(benchmark::State& state, const physbench::NarrowphasePeerEntry& entry,
           NarrowphaseShapes shapes, NarrowphaseRegime regime) {
  const NarrowphaseSet& set = set_of(shapes, regime);
  auto engine = entry.create(set);
  const auto& orders = orders_of(set.pairs.size());
  std::size_t touching = 0, pass = 0;
  for (auto _ : state) {
    for (const std::uint32_t i : orders[pass++ % kOrders]) {
      const physbench::PeerContact c = engine->collide(i);
      touching += c.touching;
    }
  }
  state.SetItemsProcessed(int64_t(state.iterations() * set.pairs.size()));  // pairs/s
  state.counters["pairs"] = double(set.pairs.size());
  state.counters["touching_fraction"] =
      double(touching) / double(state.iterations() * set.pairs.size());
  // how rtp agrees with this engine on the set (a peer's rows only)
  if (entry.name.rfind("rtp/", 0) != 0) {
    const physbench::NarrowphaseAgreement a = physbench::compare_narrowphase(set, *engine);
    const double verdicts = double(a.pairs - a.in_band);
    state.counters["verdict_agreement"] = verdicts > 0 ? double(a.verdict_agree) / verdicts : 1.0;
    state.counters["compared_contacts"] = double(a.both_deep);
    state.counters["depth_agreement"] =
        a.both_deep ? double(a.depth_agree) / double(a.both_deep) : 1.0;
    state.counters["normal_agreement"] =
        a.both_deep ? double(a.normal_agree + a.normal_tie) / double(a.both_deep) : 1.0;
    state.counters["peer_refuted"] = double(a.peer_refuted);
    state.counters["unexplained"] = double(a.disagreements.size());
    state.counters["in_band"] = double(a.in_band);
  }
}

// rtp and one peer on the same set, in turn: each round times rtp over every pair of the set and
// then the peer over the same pairs, so both meet the machine in the same state (its speed
// drifts by up to 2x within minutes, which moved the ratio of interleaved medians by as much).
// Counters: ns per pair of each, peer ÷ rtp as the ratio of summed times, and its least and
// largest over kBlocks blocks of rounds (bench/paired.h).
constexpr int kPairedRounds = 200, kBlocks = 8;
void Paired(benchmark::State& state, const physbench::NarrowphasePeerEntry& ours,
            const physbench::NarrowphasePeerEntry& peer, NarrowphaseShapes shapes,
            NarrowphaseRegime regime) {
  const NarrowphaseSet& set = set_of(shapes, regime);
  auto a = ours.create(set), b = peer.create(set);
  using Clock = std::chrono::steady_clock;
  std::vector<double> ours_ns, peer_ns;
  ours_ns.reserve(kPairedRounds), peer_ns.reserve(kPairedRounds);
  std::size_t touching = 0;
  const auto pairs = double(set.pairs.size());
  const auto& orders = orders_of(set.pairs.size());
  std::size_t pass = 0;
  for (auto _ : state) {
    const std::vector<std::uint32_t>& order = orders[pass++ % kOrders];  // the same for both
    const auto t0 = Clock::now();
    for (const std::uint32_t i : order) touching += a->collide(i).touching;
    const auto t1 = Clock::now();
    for (const std::uint32_t i : order) touching += b->collide(i).touching;
    const auto t2 = Clock::now();
    ours_ns.push_back(std::chrono::duration<double, std::nano>(t1 - t0).count() / pairs);
    peer_ns.push_back(std::chrono::duration<double, std::nano>(t2 - t1).count() / pairs);
    state.SetIterationTime((ours_ns.back() + peer_ns.back()) * pairs * 1e-9);
  }
  benchmark::DoNotOptimize(touching);
  const physbench_bench::PairedRatio r = physbench_bench::paired_ratio(peer_ns, ours_ns, kBlocks);
  state.counters["rtp_ns"] = r.mean_denominator;
  state.counters["peer_ns"] = r.mean_numerator;
  physbench_bench::report_paired(state, "ratio", r);
}

void Triangles(benchmark::State& state, bool bullet) {
  static const std::vector<physbench::TriangleQuery> queries =
      physbench::make_triangle_queries(kTriangleQueries, 2026);
  auto batch = bullet ? physbench::make_bullet_triangle_batch(queries)
                      : physbench::make_rtp_triangle_batch(queries);
  const auto& orders = orders_of(queries.size());
  double sum = 0.0;
  std::size_t pass = 0;
  for (auto _ : state) benchmark::DoNotOptimize(sum += batch->run(orders[pass++ % kOrders]));
  state.SetItemsProcessed(int64_t(state.iterations() * queries.size()));
  state.counters["pairs"] = double(queries.size());
  if (bullet) {
    // the largest distance between Bullet's closest point (single precision) and rtp's
    auto ours = physbench::make_rtp_triangle_batch(queries);
    double worst = 0.0;
    for (std::size_t i = 0; i < queries.size(); ++i)
      worst = std::max(worst, (batch->closest(i) - ours->closest(i)).norm());
    state.counters["worst_point_difference"] = worst;
  }
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;

  std::vector<physbench::NarrowphasePeerEntry> engines = physbench::rtp_narrowphases();
  for (auto& e : physbench::narrowphase_peers()) engines.push_back(std::move(e));

  const std::pair<NarrowphaseShapes, NarrowphaseRegime> cases[] = {
      {NarrowphaseShapes::BoxBox, NarrowphaseRegime::Separated},
      {NarrowphaseShapes::BoxBox, NarrowphaseRegime::Touching},
      {NarrowphaseShapes::BoxBox, NarrowphaseRegime::Deep},
      {NarrowphaseShapes::HullHull, NarrowphaseRegime::Separated},
      {NarrowphaseShapes::HullHull, NarrowphaseRegime::Touching},
      {NarrowphaseShapes::HullHull, NarrowphaseRegime::Deep},
  };
  for (const auto& [shapes, regime] : cases) {
    // a set only to ask each engine whether it can run the kind; sets are built once, on use
    NarrowphaseSet probe;
    probe.shapes_kind = shapes;
    probe.regime = regime;
    for (const auto& entry : engines) {
      if (entry.unsupported(probe)) continue;
      const std::string name = "Pairs/" + probe.name() + "/" + entry.name;
      benchmark::RegisterBenchmark(name.c_str(), Pairs, entry, shapes, regime)
          ->Unit(benchmark::kMicrosecond)
          ->MinTime(0.1)
          ->Repetitions(5)
          ->ReportAggregatesOnly(false);
    }
  }
  // the box-box target, paired: rtp's closed-form test against Bullet's box-box detector
  const auto find = [&](const std::string& name) -> const physbench::NarrowphasePeerEntry* {
    for (const auto& e : engines)
      if (e.name == name) return &e;
    return nullptr;
  };
  const physbench::NarrowphasePeerEntry* ours = find("rtp/sat");
  const physbench::NarrowphasePeerEntry* box_box = find("bullet/box-box");
  for (const NarrowphaseRegime regime :
       {NarrowphaseRegime::Separated, NarrowphaseRegime::Touching, NarrowphaseRegime::Deep}) {
    if (!ours || !box_box) break;
    NarrowphaseSet probe;
    probe.shapes_kind = NarrowphaseShapes::BoxBox;
    probe.regime = regime;
    const std::string name = "Paired/" + probe.name() + "/" + box_box->name;
    benchmark::RegisterBenchmark(name.c_str(), Paired, *ours, *box_box, NarrowphaseShapes::BoxBox,
                                 regime)
        ->Iterations(kPairedRounds)
        ->UseManualTime()
        ->Unit(benchmark::kMicrosecond);
  }
  benchmark::RegisterBenchmark("Query/triangle/closest-point/rtp/voronoi", Triangles, false)
      ->Unit(benchmark::kMicrosecond)
      ->MinTime(0.1)
      ->Repetitions(5);
  if (physbench::make_bullet_triangle_batch({}))
    benchmark::RegisterBenchmark("Query/triangle/closest-point/bullet/voronoi-simplex", Triangles,
                                 true)
        ->Unit(benchmark::kMicrosecond)
        ->MinTime(0.1)
        ->Repetitions(5);

  for (const auto& entry : engines) {
    std::string settings;
    for (const auto& s : entry.settings)
      settings += (settings.empty() ? "" : "; ") + s.name + ": " + s.value + " (" + s.why + ")";
    benchmark::AddCustomContext("settings " + entry.name, entry.version + "; " + settings);
  }
  const physbench::NarrowphaseTolerances t;
  std::ostringstream tolerances;
  tolerances << "verdict band " << t.verdict_band << " m; depth " << t.depth_absolute << " m + "
             << 100 * t.depth_relative << " %; normal " << t.normal_degrees
             << " degrees or a tie; contact points on both surfaces within " << t.surface << " m";
  benchmark::AddCustomContext("tolerances", tolerances.str());
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
