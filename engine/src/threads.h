// How the contact pipeline's parallel loops share their work among an OpenMP team: each thread
// a contiguous share, the same wherever it is asked, so a thread's loops touch the same items from
// stage to stage (and the results do not depend on the team's size).
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <thread>
#include <utility>

#if defined(_OPENMP)
#include <omp.h>
#endif

namespace rtp {

// the share of n items that part `part` of `parts` takes: [first, last)
inline std::pair<std::size_t, std::size_t> share_of(std::size_t n, int parts, int part) {
  return {n * std::size_t(part) / std::size_t(parts),
          n * std::size_t(part + 1) / std::size_t(parts)};
}

// the calling thread's place in its team (one thread, the first, without OpenMP)
inline int team_size() {
#if defined(_OPENMP)
  return omp_get_num_threads();
#else
  return 1;
#endif
}
inline int team_index() {
#if defined(_OPENMP)
  return omp_get_thread_num();
#else
  return 0;
#endif
}

// body(i) for each i in [0, n): on a team of `threads`, each thread a contiguous share (OpenMP's
// static schedule), where threads > 1 and the loop is `worth` a team; otherwise on the calling
// thread without entering OpenMP, whose runtime makes and frees a team even for a region of one
// thread (a heap allocation, and futex calls: `perf` put them at a tenth of a four-box scene's
// step, some 25 regions a step)
template <class Index, class Body>
inline void parallel_for(int threads, Index n, bool worth, Body&& body) {
#if defined(_OPENMP)
  if (threads > 1 && worth) {
#pragma omp parallel for num_threads(threads) schedule(static)
    for (Index i = 0; i < n; ++i) body(i);
    return;
  }
#endif
  for (Index i = 0; i < n; ++i) body(i);
}

// body() once on each thread of a team of `threads` where threads > 1 and the work is `worth` a
// team (team_size() and team_index() tell a thread its place), otherwise once on the calling
// thread, without entering OpenMP (as parallel_for)
template <class Body>
inline void parallel_region(int threads, bool worth, Body&& body) {
#if defined(_OPENMP)
  if (threads > 1 && worth) {
#pragma omp parallel num_threads(threads)
    body();
    return;
  }
#endif
  body();
}

// a hint to the core that this thread spins on a flag
inline void spin_pause() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#endif
}

// A barrier for the threads of one team, spinning: a pass has one between two colours, and an
// OpenMP barrier costs about 0.35 µs more than this one (two threads on these VMs: a region with
// six of them 2.1–2.3 µs, with six OpenMP barriers 4.1–4.3). Past a spin budget, or at once in a
// team larger than the cores, a waiting thread yields, so the threads it waits for can run.
class SpinBarrier {
 public:
  void wait(int team) {
    const unsigned generation = generation_.load(std::memory_order_acquire);
    if (arrived_.fetch_add(1, std::memory_order_acq_rel) + 1 == team) {
      arrived_.store(0, std::memory_order_relaxed);
      generation_.store(generation + 1, std::memory_order_release);
      return;
    }
    // a team larger than the cores yields at once: the thread it waits for may need this core
    static const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
    const int budget = unsigned(team) > cores ? 0 : kSpins;
    for (int spins = 0; generation_.load(std::memory_order_acquire) == generation; ++spins) {
      if (spins < budget)
        spin_pause();
      else
        std::this_thread::yield();
    }
  }

 private:
  // about 40 µs of pauses, twice a colour's share of a pass at base 100: a thread still waiting
  // then is waiting for one the machine has descheduled (another process on its core)
  static constexpr int kSpins = 1 << 11;
  alignas(64) std::atomic<int> arrived_{0};
  alignas(64) std::atomic<unsigned> generation_{0};
};

}  // namespace rtp
