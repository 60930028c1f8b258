// Which team a contact step runs on, when the machine is not ours alone. A colour of the solve
// ends at a barrier that waits for every thread of the team; with another process busy on one of
// two cores, a thread is descheduled for whole time slices, and the team waits at each colour
// (pyramid-100 beside a busy loop: 30 ms a step on two threads against 10 on one). The governor
// times each step and keeps an estimate for the whole team and for one thread; it runs the faster,
// and the other one step in kProbeEvery, so a change in the machine turns it around at the first
// probe that finds it (a probe's time replaces its team's estimate). While the team is the faster,
// each probe that finds it so doubles the steps to the next one, up to kMostProbeEvery: one thread's probe is a step at twice the time (2.6 % of an idle
// two-thread pyramid-100's steps at one in 32), and a team slowed by a busy machine needs no probe
// to be left, since its own estimate rises at once. The results are the same on any team (a
// colour's contacts share no dynamic body), so only the time depends on it.
#pragma once

#include <algorithm>

namespace rtp {

class ThreadGovernor {
 public:
  static constexpr int kProbeEvery = 32;  // steps between two steps on the other team
  static constexpr int kMostProbeEvery = 512;  // while the team holds, probes grow this rare
  static constexpr int kFirstProbe = 4;   // the first step on one thread (after warm-up steps)
  static constexpr double kWeight = 0.5;  // of a new time in its team's estimate
  // a step blended into a fresh estimate counts as at most this times it: one slow step (the
  // worker's core taken away for a moment) does not outweigh the steps before it, and two in a
  // row still turn the team (a busy machine's team is left within two steps)
  static constexpr double kMostOfEstimate = 2.0;

  // `most`: the threads asked for; `adaptive` false keeps them on every step
  ThreadGovernor(int most, bool adaptive) : most_(most < 1 ? 1 : most), adaptive_(adaptive) {}

  // the team for the next step
  int next() {
    ++step_;
    if (most_ == 1 || !adaptive_) return most_;
    if (team_seconds_ < 0.0) return most_;
    if (one_seconds_ < 0.0) return step_ >= kFirstProbe ? 1 : most_;
    const int preferred = one_seconds_ < team_seconds_ ? 1 : most_;
    if (preferred != preferred_) {  // turned: probe the other at the first rate again
      preferred_ = preferred;
      interval_ = kProbeEvery;
      since_probe_ = 0;
    }
    if (++since_probe_ < interval_) return preferred;
    since_probe_ = 0;
    if (preferred == most_) interval_ = interval_ * 2 > kMostProbeEvery ? kMostProbeEvery
                                                                        : interval_ * 2;
    return preferred == 1 ? most_ : 1;
  }
  // the step just run on `team` took `seconds`. An estimate last measured more than two steps
  // ago (at a probe, or at the first step after a turn) is replaced, not blended: it is a probe's
  // interval old or more, and blended with it a busy spell's figure held the team off for four
  // probes (2 s at 60 Hz) after the machine was idle again. The step after a probe, back on the
  // preferred team, joins that team's running mean, at most kMostOfEstimate times it
  void record(int team, double seconds) {
    if (most_ == 1 || !adaptive_ || !(seconds >= 0.0)) return;
    double& estimate = team == 1 ? one_seconds_ : team_seconds_;
    long& measured = team == 1 ? one_measured_ : team_measured_;
    estimate = estimate < 0.0 || step_ - measured > 2
                   ? seconds
                   : (1.0 - kWeight) * estimate +
                         kWeight * std::min(seconds, kMostOfEstimate * estimate);
    measured = step_;
  }

 private:
  int most_;
  bool adaptive_;
  long step_ = 0;
  double team_seconds_ = -1.0, one_seconds_ = -1.0;  // estimates; below zero: not measured yet
  int preferred_ = 0;     // the team the estimates last preferred (0: none yet)
  int interval_ = kProbeEvery;  // steps from one probe of the other team to the next
  int since_probe_ = 0;
  long team_measured_ = 0, one_measured_ = 0;  // the steps each estimate was last recorded at
};

}  // namespace rtp
