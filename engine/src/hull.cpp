// Collision meshes: the box's by hand, any other convex point set's by qhull; both finished by
// one pass that derives edges, unique edge directions and unique face normals from the faces.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>

#include "rtp/collision.h"

extern "C" {
#include <libqhull_r/qhull_ra.h>
}

namespace rtp {
namespace {

// two unit vectors closer than this in angle (rad) are one direction
constexpr double kDirectionTolerance = 1e-6;

// adds v to the list unless it or −v is there already
void add_unique_direction(std::vector<Vec3>& directions, const Vec3& v) {
  for (const Vec3& d : directions)
    if (d.cross(v).norm() < kDirectionTolerance && std::abs(d.dot(v)) > 0.5) return;
  directions.push_back(v);
}

void fill_columns(const std::vector<Vec3>& points, PointColumns& columns) {
  const std::size_t n = points.size(), padded = (n + 7) / 8 * 8;
  columns.count = n;
  for (auto* column : {&columns.x, &columns.y, &columns.z}) column->resize(padded);
  for (std::size_t i = 0; i < padded; ++i) {
    const Vec3& p = points[i < n ? i : 0];
    columns.x[i] = p.x(), columns.y[i] = p.y(), columns.z[i] = p.z();
  }
}

// edges (each once, with the faces either side), unique directions, unique normals, centre,
// the columns of the vertices and unique normals;
// throws when the faces do not close into a polyhedron
void finish_topology(ConvexHull& hull) {
  hull.centre = Vec3::Zero();
  for (const Vec3& v : hull.vertices) hull.centre += v;
  hull.centre /= double(hull.vertices.size());

  // each directed edge tail → head is counter-clockwise in exactly one face; its twin in another
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> face_of_directed_edge;
  for (std::uint32_t f = 0; f < hull.faces.size(); ++f) {
    const HullFace& face = hull.faces[f];
    for (std::uint32_t i = 0; i < face.count; ++i) {
      const std::uint32_t tail = hull.face_vertices[face.first + i];
      const std::uint32_t head = hull.face_vertices[face.first + (i + 1) % face.count];
      if (!face_of_directed_edge.emplace(std::pair{tail, head}, f).second)
        throw std::invalid_argument("rtp: hull edge " + std::to_string(tail) + "-" +
                                    std::to_string(head) + " appears twice in one direction");
    }
  }
  hull.edges.clear();
  for (const auto& [edge, left] : face_of_directed_edge) {
    const auto twin = face_of_directed_edge.find({edge.second, edge.first});
    if (twin == face_of_directed_edge.end())
      throw std::invalid_argument("rtp: hull edge " + std::to_string(edge.first) + "-" +
                                  std::to_string(edge.second) + " borders only one face");
    if (edge.first < edge.second)
      hull.edges.push_back({edge.first, edge.second, left, twin->second});
  }

  hull.unique_edge_directions.clear();
  for (const HullEdge& edge : hull.edges)
    add_unique_direction(hull.unique_edge_directions,
                         (hull.vertices[edge.head] - hull.vertices[edge.tail]).normalized());
  hull.unique_face_normals.clear();
  for (const HullFace& face : hull.faces)
    add_unique_direction(hull.unique_face_normals, face.normal);
  hull.unique_normal_faces.assign(hull.unique_face_normals.size(), {kNoFace, kNoFace});
  for (std::uint32_t f = 0; f < hull.faces.size(); ++f)
    for (std::size_t k = 0; k < hull.unique_face_normals.size(); ++k) {
      const double cosine = hull.faces[f].normal.dot(hull.unique_face_normals[k]);
      if (std::abs(cosine) > 0.5 &&
          hull.faces[f].normal.cross(hull.unique_face_normals[k]).norm() < kDirectionTolerance)
        hull.unique_normal_faces[k][cosine > 0.0 ? 0 : 1] = f;
    }
  fill_columns(hull.vertices, hull.vertex_columns);
  fill_columns(hull.unique_face_normals, hull.normal_columns);
}

// frees qhull's memory however the computation ended
struct QhullSession {
  qhT state;
  std::FILE* errors = nullptr;
  char* error_text = nullptr;
  std::size_t error_size = 0;
  QhullSession() {
    errors = open_memstream(&error_text, &error_size);
    qh_zero(&state, errors);
  }
  ~QhullSession() {
    int current_long = 0, total_long = 0;
    qh_freeqhull(&state, !qh_ALL);
    qh_memfreeshort(&state, &current_long, &total_long);
    if (errors) std::fclose(errors);
    std::free(error_text);
  }
  std::string error_message() {
    if (errors) std::fflush(errors);
    std::string text = error_text ? std::string(error_text, error_size) : std::string();
    // qhull's first line names the problem (QH6154 "initial simplex is flat", …)
    return text.substr(0, text.find('\n'));
  }
};

}  // namespace

ConvexHull make_box_hull(const Vec3& half_extents) {
  if (!half_extents.allFinite() || (half_extents.array() <= 0.0).any())
    throw std::invalid_argument("rtp: box half extents must be finite and positive");
  ConvexHull hull;
  for (std::uint32_t i = 0; i < 8; ++i)
    hull.vertices.emplace_back((i & 1 ? 1.0 : -1.0) * half_extents.x(),
                               (i & 2 ? 1.0 : -1.0) * half_extents.y(),
                               (i & 4 ? 1.0 : -1.0) * half_extents.z());
  // faces +x, −x, +y, −y, +z, −z, each loop counter-clockwise seen from outside
  const std::uint32_t loops[6][4] = {{1, 3, 7, 5}, {0, 4, 6, 2}, {2, 6, 7, 3},
                                     {0, 1, 5, 4}, {4, 5, 7, 6}, {0, 2, 3, 1}};
  for (std::uint32_t f = 0; f < 6; ++f) {
    Vec3 normal = Vec3::Zero();
    normal[f / 2] = f % 2 == 0 ? 1.0 : -1.0;
    hull.faces.push_back(
        {normal, half_extents[f / 2], std::uint32_t(hull.face_vertices.size()), 4});
    hull.face_vertices.insert(hull.face_vertices.end(), loops[f], loops[f] + 4);
  }
  finish_topology(hull);
  return hull;
}

ConvexHull make_convex_hull(std::span<const Vec3> points) {
  for (std::size_t i = 0; i < points.size(); ++i)
    if (!points[i].allFinite())
      throw std::invalid_argument("rtp: hull point " + std::to_string(i) + " is not finite");
  if (points.size() < 4)
    throw std::invalid_argument("rtp: a hull needs at least 4 points, got " +
                                std::to_string(points.size()));

  std::vector<coordT> coordinates;
  coordinates.reserve(points.size() * 3);
  for (const Vec3& p : points) coordinates.insert(coordinates.end(), {p.x(), p.y(), p.z()});

  // "qhull" alone merges coplanar facets in 3-d ('C-0'), so faces come out as polygons
  QhullSession session;
  qhT* qh = &session.state;
  char options[] = "qhull";
  if (qh_new_qhull(qh, 3, int(points.size()), coordinates.data(), False, options, nullptr,
                   session.errors) != 0)
    throw std::invalid_argument("rtp: qhull could not build a hull of " +
                                std::to_string(points.size()) +
                                " points (flat or degenerate?): " + session.error_message());

  ConvexHull hull;
  std::map<int, std::uint32_t> index_of_point;  // qhull point id → hull vertex
  facetT* facet;
  FORALLfacets {
    const Vec3 normal(facet->normal[0], facet->normal[1], facet->normal[2]);
    // the face's vertices ordered counter-clockwise about its normal, by angle round their mean
    std::vector<std::pair<double, std::uint32_t>> loop;
    Vec3 mean = Vec3::Zero();
    vertexT *vertex, **vertexp;
    FOREACHvertex_(facet->vertices) {
      const int id = qh_pointid(qh, vertex->point);
      auto [it, inserted] = index_of_point.emplace(id, std::uint32_t(hull.vertices.size()));
      if (inserted) hull.vertices.push_back(points[std::size_t(id)]);
      loop.emplace_back(0.0, it->second);
      mean += hull.vertices[it->second];
    }
    mean /= double(loop.size());
    const Vec3 u = (hull.vertices[loop[0].second] - mean).normalized();
    const Vec3 v = normal.cross(u);
    for (auto& [angle, index] : loop) {
      const Vec3 r = hull.vertices[index] - mean;
      angle = std::atan2(r.dot(v), r.dot(u));
    }
    std::sort(loop.begin(), loop.end());
    if (loop.size() > kMaxFaceVertices)
      throw std::invalid_argument("rtp: a hull face has " + std::to_string(loop.size()) +
                                  " vertices; at most " + std::to_string(kMaxFaceVertices));
    // the plane through the face's outermost vertex, so that every vertex is inside or on it
    double offset = -std::numeric_limits<double>::infinity();
    for (const auto& entry : loop)
      offset = std::max(offset, normal.dot(hull.vertices[entry.second]));
    hull.faces.push_back(
        {normal, offset, std::uint32_t(hull.face_vertices.size()), std::uint32_t(loop.size())});
    for (const auto& entry : loop) hull.face_vertices.push_back(entry.second);
  }
  if (hull.vertices.size() > kMaxHullVertices)
    throw std::invalid_argument("rtp: the hull has " + std::to_string(hull.vertices.size()) +
                                " vertices; at most " + std::to_string(kMaxHullVertices) +
                                " (simplify the point set)");
  finish_topology(hull);
  return hull;
}

}  // namespace rtp
