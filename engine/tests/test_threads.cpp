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
