// rtp is bit-deterministic: the same scene gives the same bits — every sample of every probed
// body — on every run in one process and at one or two threads. The hashes of scenes without
// contacts are pinned (docs/engines.md, "Determinism", says which build changes may move them);
// the stacking scene is only compared run against run while the contact solver is being rewritten.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <iomanip>
#include <sstream>

#include "physbench/scenarios.h"
#include "support.h"
#include "physbench/registry.h"

// the linked MuJoCo build's name ("mujoco-2.2" where MuJoCo 4, in physbench-mujoco4, is the
// mujoco row)
static const std::string kMujoco = physbench::mujoco_engine_name();

namespace {

using namespace physbench;

// FNV-1a over the bit patterns of every sampled number
std::uint64_t trajectory_hash(const Trajectory& t) {
  std::uint64_t h = 1469598103934665603ull;
  auto mix = [&](double v) {
    unsigned char bytes[sizeof v];
    std::memcpy(bytes, &v, sizeof v);
    for (unsigned char b : bytes) h = (h ^ b) * 1099511628211ull;
  };
  for (const Sample& s : t.samples) {
    mix(s.time);
    for (const SampledState& b : s.bodies) {
      for (int k = 0; k < 3; ++k) mix(b.position[k]);
      mix(b.orientation.w());
      for (int k = 0; k < 3; ++k) mix(b.orientation.vec()[k]);
      for (int k = 0; k < 3; ++k) mix(b.linear_velocity[k]);
      for (int k = 0; k < 3; ++k) mix(b.angular_velocity[k]);
    }
  }
  return h;
}

std::string hex(std::uint64_t h) {
  std::ostringstream out;
  out << "0x" << std::hex << std::setw(16) << std::setfill('0') << h;
  return out.str();
}

Scene scenario(const std::string& name, double duration = 0.0) {
  const Scenario* s = find_scenario(name);
  if (!s) throw std::runtime_error("no scenario " + name);
  Scene scene = s->build();
  if (duration > 0.0) scene.duration = duration;
  return scene;
}

std::uint64_t run_hash(const std::string& variant, const Scene& scene) {
  SimulateOptions options;
  options.timing_budget = 0.0;
  const RunResult r = simulate(rtp_engine_info(), variant, scene, options);
  EXPECT_EQ(r.status, Status::Ok) << scene.name << " " << variant << ": " << r.message;
  return trajectory_hash(r.trajectory);
}

struct Pinned {
  const char* scenario;
  const char* variant;
  std::uint64_t hash;
};

// scenes without contacts: free flight, the tumble, a top, springs and impulses
const Pinned kPinned[] = {
    {"projectile", "rk4", 0xec49f46b764dca36ull},
    {"tumbling-box", "rk4", 0xf5dc02727df981c6ull},
    {"tumbling-box", "euler", 0x5f5ac9f174b6a6d4ull},
    {"symmetric-top", "symplectic", 0x3f7ea30ac8fc5073ull},
    {"spring-chain", "midpoint", 0x3e6c987e23d367d4ull},
    {"pushed-box", "rk4", 0x1e4657ac6039770full},
};

TEST(Determinism, FreeBodyScenesGiveThePinnedHashOnEveryRun) {
  for (const Pinned& p : kPinned) {
    const Scene scene = scenario(p.scenario);
    ASSERT_FALSE(scene.has_contacts()) << p.scenario;
    const std::uint64_t first = run_hash(p.variant, scene);
    for (int repeat = 0; repeat < 2; ++repeat)
      EXPECT_EQ(run_hash(p.variant, scene), first) << p.scenario << " " << p.variant << " run " << repeat + 2;
    EXPECT_EQ(first, p.hash) << p.scenario << " " << p.variant << ": hash " << hex(first)
                             << " (pinned " << hex(p.hash) << ")";
  }
}

// the particle update at one and two OpenMP threads: each particle is its own, so the bits agree.
// Not pinned: the update picks AVX-512 kernels at run time where the CPU has them.
TEST(Determinism, ParticlesAgreeAtOneAndTwoThreads) {
  const Scene scene = scenario("particles-attractors", 1.0);
  const std::uint64_t one = run_hash("midpoint", scene);
  EXPECT_EQ(run_hash("midpoint", scene), one);
  EXPECT_EQ(run_hash("midpoint-2t", scene), one);
  EXPECT_EQ(run_hash("midpoint-2t", scene), one);
}

// a stack: the contact solver's narrow phase and each colour of the solve at one and two threads.
// Compared run against run, not pinned: the solver is being rewritten.
TEST(Determinism, StackingSceneAgreesAcrossRepeatsAndThreads) {
  const Scene scene = scenario("tower-10", 1.0);
  ASSERT_TRUE(scene.has_contacts());
  const std::uint64_t one = run_hash("soft-step", scene);
  EXPECT_EQ(run_hash("soft-step", scene), one);
  EXPECT_EQ(run_hash("soft-step-2t", scene), one);
  EXPECT_EQ(run_hash("soft-step-2t", scene), one);
}

// each peer adapter gives the same bits on two runs in one process (a fresh world each; a run in
// a second process: harness/tests, Runner.EveryEngineGivesTheSameBitsTwiceInSeparateProcesses),
// on springs and on boxes started in contact. Bullet's double build lives in another executable.
TEST(Determinism, EveryPeerGivesTheSameBitsOnTwoRunsInOneProcess) {
  std::vector<std::pair<std::string, std::string>> peers;
#ifdef PHYSBENCH_HAVE_BULLET
  peers.push_back({"bullet", "float"});
#endif
#ifdef PHYSBENCH_HAVE_ODE
  peers.push_back({"ode", "quickstep"});  // shuffles its rows with ODE's global generator
  peers.push_back({"ode", "step"});
#endif
#ifdef PHYSBENCH_HAVE_BOX2D
  peers.push_back({"box2d", "default"});
#endif
#ifdef PHYSBENCH_HAVE_MUJOCO
  peers.push_back({kMujoco, "euler"});
  peers.push_back({kMujoco, "pgs-10"});  // contact scenes only
#endif
  if (peers.empty()) GTEST_SKIP() << "no peer engine in this build";
  for (const Scene& scene : {scenario("spring-chain", 2.0), scenario("overlap-recovery", 1.0)}) {
    for (const auto& [name, variant] : peers) {
      if (variant == "pgs-10" && !scene.has_contacts()) continue;
      SimulateOptions options;
      options.timing_budget = 0.0;
      const RunResult first = simulate(physbench::testing::engine(name), variant, scene, options);
      const RunResult second = simulate(physbench::testing::engine(name), variant, scene, options);
      const std::string what = scene.name + " " + name + "/" + variant;
      EXPECT_NE(first.status, Status::Unsupported) << what << ": " << first.message;
      EXPECT_EQ(first.status, second.status) << what;
      ASSERT_GT(first.trajectory.samples.size(), 10u) << what << ": " << first.message;
      EXPECT_EQ(trajectory_hash(first.trajectory), trajectory_hash(second.trajectory)) << what;
    }
  }
}

}  // namespace
