// The replay viewer's pose files (docs/viewer.md): each job's sampled body poses at a chosen
// frame rate of simulated time, float32, written into the results folder's poses/ by the runner.
#pragma once

#include <cstdint>
#include <filesystem>

#include "physbench/simulate.h"

namespace physbench {

// frames per second of simulated time the viewer replays at (a coarser probe keeps every sample)
inline constexpr double kPoseFrameRate = 30.0;
// one job's file at most: a scene with many bodies keeps fewer frames per second to fit
inline constexpr std::uint64_t kPoseBytesPerJob = 4ull << 20;
// one run's pose files at most: past it the runner writes no more and metadata.json says which
inline constexpr std::uint64_t kPoseBytesPerRun = 256ull << 20;
// floats per body per frame: position (3), orientation quaternion x, y, z, w (4), speed |v| (1)
inline constexpr int kPoseFloats = 8;

struct PoseLayout {
  std::uint32_t frames = 0;
  std::uint32_t bodies = 0;
  std::uint32_t stride = 1;  // samples per frame
  std::uint64_t bytes = 0;   // the whole file
};

// The frames a trajectory gives at kPoseFrameRate within byte_cap: every stride-th sample from
// the first, and the last sample too. frames = 0 when even two frames exceed the cap.
PoseLayout pose_layout(const Trajectory& run, std::uint64_t byte_cap = kPoseBytesPerJob);

// Writes the pose file (little-endian):
//   char[8] "PBPOSES1"; uint32 frames, bodies; float32 seconds per frame (nominal); uint32 0
//   int32 scene body index [bodies]   (particle i is body index scene.bodies.size() + i)
//   float32 time [frames]
//   float32 [frames][bodies][8]       px py pz qx qy qz qw |v|
void write_pose_file(const std::filesystem::path& path, const Trajectory& run,
                     const PoseLayout& layout);

}  // namespace physbench
