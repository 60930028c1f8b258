// The replay viewer's pose files: the frame rate, the per-job cap and the bytes on disk.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <vector>

#include "physbench/poses.h"

namespace physbench {
namespace {

Trajectory still_run(int bodies, int samples, double interval) {
  Trajectory run;
  for (int b = 0; b < bodies; ++b) run.bodies.push_back(b + 1);
  for (int k = 0; k < samples; ++k) {
    Sample s;
    s.time = k * interval;
    for (int b = 0; b < bodies; ++b) {
      SampledState st;
      st.position = Vec3(b, 0.5 + k * 0.01, -b);
      st.linear_velocity = Vec3(3.0, 4.0, 0.0);
      s.bodies.push_back(st);
    }
    run.samples.push_back(s);
  }
  return run;
}

TEST(PoseFiles, SixtyHertzSamplesGiveThirtyFramesPerSecondAndTheLastSample) {
  const PoseLayout layout = pose_layout(still_run(20, 601, 1.0 / 60.0));
  EXPECT_EQ(layout.stride, 2u);
  EXPECT_EQ(layout.frames, 301u);  // 0, 2, …, 600
  EXPECT_EQ(layout.bytes, 24u + 4 * 20 + 4 * 301 + 32ull * 301 * 20);
  // an odd sample count: the last sample is a frame of its own
  EXPECT_EQ(pose_layout(still_run(1, 600, 1.0 / 60.0)).frames, 301u);
}

TEST(PoseFiles, AManyBodySceneKeepsFewerFramesWithinTheJobCap) {
  const Trajectory run = still_run(5050, 61, 1.0 / 60.0);
  const PoseLayout layout = pose_layout(run);
  EXPECT_LE(layout.bytes, kPoseBytesPerJob);
  EXPECT_GT(layout.frames, 2u);
  EXPECT_GT(layout.stride, 2u);
  // a cap below two frames: nothing to write
  EXPECT_EQ(pose_layout(run, 5050ull * 32).frames, 0u);
}

TEST(PoseFiles, TheFileHoldsItsHeaderTimesAndPoses) {
  const Trajectory run = still_run(3, 7, 0.1);  // 0.1 s apart: every sample is a frame
  const PoseLayout layout = pose_layout(run);
  ASSERT_EQ(layout.frames, 7u);
  const auto path = std::filesystem::temp_directory_path() / "physbench_test_poses.bin";
  write_pose_file(path, run, layout);
  std::ifstream in(path, std::ios::binary);
  std::vector<char> bytes((std::istreambuf_iterator<char>(in)), {});
  std::filesystem::remove(path);
  ASSERT_EQ(bytes.size(), layout.bytes);
  EXPECT_EQ(std::string(bytes.data(), 8), "PBPOSES1");
  std::uint32_t frames = 0, bodies = 0;
  std::memcpy(&frames, bytes.data() + 8, 4);
  std::memcpy(&bodies, bytes.data() + 12, 4);
  EXPECT_EQ(frames, 7u);
  EXPECT_EQ(bodies, 3u);
  std::int32_t index = 0;
  std::memcpy(&index, bytes.data() + 24 + 4 * 2, 4);
  EXPECT_EQ(index, 3);
  auto float_at = [&](std::size_t offset) {
    float f = 0;
    std::memcpy(&f, bytes.data() + offset, 4);
    return f;
  };
  const std::size_t times = 24 + 4 * 3, poses = times + 4 * 7;
  EXPECT_FLOAT_EQ(float_at(times + 4 * 6), 0.6f);
  // frame 6, body 2: position (2, 0.56, -2), identity quaternion (w last), speed 5
  const std::size_t at = poses + 4 * 8 * (6 * 3 + 2);
  EXPECT_FLOAT_EQ(float_at(at), 2.0f);
  EXPECT_FLOAT_EQ(float_at(at + 4), 0.56f);
  EXPECT_FLOAT_EQ(float_at(at + 8), -2.0f);
  EXPECT_FLOAT_EQ(float_at(at + 24), 1.0f);
  EXPECT_FLOAT_EQ(float_at(at + 28), 5.0f);
}

}  // namespace
}  // namespace physbench
