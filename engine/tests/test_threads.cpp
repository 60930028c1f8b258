// The contact pipeline's team helpers (engine/src/threads.h): the shares cover the items once,
// and the spinning barrier lets no thread past until every one has arrived, with each one's
// writes before it seen by all after it — on as many threads as cores, and on more (its yield).
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <thread>
#include <vector>

#include "threads.h"
#include "rtp/thread_governor.h"

namespace {

using rtp::share_of;
using rtp::SpinBarrier;

TEST(Threads, SharesCoverTheItemsOnceInOrder) {
  for (const std::size_t n : {0u, 1u, 7u, 312u, 14950u})
    for (int parts = 1; parts <= 5; ++parts) {
      std::size_t next = 0;
      for (int part = 0; part < parts; ++part) {
        const auto [first, last] = share_of(n, parts, part);
        EXPECT_EQ(first, next) << n << " items, part " << part << " of " << parts;
        EXPECT_LE(first, last);
        EXPECT_LE(last - first, n / std::size_t(parts) + 1);
        next = last;
      }
      EXPECT_EQ(next, n) << n << " items in " << parts << " parts";
    }
}

// each round: every thread writes the round into its slot, waits, reads every slot (each must
// hold this round: nobody is a round behind, nobody's write unseen), and waits again before the
// next round's write
void every_thread_sees_every_write(int threads, int rounds) {
  SpinBarrier barrier;
  std::vector<std::atomic<int>> slots(static_cast<std::size_t>(threads));
  for (auto& slot : slots) slot.store(-1, std::memory_order_relaxed);
  std::vector<int> stale(std::size_t(threads), 0);
  std::vector<std::thread> team;
  for (int t = 0; t < threads; ++t)
    team.emplace_back([&, t] {
      for (int round = 0; round < rounds; ++round) {
        slots[std::size_t(t)].store(round, std::memory_order_relaxed);
        barrier.wait(threads);
        for (const auto& slot : slots)
          stale[std::size_t(t)] += slot.load(std::memory_order_relaxed) != round;
        barrier.wait(threads);
      }
    });
  for (std::thread& thread : team) thread.join();
  for (int t = 0; t < threads; ++t)
    EXPECT_EQ(stale[std::size_t(t)], 0) << "thread " << t << " of " << threads;
}

TEST(Threads, SpinBarrierHoldsEveryThreadUntilAllArrive) {
  every_thread_sees_every_write(2, 5000);
  every_thread_sees_every_write(3, 2000);
}

TEST(Threads, SpinBarrierWithMoreThreadsThanCoresStillFinishes) {
  // more threads than these machines' two cores: a waiting thread spins out its budget and
  // yields, so the ones it waits for run
  const int threads = int(std::max(4u, 2 * std::thread::hardware_concurrency()));
  every_thread_sees_every_write(threads, 200);
}

}  // namespace

// ---- the governor's choice of team (rtp/thread_governor.h), fed step times, no clock --------

namespace {

// n steps through the governor, each on the team it chose, taking `team` s on two threads and
// `one` s on one; returns how many ran on one thread
int steps_on_one_thread(rtp::ThreadGovernor& g, int n, double team, double one) {
  int on_one = 0;
  for (int i = 0; i < n; ++i) {
    const int threads = g.next();
    EXPECT_TRUE(threads == 1 || threads == 2) << threads;
    on_one += threads == 1;
    g.record(threads, threads == 1 ? one : team);
  }
  return on_one;
}

}  // namespace

TEST(ThreadGovernor, AnIdleMachineRunsTheTeamAndProbesOneThreadRarely) {
  rtp::ThreadGovernor g(2, true);
  // pyramid-100's idle figures: 4.8 ms on two threads, 9.3 on one
  const int on_one = steps_on_one_thread(g, 320, 4.8e-3, 9.3e-3);
  // the first probe and one in every kProbeEvery after it
  EXPECT_GE(on_one, 1);
  EXPECT_LE(on_one, 320 / rtp::ThreadGovernor::kProbeEvery + 1);
}

TEST(ThreadGovernor, ABusyMachineRunsOneThreadAndProbesTheTeamRarely) {
  rtp::ThreadGovernor g(2, true);
  // beside a busy loop: 30 ms on two threads, 10 on one
  const int on_one = steps_on_one_thread(g, 320, 30e-3, 10e-3);
  EXPECT_GE(on_one, 320 - 320 / rtp::ThreadGovernor::kProbeEvery - rtp::ThreadGovernor::kFirstProbe);
  // the time it costs: within 1.1 of one thread's all along
  rtp::ThreadGovernor h(2, true);
  double total = 0.0;
  for (int i = 0; i < 3200; ++i) {
    const int threads = h.next();
    const double seconds = threads == 1 ? 10e-3 : 30e-3;
    total += seconds;
    h.record(threads, seconds);
  }
  EXPECT_LT(total / 3200, 1.1 * 10e-3);
}

TEST(ThreadGovernor, AnIdleMachineProbesOneThreadEverMoreRarelyAndABusyOneIsLeftAtOnce) {
  rtp::ThreadGovernor g(2, true);
  // idle for 10,000 steps: each probe finds the team faster, and the next comes twice as late,
  // up to one in kMostProbeEvery
  const int on_one = steps_on_one_thread(g, 10000, 4.8e-3, 9.3e-3);
  EXPECT_GE(on_one, 10000 / rtp::ThreadGovernor::kMostProbeEvery);
  EXPECT_LE(on_one, 10000 / rtp::ThreadGovernor::kMostProbeEvery + 8);
  // then busy: the team's own estimate turns it to one thread within two steps, no probe needed
  EXPECT_GE(steps_on_one_thread(g, 20, 30e-3, 10e-3), 18);
  // and idle again: back on the team within a few probes at the first rate
  steps_on_one_thread(g, 4 * rtp::ThreadGovernor::kProbeEvery, 4.8e-3, 9.3e-3);
  EXPECT_LE(steps_on_one_thread(g, 320, 4.8e-3, 9.3e-3), 320 / rtp::ThreadGovernor::kProbeEvery + 1);
}

TEST(ThreadGovernor, TurnsBackWhenTheMachineChanges) {
  rtp::ThreadGovernor g(2, true);
  steps_on_one_thread(g, 200, 30e-3, 10e-3);  // busy: one thread
  // the other process ends: within a few probes the team is back
  steps_on_one_thread(g, 4 * rtp::ThreadGovernor::kProbeEvery, 4.8e-3, 9.3e-3);
  EXPECT_LE(steps_on_one_thread(g, 320, 4.8e-3, 9.3e-3), 320 / rtp::ThreadGovernor::kProbeEvery + 1);
}

// a busy spell long past does not hold the team off: the first probe after the machine is idle
// again turns it back (blended with the busy estimate, it took four probes: 2 s at 60 Hz)
TEST(ThreadGovernor, TheFirstProbeOnAnIdleMachineTurnsBackToTheTeam) {
  rtp::ThreadGovernor g(2, true);
  steps_on_one_thread(g, 200, 30e-3, 10e-3);  // busy: one thread
  // idle: one thread until the next probe of the team, at most kProbeEvery steps away
  int steps = 0;
  for (int threads = 1; threads == 1; ++steps) {
    ASSERT_LE(steps, rtp::ThreadGovernor::kProbeEvery) << "no probe of the team";
    threads = g.next();
    g.record(threads, threads == 1 ? 9.3e-3 : 4.8e-3);
  }
  // and from that probe on, the team, until it probes one thread again
  EXPECT_EQ(steps_on_one_thread(g, rtp::ThreadGovernor::kProbeEvery - 1, 4.8e-3, 9.3e-3), 0);
}

// a probe that finds the team fast once, where the machine is still busy, costs a step or two on
// the team, not a run of them: the team's own steps raise its estimate at once
TEST(ThreadGovernor, OneLuckyProbeOfTheTeamCostsAFewSteps) {
  rtp::ThreadGovernor g(2, true);
  steps_on_one_thread(g, 200, 30e-3, 10e-3);  // busy: one thread
  int on_team = 0, probes_seen = 0;
  for (int i = 0; i < 64; ++i) {
    const int threads = g.next();
    // the first probe of the team finds it at 5 ms; every team step after that takes 30
    const bool lucky = threads == 2 && probes_seen++ == 0;
    on_team += threads == 2;
    g.record(threads, threads == 1 ? 10e-3 : lucky ? 5e-3 : 30e-3);
  }
  EXPECT_LE(on_team, 4);
}

// one slow team step on an idle machine (the worker's core taken away for a moment, as these VMs
// do) costs that step, not a run on one thread: blended at its full 20 ms, it lifted the team's
// estimate past one thread's and kept the step on one thread until the team's next probe, up to
// kProbeEvery steps (ThreadScaling's two-thread world ran 12–22 % of its steps on one thread in
// a noisy spell); two slow steps in a row still turn it (the busy-machine tests above)
TEST(ThreadGovernor, OneSlowTeamStepOnAnIdleMachineCostsThatStepOnly) {
  rtp::ThreadGovernor g(2, true);
  steps_on_one_thread(g, 200, 4.8e-3, 9.3e-3);  // idle: the team
  int threads = g.next();
  while (threads != 2) {  // (past a probe of one thread, if one falls here)
    g.record(threads, 9.3e-3);
    threads = g.next();
  }
  g.record(threads, 20e-3);  // the one slow step
  EXPECT_LE(steps_on_one_thread(g, rtp::ThreadGovernor::kProbeEvery, 4.8e-3, 9.3e-3), 1);
}

TEST(ThreadGovernor, FixedOrOneThreadNeverChanges) {
  rtp::ThreadGovernor fixed(2, false), single(1, true);
  for (int i = 0; i < 100; ++i) {
    EXPECT_EQ(fixed.next(), 2);
    fixed.record(2, 1.0);
    EXPECT_EQ(single.next(), 1);
    single.record(1, 1.0);
  }
}
