// Clipping a hull face to a manifold (the seed's choice): the incident face against the reference
// face's side planes (Sutherland–Hodgman), and the edge–edge point. Two boxes clip by candidates in
// their own frame instead (narrowphase_box.cpp), so the hull path is the only user.
//
// A header, included by narrowphase_hull.cpp alone, with internal linkage (as
// narrowphase_internal.h explains): the compiler inlines the clip into collide_hulls as it did when
// the narrow phase was one file, which keeps the native build's results bit for bit.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>

#include "narrowphase_internal.h"

namespace rtp::detail {
namespace {

struct ClipVertex {
  Vec3 point;
  ContactFeature feature;
};

// the vertices of a clipped hull face: the incident face plus one per side plane (boxes clip in
// their own frame, by candidates: collide_boxes)
constexpr std::size_t kHullClip = 2 * kMaxFaceVertices + 2;

// a polygon being clipped
struct ClipPolygon {
  std::array<ClipVertex, kHullClip> vertices;
  std::size_t count = 0;
};

// the reference face in the world: its plane and its side planes (normals need not be unit)
struct ReferenceFace {
  Vec3 normal;    // unit, outward
  double offset;  // normal · x = offset on the face
  std::array<Vec3, kMaxFaceVertices> side_normals;
  std::array<double, kMaxFaceVertices> side_offsets;
  std::size_t side_count = 0;
  std::uint16_t face = 0;
};

// Sutherland–Hodgman: the part of the polygon where side · x ≤ offset
void clip_against_side(const ClipPolygon& in, const Vec3& side, double offset,
                       std::uint8_t side_index, ClipPolygon& out) {
  out.count = 0;
  if (in.count == 0) return;
  const ClipVertex* previous = &in.vertices[in.count - 1];
  double previous_distance = side.dot(previous->point) - offset;
  for (std::size_t i = 0; i < in.count; ++i) {
    const ClipVertex& current = in.vertices[i];
    const double distance = side.dot(current.point) - offset;
    if ((previous_distance <= 0.0) != (distance <= 0.0)) {
      // the edge previous → current crosses the side plane: a new point on the incident edge
      // that starts at previous's incident vertex
      const double t = previous_distance / (previous_distance - distance);
      ClipVertex& crossing = out.vertices[out.count++];
      crossing.point = previous->point + t * (current.point - previous->point);
      crossing.feature = previous->feature;
      crossing.feature.type = ContactType::FaceClip;
      crossing.feature.reference_side = side_index;
    }
    if (distance <= 0.0) out.vertices[out.count++] = current;
    previous = &current;
    previous_distance = distance;
  }
}

// clips the incident polygon to the reference face and writes the manifold; `flipped` when the
// second shape holds the reference face (the manifold's normal then opposes the face's)
void clip_to_manifold(const ReferenceFace& reference, const ClipPolygon& incident, bool flipped,
                      double depth, Manifold& out) {
  ClipPolygon buffers[2];
  const ClipPolygon* current = &incident;
  for (std::size_t s = 0; s < reference.side_count; ++s) {
    ClipPolygon& next = buffers[s % 2];
    clip_against_side(*current, reference.side_normals[s], reference.side_offsets[s],
                      std::uint8_t(s), next);
    current = &next;
  }

  // points on or below the reference face, placed midway between the two surfaces
  std::array<ContactPoint, kHullClip> points;
  std::size_t count = 0;
  for (std::size_t i = 0; i < current->count; ++i) {
    const ClipVertex& v = current->vertices[i];
    const double distance = reference.normal.dot(v.point) - reference.offset;
    if (distance > 0.0) continue;
    ContactPoint& p = points[count++];
    p.point = v.point - 0.5 * distance * reference.normal;
    p.depth = -distance;
    p.feature = v.feature;
    p.feature.reference = reference.face;
    p.feature.flipped = flipped;
  }
  if (count > 4) reduce_to_four(points, count, reference.normal);

  out.normal = flipped ? Vec3(-reference.normal) : reference.normal;
  out.depth = depth;
  out.count = std::uint8_t(count);
  std::copy(points.begin(), points.begin() + count, out.points.begin());
}

// the closest points of segments p1 + s d1 and p2 + t d2, s, t ∈ [0, 1] (Ericson §5.1.9)
void closest_points_of_segments(const Vec3& p1, const Vec3& d1, const Vec3& p2, const Vec3& d2,
                                Vec3& c1, Vec3& c2) {
  const Vec3 r = p1 - p2;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  const double c = d1.dot(r), b = d1.dot(d2);
  const double denominator = a * e - b * b;
  double s = denominator > 1e-30 ? std::clamp((b * f - c * e) / denominator, 0.0, 1.0) : 0.0;
  double t = (b * s + f) / e;
  if (t < 0.0) {
    t = 0.0;
    s = std::clamp(-c / a, 0.0, 1.0);
  } else if (t > 1.0) {
    t = 1.0;
    s = std::clamp((b - c) / a, 0.0, 1.0);
  }
  c1 = p1 + s * d1;
  c2 = p2 + t * d2;
}

// the reference face `face` of a hull at a pose, with its side planes
void reference_face_of(const ConvexHull& hull, const Pose& pose, std::uint32_t face,
                       ReferenceFace& out) {
  const HullFace& f = hull.faces[face];
  out.normal = pose.rotation * f.normal;
  out.offset = f.offset + out.normal.dot(pose.position);
  out.face = std::uint16_t(face);
  out.side_count = f.count;
  Vec3 tail = pose.position + pose.rotation * hull.vertices[hull.face_vertices[f.first]];
  for (std::uint32_t i = 0; i < f.count; ++i) {
    const Vec3 head =
        pose.position +
        pose.rotation * hull.vertices[hull.face_vertices[f.first + (i + 1) % f.count]];
    // for a counter-clockwise loop, edge × normal points out of the face
    out.side_normals[i] = (head - tail).cross(out.normal);
    out.side_offsets[i] = out.side_normals[i].dot(tail);
    tail = head;
  }
}

void incident_face_of(const ConvexHull& hull, const Pose& pose, std::uint32_t face,
                      ClipPolygon& out) {
  const HullFace& f = hull.faces[face];
  out.count = f.count;
  for (std::uint32_t i = 0; i < f.count; ++i) {
    out.vertices[i].point =
        pose.position + pose.rotation * hull.vertices[hull.face_vertices[f.first + i]];
    out.vertices[i].feature = {0, std::uint16_t(face), 0, std::uint8_t(i), ContactType::FaceVertex,
                               0};
  }
}

// the incident face for a reference normal (world): among the faces around the incident hull's
// deepest vertex, the one most opposed to the normal. The most opposed face of the whole hull
// can lie beside the contact on a hull of many small faces; the faces at the deepest vertex hold
// the deepest point.
std::uint32_t incident_face_for(const ConvexHull& hull, const Pose& pose,
                                const Vec3& reference_normal) {
  const Vec3 local = pose.rotation.transpose() * reference_normal;
  std::uint32_t deepest = 0;
  for (std::uint32_t i = 1; i < hull.vertices.size(); ++i)
    if (hull.vertices[i].dot(local) < hull.vertices[deepest].dot(local)) deepest = i;
  std::uint32_t best = 0;
  double most_opposed = std::numeric_limits<double>::infinity();
  for (std::uint32_t f = 0; f < hull.faces.size(); ++f) {
    const HullFace& face = hull.faces[f];
    const double alignment = face.normal.dot(local);
    if (alignment >= most_opposed) continue;
    for (std::uint32_t i = 0; i < face.count; ++i)
      if (hull.face_vertices[face.first + i] == deepest) {
        most_opposed = alignment, best = f;
        break;
      }
  }
  return best;
}

// the face-contact manifold when `reference_face` of the reference hull is the separating axis
void hull_face_manifold(const ConvexHull& reference_hull, const Pose& reference_pose,
                        std::uint32_t reference_face, const ConvexHull& incident_hull,
                        const Pose& incident_pose, bool flipped, double depth, Manifold& out) {
  ReferenceFace reference;
  reference_face_of(reference_hull, reference_pose, reference_face, reference);
  ClipPolygon incident;
  incident_face_of(incident_hull, incident_pose,
                   incident_face_for(incident_hull, incident_pose, reference.normal), incident);
  clip_to_manifold(reference, incident, flipped, depth, out);
}

// one edge–edge contact point midway between the edges' closest points
void edge_contact(const Vec3& tail_a, const Vec3& edge_a, const Vec3& tail_b, const Vec3& edge_b,
                  const Vec3& normal, double depth, std::uint16_t feature_a,
                  std::uint16_t feature_b, Manifold& out) {
  Vec3 on_a, on_b;
  closest_points_of_segments(tail_a, edge_a, tail_b, edge_b, on_a, on_b);
  out.normal = normal;
  out.depth = depth;
  out.count = 1;
  out.points[0].point = 0.5 * (on_a + on_b);
  out.points[0].depth = depth;
  out.points[0].feature = {feature_a, feature_b, 0, 0, ContactType::EdgeEdge, 0};
}

}  // namespace
}  // namespace rtp::detail
