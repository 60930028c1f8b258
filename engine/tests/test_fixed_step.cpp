#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "rtp/fixed_step.h"

namespace {

TEST(FixedStepper, StepsFloorOfTotalOverDtForARandomFrameSequence) {
  std::mt19937 random(42);
  std::uniform_real_distribution<double> frame(0.0,
                                               1.0 / 20.0);  // 0 to 50 ms frames, no cap reached
  const double dt = 1.0 / 120.0;
  rtp::FixedStepper stepper(dt, 100);
  long steps = 0;
  double total = 0.0;
  for (int i = 0; i < 10000; ++i) {
    const double t = frame(random);
    total += t;
    steps += stepper.advance(t);
    // after every frame: every whole step of the time so far has been taken, and no more
    const long expected = static_cast<long>(std::floor(total / dt + 1e-9));
    ASSERT_LE(std::abs(steps - expected), 1)
        << "frame " << i;  // one ulp of rounding at the boundary
    ASSERT_GE(stepper.alpha(), 0.0);
    ASSERT_LT(stepper.alpha(), 1.0);
  }
  EXPECT_EQ(steps, static_cast<long>(std::floor(total / dt + 1e-9)));
  EXPECT_NEAR((total - steps * dt) / dt, stepper.alpha(), 1e-6);
}

TEST(FixedStepper, ShortFramesAccumulateIntoOneStep) {
  rtp::FixedStepper stepper(0.01);
  EXPECT_EQ(stepper.advance(0.004), 0);
  EXPECT_EQ(stepper.advance(0.004), 0);
  EXPECT_EQ(stepper.advance(0.004), 1);
  EXPECT_NEAR(stepper.alpha(), 0.2, 1e-9);
}

TEST(FixedStepper, LongFrameIsCappedAndTheRestDropped) {
  rtp::FixedStepper stepper(0.01, 4);
  EXPECT_EQ(stepper.advance(1.0), 4);  // a 1 s hitch: 4 steps, not 100
  // every second is stepped, dropped or left over, and less than a step is left over
  EXPECT_NEAR(4 * 0.01 + stepper.dropped_seconds() + stepper.alpha() * 0.01, 1.0, 1e-12);
  EXPECT_LT(stepper.alpha(), 1.0);
  EXPECT_EQ(stepper.advance(0.01), 1);  // and the next frame is normal again
}

TEST(FixedStepper, NegativeFrameTimeIsIgnored) {
  rtp::FixedStepper stepper(0.01);
  EXPECT_EQ(stepper.advance(-5.0), 0);
  EXPECT_EQ(stepper.advance(0.01), 1);
}

}  // namespace
