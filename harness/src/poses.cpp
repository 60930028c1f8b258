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

constexpr std::uint64_t kHeaderBytes = 32;

// the whole file: header, body indices, times, poses, and with contacts each body's depth per
// frame, the points per frame and the points
std::uint64_t file_bytes(std::uint64_t frames, std::uint64_t bodies, bool contacts,
                         std::uint64_t contact_points) {
  std::uint64_t bytes =
      kHeaderBytes + 4 * bodies + 4 * frames + 4ull * kPoseFloats * frames * bodies;
  if (contacts) bytes += 4 * frames * bodies + 4 * frames + 4ull * kContactFloats * contact_points;
  return bytes;
}

// the samples kept as frames: every stride-th, and the last even when the stride steps over it
std::vector<std::size_t> picked_samples(std::size_t samples, std::size_t stride) {
  std::vector<std::size_t> picked;
  for (std::size_t k = 0; k < samples; k += stride) picked.push_back(k);
  if (samples > 0 && picked.back() != samples - 1) picked.push_back(samples - 1);
  return picked;
}

}  // namespace

PoseLayout pose_layout(const Trajectory& run, const OverlapGauge* contacts,
                       std::uint64_t byte_cap) {
  PoseLayout layout;
  layout.bodies = static_cast<std::uint32_t>(run.bodies.size());
  layout.contacts = contacts != nullptr;
  const std::size_t samples = run.samples.size();
  if (samples == 0 || layout.bodies == 0) return layout;
  std::size_t stride = 1;
  if (samples > 1) {
    const double interval = run.samples[1].time - run.samples[0].time;
    if (interval > 0.0)
      stride = std::max<std::size_t>(1, std::lround(1.0 / (kPoseFrameRate * interval)));
  }
  // each sample's contact points, measured once when a stride first picks it
  constexpr std::uint64_t kUnmeasured = ~std::uint64_t{0};
  std::vector<std::uint64_t> points_at(samples, kUnmeasured);
  Overlaps overlaps;
  auto bytes_at = [&](std::size_t stride_now, std::uint32_t& frames, std::uint64_t& points) {
    const std::vector<std::size_t> picked = picked_samples(samples, stride_now);
    frames = static_cast<std::uint32_t>(picked.size());
    points = 0;
    if (contacts)
      for (std::size_t k : picked) {
        if (points_at[k] == kUnmeasured) {
          contacts->measure(run.samples[k], overlaps);
          points_at[k] = overlaps.points.size();
        }
        points += points_at[k];
      }
    return file_bytes(frames, layout.bodies, layout.contacts, points);
  };
  // fewer frames per second until the file fits; at least the first and last sample
  std::uint32_t frames = 0;
  std::uint64_t points = 0;
  while (bytes_at(stride, frames, points) > byte_cap && frames > 2) ++stride;
  const std::uint64_t bytes = bytes_at(stride, frames, points);
  if (bytes > byte_cap) return layout;
  layout.frames = frames;
  layout.stride = static_cast<std::uint32_t>(stride);
  layout.contact_points = points;
  layout.bytes = bytes;
  return layout;
}

void write_pose_file(const std::filesystem::path& path, const Trajectory& run,
                     const PoseLayout& layout, const OverlapGauge* contacts) {
  if (layout.frames == 0) throw std::invalid_argument("write_pose_file: no frames to write");
  const std::vector<std::size_t> picked = picked_samples(run.samples.size(), layout.stride);
  if (picked.size() != layout.frames || layout.contacts != (contacts != nullptr))
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
  put("PBPOSES2", 8);
  put(&layout.frames, 4);
  put(&layout.bodies, 4);
  put_f(picked.size() > 1 ? run.samples[picked[1]].time - run.samples[picked[0]].time : 0.0);
  const std::uint32_t sections = layout.contacts ? kPoseSectionContacts : 0;
  const std::uint32_t contact_points = static_cast<std::uint32_t>(layout.contact_points);
  const std::uint32_t reserved = 0;
  put(&sections, 4);
  put(&contact_points, 4);
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
  if (contacts) {
    // each body's deepest penetration per frame, then the points: counts first, so a reader
    // finds frame k's points without walking the ones before
    std::vector<Overlaps> frames(picked.size());
    for (std::size_t f = 0; f < picked.size(); ++f)
      contacts->measure(run.samples[picked[f]], frames[f]);
    for (const Overlaps& o : frames)
      for (double depth : o.body_depth) put_f(depth);
    std::uint64_t written = 0;
    for (const Overlaps& o : frames) {
      const std::uint32_t count = static_cast<std::uint32_t>(o.points.size());
      put(&count, 4);
      written += count;
    }
    if (written != layout.contact_points)
      throw std::logic_error("write_pose_file: the contacts differ from the layout's");
    for (const Overlaps& o : frames)
      for (const OverlapPoint& point : o.points) {
        for (int i = 0; i < 3; ++i) put_f(point.point[i]);
        put_f(point.depth);
      }
  }
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!out) throw std::runtime_error("cannot write " + path.string());
}

}  // namespace physbench
