// The replay viewer's pose files: the frame rate, the per-job cap, the bytes on disk, and the
// contacts a contact scene's file holds (rtp's narrow phase on the recorded poses).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <vector>

#include "physbench/poses.h"
#include "physbench/scenarios.h"

namespace physbench {
namespace {

template <class T>
T value_at(const std::vector<char>& bytes, std::size_t offset) {
  T value{};
  std::memcpy(&value, bytes.data() + offset, sizeof(T));
  return value;
}

std::vector<char> written(const Trajectory& run, const PoseLayout& layout,
                          const OverlapGauge* contacts) {
  // one file per test: CTest may run this binary's tests side by side
  const auto path = std::filesystem::temp_directory_path() /
                    (std::string("physbench_test_poses_") +
                     ::testing::UnitTest::GetInstance()->current_test_info()->name() + ".bin");
  write_pose_file(path, run, layout, contacts);
  std::ifstream in(path, std::ios::binary);
  std::vector<char> bytes((std::istreambuf_iterator<char>(in)), {});
  std::filesystem::remove(path);
  return bytes;
}

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
  const PoseLayout layout = pose_layout(still_run(20, 601, 1.0 / 60.0), nullptr, 4ull << 20);
  EXPECT_EQ(layout.stride, 2u);
  EXPECT_EQ(layout.frames, 301u);  // 0, 2, …, 600
  EXPECT_EQ(layout.bytes, 32u + 4 * 20 + 4 * 301 + 32ull * 301 * 20);
  // an odd sample count: the last sample is a frame of its own
  EXPECT_EQ(pose_layout(still_run(1, 600, 1.0 / 60.0), nullptr, 4ull << 20).frames, 301u);
}

TEST(PoseFiles, AManyBodySceneKeepsFewerFramesWithinTheJobCap) {
  // 400 boxes over 5 s
  const Trajectory run = still_run(400, 301, 1.0 / 60.0);
  const PoseLayout layout = pose_layout(run);
  EXPECT_LE(layout.bytes, kPoseBytesPerJob);
  EXPECT_GT(layout.frames, 2u);
  EXPECT_GT(layout.stride, 2u);
  // a cap below two frames: nothing to write
  EXPECT_EQ(pose_layout(run, nullptr, 400ull * 32).frames, 0u);
}

TEST(PoseFiles, TheFileHoldsItsHeaderTimesAndPoses) {
  const Trajectory run = still_run(3, 7, 0.1);  // 0.1 s apart: every sample is a frame
  const PoseLayout layout = pose_layout(run);
  ASSERT_EQ(layout.frames, 7u);
  const std::vector<char> bytes = written(run, layout, nullptr);
  ASSERT_EQ(bytes.size(), layout.bytes);
  EXPECT_EQ(std::string(bytes.data(), 8), "PBPOSES2");
  std::uint32_t frames = 0, bodies = 0;
  std::memcpy(&frames, bytes.data() + 8, 4);
  std::memcpy(&bodies, bytes.data() + 12, 4);
  EXPECT_EQ(frames, 7u);
  EXPECT_EQ(bodies, 3u);
  EXPECT_EQ(value_at<std::uint32_t>(bytes, 20), 0u);  // no contact sections: not a contact scene
  EXPECT_EQ(value_at<std::int32_t>(bytes, 32 + 4 * 2), 3);
  auto float_at = [&](std::size_t offset) { return value_at<float>(bytes, offset); };
  const std::size_t times = 32 + 4 * 3, poses = times + 4 * 7;
  EXPECT_FLOAT_EQ(float_at(times + 4 * 6), 0.6f);
  // frame 6, body 2: position (2, 0.56, -2), identity quaternion (w last), speed 5
  const std::size_t at = poses + 4 * 8 * (6 * 3 + 2);
  EXPECT_FLOAT_EQ(float_at(at), 2.0f);
  EXPECT_FLOAT_EQ(float_at(at + 4), 0.56f);
  EXPECT_FLOAT_EQ(float_at(at + 8), -2.0f);
  EXPECT_FLOAT_EQ(float_at(at + 24), 1.0f);
  EXPECT_FLOAT_EQ(float_at(at + 28), 5.0f);
}

// one contact frame's contacts as the file holds them
struct FrameContacts {
  std::vector<float> body_depth;     // per recorded body (m)
  std::vector<OverlapPoint> points;  // x y z depth
};

std::vector<FrameContacts> contacts_in(const std::vector<char>& bytes) {
  const auto frames = value_at<std::uint32_t>(bytes, 8);
  const auto bodies = value_at<std::uint32_t>(bytes, 12);
  EXPECT_EQ(value_at<std::uint32_t>(bytes, 20), kPoseSectionContacts);
  const auto stride = value_at<std::uint32_t>(bytes, 28);
  EXPECT_GT(stride, 0u);
  const std::uint32_t contact_frames = (frames + stride - 1) / stride;
  std::size_t at = 32 + 4 * bodies + 4 * frames + 4 * kPoseFloats * frames * bodies;
  std::vector<FrameContacts> out(contact_frames);
  for (FrameContacts& f : out)
    for (std::uint32_t b = 0; b < bodies; ++b, at += 4)
      f.body_depth.push_back(value_at<float>(bytes, at));
  std::vector<std::uint32_t> counts;
  for (std::uint32_t f = 0; f < contact_frames; ++f, at += 4)
    counts.push_back(value_at<std::uint32_t>(bytes, at));
  for (std::uint32_t f = 0; f < contact_frames; ++f)
    for (std::uint32_t k = 0; k < counts[f]; ++k, at += 4 * kContactFloats)
      out[f].points.push_back({Vec3(value_at<float>(bytes, at), value_at<float>(bytes, at + 4),
                                    value_at<float>(bytes, at + 8)),
                               value_at<float>(bytes, at + 12)});
  EXPECT_EQ(at, bytes.size());
  return out;
}

SampledState at_rest(const Vec3& position) {
  SampledState s;
  s.position = position;
  return s;
}

// tower-2's ground and two unit boxes, recorded at two moments: frame 0 as the scene starts them
// (the lower box resting on the ground, the upper exactly on it), frame 1 with the upper box sunk
// 5 cm into the lower and shifted 0.25 m along x
Trajectory two_boxes() {
  Trajectory run;
  run.bodies = {1, 2};
  Sample start;
  start.bodies = {at_rest(Vec3(0, 0.5, 0)), at_rest(Vec3(0, 1.5, 0))};
  Sample sunk;
  sunk.time = 0.5;
  sunk.bodies = {at_rest(Vec3(0, 0.5, 0)), at_rest(Vec3(0.25, 1.45, 0))};
  run.samples = {start, sunk};
  return run;
}

// the points of a frame within 1 mm of height y
std::vector<OverlapPoint> at_height(const FrameContacts& frame, double y) {
  std::vector<OverlapPoint> level;
  for (const OverlapPoint& p : frame.points)
    if (std::abs(p.point.y() - y) < 1e-3) level.push_back(p);
  return level;
}

// the corners (x, z) a set of points sits on, sorted
std::vector<std::pair<double, double>> corners_of(const std::vector<OverlapPoint>& points) {
  std::vector<std::pair<double, double>> corners;
  for (const OverlapPoint& p : points)
    corners.emplace_back(std::round(p.point.x() * 1000) / 1000,
                         std::round(p.point.z() * 1000) / 1000);
  std::sort(corners.begin(), corners.end());
  return corners;
}

TEST(PoseFiles, ABoxRestingOnTheGroundTouchesItAtItsFourBottomCorners) {
  const Scene scene = tower_scene(2);
  const Trajectory run = two_boxes();
  const OverlapGauge gauge(scene, run.bodies);
  const PoseLayout layout = pose_layout(run, &gauge);
  ASSERT_EQ(layout.frames, 2u);
  const std::vector<char> bytes = written(run, layout, &gauge);
  ASSERT_EQ(bytes.size(), layout.bytes);
  EXPECT_EQ(value_at<std::uint32_t>(bytes, 24), layout.contact_points);
  const FrameContacts start = contacts_in(bytes)[0];
  // y is up (gravity −y): the lower box's bottom face corners at y = 0, and the upper box's on
  // the lower box's top at y = 1; nothing else touches, and nothing is sunk
  const std::vector<std::pair<double, double>> unit_square = {
      {-0.5, -0.5}, {-0.5, 0.5}, {0.5, -0.5}, {0.5, 0.5}};
  EXPECT_EQ(corners_of(at_height(start, 0.0)), unit_square);
  EXPECT_EQ(corners_of(at_height(start, 1.0)), unit_square);
  EXPECT_EQ(start.points.size(), 8u);
  for (const OverlapPoint& p : start.points) EXPECT_NEAR(p.depth, 0.0, 1e-6);
  for (float depth : start.body_depth) EXPECT_NEAR(depth, 0.0, 1e-6);
}

TEST(PoseFiles, TwoOverlappingBoxesRecordTheirDepthWhereTheirFacesOverlap) {
  const Scene scene = tower_scene(2);
  const Trajectory run = two_boxes();
  const OverlapGauge gauge(scene, run.bodies);
  const FrameContacts sunk = contacts_in(written(run, pose_layout(run, &gauge), &gauge))[1];
  // the lower box's top is at y = 1, the upper's bottom at 0.95: 5 cm deep, the points midway;
  // the faces overlap where x is in [−0.25, 0.5] (the upper box moved 0.25 m along x)
  const std::vector<OverlapPoint> between = at_height(sunk, 0.975);
  const std::vector<std::pair<double, double>> overlap = {
      {-0.25, -0.5}, {-0.25, 0.5}, {0.5, -0.5}, {0.5, 0.5}};
  EXPECT_EQ(corners_of(between), overlap);
  for (const OverlapPoint& p : between) EXPECT_NEAR(p.depth, 0.05, 1e-6);
  // both boxes are 5 cm into each other: each one's deepest penetration
  ASSERT_EQ(sunk.body_depth.size(), 2u);
  EXPECT_NEAR(sunk.body_depth[0], 0.05, 1e-6);
  EXPECT_NEAR(sunk.body_depth[1], 0.05, 1e-6);
  // the lower box still rests on the ground, untouched by the overlap above it
  EXPECT_EQ(at_height(sunk, 0.0).size(), 4u);
  EXPECT_EQ(sunk.points.size(), 8u);
  // the deepest body is the penetration metric's sample
  EXPECT_NEAR(gauge.deepest(run.samples[1]), 0.05, 1e-9);
}

TEST(PoseFiles, ContactsFillWhatTheJobCapLeavesAfterThePoses) {
  // tower-20 at rest for 10 s: 20 touching pairs (19 box-box, one on the ground) of 4 points
  // each, every frame
  const Scene scene = tower_scene(20);
  Trajectory run;
  run.bodies = scene.probed_bodies();
  for (int k = 0; k <= 600; ++k) {
    Sample s;
    s.time = k / 60.0;
    for (int b : run.bodies) s.bodies.push_back(at_rest(scene.bodies[b].position));
    run.samples.push_back(s);
  }
  const OverlapGauge gauge(scene, run.bodies);
  // a cap with room for every frame's contacts
  const PoseLayout plain = pose_layout(run, nullptr, 4ull << 20),
                   with = pose_layout(run, &gauge, 4ull << 20);
  EXPECT_EQ(with.frames, plain.frames);
  EXPECT_EQ(with.contact_stride, 1u);
  EXPECT_EQ(with.contact_points, 301u * 20 * 4);
  EXPECT_EQ(with.bytes, plain.bytes + 301ull * (4 * 20 + 4) + 16ull * with.contact_points);
  // a cap with room for 101 frames' contacts (4 bytes a body's depth, 4 the count, 16 a point):
  // every pose frame stays, and the contacts of one frame in 3 (0, 3, …, 300) fill what is left
  const std::uint64_t per_contact_frame = 4 * 20 + 4 + 16 * 80;
  const PoseLayout capped = pose_layout(run, &gauge, plain.bytes + 101 * per_contact_frame);
  EXPECT_EQ(capped.frames, plain.frames);
  EXPECT_EQ(capped.stride, plain.stride);
  EXPECT_EQ(capped.contact_stride, 3u);
  EXPECT_EQ(capped.contact_frames, 101u);
  EXPECT_EQ(capped.contact_points, 101u * 80);
  EXPECT_EQ(capped.bytes, plain.bytes + 101 * per_contact_frame);
  // one byte less: one frame in 4 (76 frames)
  EXPECT_EQ(pose_layout(run, &gauge, plain.bytes + 101 * per_contact_frame - 1).contact_frames, 76u);
  const std::vector<char> bytes = written(run, capped, &gauge);
  EXPECT_EQ(bytes.size(), capped.bytes);
  EXPECT_EQ(contacts_in(bytes).size(), 101u);
  // a cap the poses alone fill: no contact sections, the poses as they were
  const PoseLayout full = pose_layout(run, &gauge, plain.bytes);
  EXPECT_EQ(full.contact_stride, 0u);
  EXPECT_EQ(full.bytes, plain.bytes);
  EXPECT_EQ(value_at<std::uint32_t>(written(run, full, &gauge), 20), 0u);
}

}  // namespace
}  // namespace physbench
