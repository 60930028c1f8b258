#include "physbench/poses.h"

#include <bit>
#include <cmath>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <vector>

namespace physbench {

namespace {

static_assert(std::endian::native == std::endian::little, "pose files are written little-endian");

std::uint64_t file_bytes(std::uint64_t frames, std::uint64_t bodies) {
  return 24 + 4 * bodies + 4 * frames + 4ull * kPoseFloats * frames * bodies;
}

// the samples kept as frames: every stride-th, and the last even when the stride steps over it
std::vector<std::size_t> picked_samples(std::size_t samples, std::size_t stride) {
  std::vector<std::size_t> picked;
  for (std::size_t k = 0; k < samples; k += stride) picked.push_back(k);
  if (samples > 0 && picked.back() != samples - 1) picked.push_back(samples - 1);
  return picked;
}

std::uint32_t frame_count(std::size_t samples, std::size_t stride) {
  return static_cast<std::uint32_t>(picked_samples(samples, stride).size());
}

}  // namespace

PoseLayout pose_layout(const Trajectory& run, std::uint64_t byte_cap) {
  PoseLayout layout;
  layout.bodies = static_cast<std::uint32_t>(run.bodies.size());
  const std::size_t samples = run.samples.size();
  if (samples == 0 || layout.bodies == 0) return layout;
  std::size_t stride = 1;
  if (samples > 1) {
    const double interval = run.samples[1].time - run.samples[0].time;
    if (interval > 0.0)
      stride = std::max<std::size_t>(1, std::lround(1.0 / (kPoseFrameRate * interval)));
  }
  // fewer frames per second until the file fits; at least the first and last sample
  while (frame_count(samples, stride) > 2 &&
         file_bytes(frame_count(samples, stride), layout.bodies) > byte_cap)
    ++stride;
  const std::uint32_t frames = frame_count(samples, stride);
  if (file_bytes(frames, layout.bodies) > byte_cap) return layout;
  layout.frames = frames;
  layout.stride = static_cast<std::uint32_t>(stride);
  layout.bytes = file_bytes(frames, layout.bodies);
  return layout;
}

void write_pose_file(const std::filesystem::path& path, const Trajectory& run,
                     const PoseLayout& layout) {
  if (layout.frames == 0) throw std::invalid_argument("write_pose_file: no frames to write");
  const std::vector<std::size_t> picked = picked_samples(run.samples.size(), layout.stride);
  if (picked.size() != layout.frames)
    throw std::logic_error("write_pose_file: layout does not match");

  std::vector<char> bytes;
  bytes.reserve(layout.bytes);
  auto put = [&bytes](const void* p, std::size_t n) {
    const char* c = static_cast<const char*>(p);
    bytes.insert(bytes.end(), c, c + n);
  };
  auto put_f = [&put](double v) {
    const float f = static_cast<float>(v);
    put(&f, 4);
  };
  put("PBPOSES1", 8);
  put(&layout.frames, 4);
  put(&layout.bodies, 4);
  put_f(picked.size() > 1 ? run.samples[picked[1]].time - run.samples[picked[0]].time : 0.0);
  const std::uint32_t reserved = 0;
  put(&reserved, 4);
  for (int b : run.bodies) {
    const std::int32_t i = b;
    put(&i, 4);
  }
  for (std::size_t k : picked) put_f(run.samples[k].time);
  for (std::size_t k : picked) {
    const Sample& s = run.samples[k];
    for (std::size_t b = 0; b < layout.bodies; ++b) {
      const SampledState& st = s.bodies.at(b);
      for (int i = 0; i < 3; ++i) put_f(st.position[i]);
      const Quat q = st.orientation.normalized();
      put_f(q.x());
      put_f(q.y());
      put_f(q.z());
      put_f(q.w());
      put_f(st.linear_velocity.norm());
    }
  }
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!out) throw std::runtime_error("cannot write " + path.string());
}

}  // namespace physbench
