// The replay viewer's pose files (docs/viewer.md): each job's sampled body poses at a chosen
// frame rate of simulated time, float32, written into the results folder's poses/ by the runner;
// for a contact scene also, per frame, each body's deepest penetration and every contact point,
// computed from the poses by rtp's narrow phase (physbench/overlaps.h), so no adapter records
// anything and every engine is measured the same way.
#pragma once

#include <cstdint>
#include <filesystem>

#include "physbench/overlaps.h"
#include "physbench/simulate.h"

namespace physbench {

// frames per second of simulated time the viewer replays at (a coarser probe keeps every sample)
inline constexpr double kPoseFrameRate = 30.0;
// one job's file at most: a scene with many bodies keeps fewer frames per second to fit. The
// report embeds at most 600 kB of compressed poses for all of a scene's engines (replay.py's
// SCENE_BYTES), so a job's 96 KiB (a 20-box tower at 15 frames a second) holds what a replay shows
inline constexpr std::uint64_t kPoseBytesPerJob = 96ull << 10;
// one run's pose files at most: past it the runner writes no more and metadata.json says which
inline constexpr std::uint64_t kPoseBytesPerRun = 64ull << 20;
// floats per body per frame: position (3), orientation quaternion x, y, z, w (4), speed |v| (1)
inline constexpr int kPoseFloats = 8;
// floats per contact point: position (3), depth (1)
inline constexpr int kContactFloats = 4;
// the header's sections word: bit 0 set when the contact sections follow the poses
inline constexpr std::uint32_t kPoseSectionContacts = 1;

struct PoseLayout {
  std::uint32_t frames = 0;
  std::uint32_t bodies = 0;
  std::uint32_t stride = 1;           // samples per frame
  std::uint32_t contact_stride = 0;   // frames per contact frame; 0: no contact sections
  std::uint32_t contact_frames = 0;   // frames 0, contact_stride, 2 contact_stride, …
  std::uint64_t contact_points = 0;   // over all contact frames
  std::uint64_t bytes = 0;            // the whole file, contacts included
};

// The file a trajectory gives within byte_cap. The poses first, as if there were no contacts:
// kPoseFrameRate, or fewer frames per second until they fit (every stride-th sample from the
// first, and the last sample too; frames = 0 when even two frames exceed the cap). Then, given
// the scene's gauge (null: no contacts), the contacts of every contact_stride-th frame, the
// stride growing until they fit in what the cap leaves, or none (contact_stride = 0). So contacts
// never cost a pose frame.
PoseLayout pose_layout(const Trajectory& run, const OverlapGauge* contacts = nullptr,
                       std::uint64_t byte_cap = kPoseBytesPerJob);

// Writes the pose file (little-endian); contacts must be the gauge pose_layout was given:
//   char[8] "PBPOSES2"; uint32 frames F, bodies B; float32 seconds per frame (nominal);
//   uint32 sections (kPoseSectionContacts); uint32 contact points C; uint32 contact stride S
//   int32 scene body index [B]        (particle i is body index scene.bodies.size() + i)
//   float32 time [F]
//   float32 [F][B][8]                 px py pz qx qy qz qw |v|
// and with kPoseSectionContacts, for the Fc = ceil(F / S) contact frames 0, S, 2S, …:
//   float32 [Fc][B]                   each body's deepest penetration (m)
//   uint32 contact points per contact frame [Fc]
//   float32 [C][4]                    x y z depth, frame by frame
void write_pose_file(const std::filesystem::path& path, const Trajectory& run,
                     const PoseLayout& layout, const OverlapGauge* contacts = nullptr);

}  // namespace physbench
