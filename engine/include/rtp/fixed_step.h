// The fixed-step accumulator (Fiedler, "Fix Your Timestep!"): physics advances in whole steps of
// dt whatever the frame time, several per frame when a frame is long, and the leftover
// fraction is returned for interpolating what is drawn.
#pragma once

#include <algorithm>
#include <cmath>

namespace rtp {

class FixedStepper {
 public:
  // max_steps_per_frame caps the catch-up after a long frame: without it a frame slower than
  // its physics makes the next frame slower still (the spiral of death); time past the cap is
  // dropped
  explicit FixedStepper(double dt = 1.0 / 120.0, int max_steps_per_frame = 8)
      : dt_(dt), max_steps_(max_steps_per_frame) {}

  // adds a frame's time and returns how many fixed steps to take now
  int advance(double frame_seconds) {
    accumulated_ += std::max(0.0, frame_seconds);
    // count in whole steps of dt; the comparison is exact because only dt is ever subtracted
    int steps = 0;
    while (accumulated_ >= dt_ && steps < max_steps_) {
      accumulated_ -= dt_;
      ++steps;
    }
    if (steps == max_steps_ && accumulated_ >= dt_) {
      // keep only the fraction of a step; fmod can round to a hair under dt, never to dt or more
      const double leftover = std::fmod(accumulated_, dt_);
      dropped_ += accumulated_ - leftover;
      accumulated_ = leftover;
    }
    return steps;
  }

  // fraction of a step left over, in [0, 1): blend the last two states by it when drawing
  double alpha() const { return accumulated_ / dt_; }
  double dt() const { return dt_; }
  double dropped_seconds() const { return dropped_; }  // time given up to the cap

 private:
  double dt_;
  int max_steps_;
  double accumulated_ = 0.0;
  double dropped_ = 0.0;
};

}  // namespace rtp
