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

// the poses' part of the file: header, body indices, times, poses
std::uint64_t pose_bytes(std::uint64_t frames, std::uint64_t bodies) {
  return kHeaderBytes + 4 * bodies + 4 * frames + 4ull * kPoseFloats * frames * bodies;
}

// the contact sections: each contact frame's body depths and point count, and the points
std::uint64_t contact_bytes(std::uint64_t contact_frames, std::uint64_t bodies,
                            std::uint64_t points) {
  return 4 * contact_frames * bodies + 4 * contact_frames + 4ull * kContactFloats * points;
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
  const std::size_t samples = run.samples.size();
  if (samples == 0 || layout.bodies == 0) return layout;
  std::size_t stride = 1;
  if (samples > 1) {
    const double interval = run.samples[1].time - run.samples[0].time;
    if (interval > 0.0)
      stride = std::max<std::size_t>(1, std::lround(1.0 / (kPoseFrameRate * interval)));
  }
  // the poses first: fewer frames per second until they fit; at least the first and last sample
  std::vector<std::size_t> picked = picked_samples(samples, stride);
  while (picked.size() > 2 && pose_bytes(picked.size(), layout.bodies) > byte_cap)
    picked = picked_samples(samples, ++stride);
  if (pose_bytes(picked.size(), layout.bodies) > byte_cap) return layout;
  layout.frames = static_cast<std::uint32_t>(picked.size());
  layout.stride = static_cast<std::uint32_t>(stride);
  layout.bytes = pose_bytes(layout.frames, layout.bodies);
  if (!contacts) return layout;

  // then the contacts in what the cap leaves: those of every contact_stride-th frame from the
  // first, the stride growing until they fit, or none; each frame's points measured once
  constexpr std::uint64_t kUnmeasured = ~std::uint64_t{0};
  std::vector<std::uint64_t> points_at(picked.size(), kUnmeasured);
  Overlaps overlaps;
  for (std::size_t contact_stride = 1; contact_stride <= picked.size(); ++contact_stride) {
    std::uint64_t contact_frames = 0, points = 0;
    for (std::size_t f = 0; f < picked.size(); f += contact_stride, ++contact_frames) {
      if (points_at[f] == kUnmeasured) {
        contacts->measure(run.samples[picked[f]], overlaps);
        points_at[f] = overlaps.points.size();
      }
      points += points_at[f];
    }
    const std::uint64_t bytes = layout.bytes + contact_bytes(contact_frames, layout.bodies, points);
    if (bytes > byte_cap) continue;
    layout.contact_stride = static_cast<std::uint32_t>(contact_stride);
    layout.contact_frames = static_cast<std::uint32_t>(contact_frames);
    layout.contact_points = points;
    layout.bytes = bytes;
    break;
  }
  return layout;
}

void write_pose_file(const std::filesystem::path& path, const Trajectory& run,
                     const PoseLayout& layout, const OverlapGauge* contacts) {
  if (layout.frames == 0) throw std::invalid_argument("write_pose_file: no frames to write");
  const std::vector<std::size_t> picked = picked_samples(run.samples.size(), layout.stride);
  if (picked.size() != layout.frames || (layout.contact_stride > 0 && !contacts))
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
  const std::uint32_t sections = layout.contact_stride > 0 ? kPoseSectionContacts : 0;
  const std::uint32_t contact_points = static_cast<std::uint32_t>(layout.contact_points);
  put(&sections, 4);
  put(&contact_points, 4);
  put(&layout.contact_stride, 4);
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
  if (layout.contact_stride > 0) {
    // each contact frame's body depths, then its point counts, then the points: counts first, so
    // a reader finds a frame's points without walking the ones before
    std::vector<Overlaps> frames(layout.contact_frames);
    for (std::size_t j = 0; j < frames.size(); ++j)
      contacts->measure(run.samples[picked[j * layout.contact_stride]], frames[j]);
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
