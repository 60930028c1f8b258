// The broadphase scene on every engine's broad phase (docs/broadphase.md):
// microseconds per update and pairs/s, with each engine's pair set checked against the exact one
// on the frames before timing (missing pairs, extra pairs as counters), and the time to build
// from scratch.
//
//   build/bench/bench/broadphase_bench --benchmark_out=broadphase.json --benchmark_out_format=json
//   build/bench/bench/broadphase_bench --benchmark_filter='coherent/10000/'
#include <benchmark/benchmark.h>
#include <physbench/broadphase.h>

#include "paired.h"

#include <algorithm>
#include <chrono>
#include <map>

namespace {

using physbench::BroadphaseMotion;
using physbench::BroadphaseScene;

// frames checked against the exact pair set before the timed loop, per case
constexpr int kCheckedFrames = 5;
// the timed loop replays this many precomputed frames forward and back (still coherent), so
// generating the motion is not timed
constexpr int kTimedFrames = 32;

std::string case_name(const BroadphaseScene& s) {
  return (s.planar ? "planar-" : "") + physbench::name_of(s.motion) + "/" + std::to_string(s.count);
}

// One case made ready: the engine built, its pairs checked, the frames to replay. Google
// Benchmark calls a benchmark several times (to size its iteration count, then per repetition,
// which bench.sh interleaves with every other engine's); each case is prepared on its first call
// and kept for the rest of the run, so the build and the exact pair sets (the slow part at 10⁵
// boxes) are done once, and an engine meets each repetition in the state its last one left it
// (Bullet's dbvt keeps improving its tree update by update; a fresh build each time would time
// it cold).
struct PreparedCase {
  std::unique_ptr<physbench::BroadphaseEngine> engine;
  std::vector<std::vector<rtp::Aabb>> replay;
  std::size_t frame = 0;
  double missing = 0, extra = 0, exact = 0;
};

PreparedCase& prepare(const physbench::BroadphaseEntry& entry, const BroadphaseScene& scene) {
  static std::map<std::string, PreparedCase> cases;
  const std::string key = entry.name + "@" + case_name(scene);
  if (auto found = cases.find(key); found != cases.end()) return found->second;
  PreparedCase& prepared = cases[key];
  physbench::BroadphaseFrames frames(scene);
  prepared.engine = entry.create();
  prepared.engine->build(frames.boxes());

  // the pair set, against the exact one, frame by frame
  for (int f = 0; f < kCheckedFrames; ++f) {
    frames.advance();
    prepared.engine->update(frames.boxes());
    const auto agreement =
        physbench::compare_pairs(prepared.engine->pairs(), physbench::exact_pairs(frames.boxes()));
    prepared.missing += double(agreement.missing);
    prepared.extra += double(agreement.extra);
    prepared.exact += double(agreement.exact);
  }
  for (int f = 0; f < kTimedFrames; ++f) {
    frames.advance();
    prepared.replay.push_back(frames.boxes());
  }
  for (int f = kTimedFrames - 2; f > 0; --f)
    prepared.replay.push_back(prepared.replay[std::size_t(f)]);
  return prepared;
}

void Update(benchmark::State& state, const physbench::BroadphaseEntry& entry,
            const BroadphaseScene& scene) {
  PreparedCase& c = prepare(entry, scene);
  std::size_t pairs = 0;
  for (auto _ : state) {
    pairs += c.engine->update(c.replay[c.frame]);
    c.frame = (c.frame + 1) % c.replay.size();
  }
  state.SetItemsProcessed(int64_t(pairs));  // pairs/s
  state.counters["boxes"] = double(scene.count);
  state.counters["exact_pairs"] = c.exact / kCheckedFrames;
  state.counters["missing_pairs"] = c.missing;  // over the checked frames: must be 0
  state.counters["extra_pairs_fraction"] = c.exact > 0 ? c.extra / c.exact : 0.0;
  state.counters["checked_frames"] = kCheckedFrames;
}

void Build(benchmark::State& state, const physbench::BroadphaseEntry& entry,
           const BroadphaseScene& scene) {
  const physbench::BroadphaseFrames frames(scene);
  for (auto _ : state) {
    auto engine = entry.create();
    engine->build(frames.boxes());
    state.PauseTiming();  // tearing down is not building
    engine.reset();
    state.ResumeTiming();
  }
  state.counters["boxes"] = double(scene.count);
}

// rtp's box pruning and one peer on the same case, updated in turn: each round times one update
// of each, back to back, so both see the same state of the machine (a slow spell of seconds, a
// neighbour's load) and the ratio of their times is free of it. A peer's update can cost very
// different amounts from frame to frame (dbvt's time over rtp's, round by round, ran from 0.6x at
// the 10th percentile to 21x at the 90th), so what is compared is time summed over rounds: the
// ratio of sums over all rounds, and its spread as the least and largest ratio of sums over
// kBlocks consecutive blocks of rounds. Counters in µs per update and peer ÷ rtp.
constexpr int kPairedRounds = 400, kBlocks = 8;
void Paired(benchmark::State& state, const physbench::BroadphaseEntry& ours,
            const physbench::BroadphaseEntry& peer, const BroadphaseScene& scene) {
  PreparedCase& a = prepare(ours, scene);
  PreparedCase& b = prepare(peer, scene);
  using Clock = std::chrono::steady_clock;
  std::vector<double> ours_us, peer_us;
  ours_us.reserve(kPairedRounds), peer_us.reserve(kPairedRounds);
  for (auto _ : state) {
    const auto t0 = Clock::now();
    a.engine->update(a.replay[a.frame]);
    const auto t1 = Clock::now();
    b.engine->update(b.replay[b.frame]);
    const auto t2 = Clock::now();
    a.frame = (a.frame + 1) % a.replay.size();
    b.frame = (b.frame + 1) % b.replay.size();
    ours_us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
    peer_us.push_back(std::chrono::duration<double, std::micro>(t2 - t1).count());
    state.SetIterationTime((ours_us.back() + peer_us.back()) * 1e-6);
  }
  const physbench_bench::PairedRatio r = physbench_bench::paired_ratio(peer_us, ours_us, kBlocks);
  state.counters["boxes"] = double(scene.count);
  state.counters["rtp_us"] = r.mean_denominator;
  state.counters["peer_us"] = r.mean_numerator;
  physbench_bench::report_paired(state, "ratio", r);
}

BroadphaseScene scene_of(BroadphaseMotion motion, std::size_t count, bool planar = false) {
  BroadphaseScene s;
  s.motion = motion;
  s.count = count;
  s.planar = planar;
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;

  // the default suite: coherent motion over the counts, then the hard cases at fixed counts
  std::vector<BroadphaseScene> updates;
  for (std::size_t n : {1000, 10000, 50000, 100000})
    updates.push_back(scene_of(BroadphaseMotion::Coherent, n));
  // reshuffled at 2000: the sweeps that keep axes sorted (rtp's incremental SAP, Bullet's
  // axis sweeps) cost O(n²) per update without coherence — seconds per update at 10⁴
  updates.push_back(scene_of(BroadphaseMotion::Reshuffled, 2000));
  updates.push_back(scene_of(BroadphaseMotion::Line, 10000));
  updates.push_back(scene_of(BroadphaseMotion::AllOverlapping, 1000));
  updates.push_back(scene_of(BroadphaseMotion::Coherent, 10000, /*planar=*/true));
  const BroadphaseScene build = scene_of(BroadphaseMotion::Coherent, 50000);

  const std::vector<physbench::BroadphaseEntry> entries = physbench::broadphase_engines();
  for (const auto& scene : updates)
    for (const auto& entry : entries) {
      if (auto why = entry.unsupported(scene)) {
        // visible in the output, so a missing engine is never silent
        std::fprintf(stderr, "broadphase_bench: %s on %s: %s\n", entry.name.c_str(),
                     case_name(scene).c_str(), why->c_str());
        continue;
      }
      benchmark::RegisterBenchmark(("Update/" + case_name(scene) + "/" + entry.name).c_str(),
                                   Update, entry, scene)
          ->Unit(benchmark::kMicrosecond)
          ->UseRealTime()
          ->MinTime(0.1)
          ->Repetitions(5)
          ->ReportAggregatesOnly(true);
    }
  // the target case (10⁴ coherent boxes): rtp's box pruning paired with every peer, round by round
  const BroadphaseScene target = scene_of(BroadphaseMotion::Coherent, 10000);
  const auto ours = std::find_if(entries.begin(), entries.end(),
                                 [](const auto& e) { return e.name == "rtp/box-pruning"; });
  if (ours != entries.end())
    for (const auto& entry : entries) {
      if (entry.engine == "rtp" || entry.unsupported(target)) continue;
      benchmark::RegisterBenchmark(
          ("Paired/" + case_name(target) + "/" + entry.name).c_str(), Paired, *ours, entry, target)
          ->Unit(benchmark::kMicrosecond)
          ->UseManualTime()
          ->Iterations(kPairedRounds);
    }
  for (const auto& entry : entries)
    if (!entry.unsupported(build))
      benchmark::RegisterBenchmark(("Build/" + case_name(build) + "/" + entry.name).c_str(), Build,
                                   entry, build)
          ->Unit(benchmark::kMillisecond)
          ->UseRealTime()
          ->MinTime(0.1);

  for (const auto& entry : entries) {
    std::string settings;
    for (const auto& s : entry.settings) settings += s.name + "=" + s.value + " (" + s.why + "); ";
    benchmark::AddCustomContext("settings " + entry.name, entry.version + "; " + settings);
  }
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
