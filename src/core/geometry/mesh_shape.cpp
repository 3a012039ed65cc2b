#include "pbd_cloth/geometry/mesh_shape.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <stdexcept>
#include <tuple>
#include <utility>

#include "pbd_cloth/geometry/triangle_queries.h"

namespace pbd_cloth {

namespace {

// Triangles per leaf of the tree: a few exact triangle tests are cheaper than another box level.
constexpr int kLeafSize = 4;

double boxDistanceSquared(const Vec3& x, const Vec3& lo, const Vec3& hi) {
  return (lo - x).cwiseMax(x - hi).cwiseMax(0.0).squaredNorm();
}

}  // namespace

TriangleMesh::TriangleMesh(std::vector<Vec3> vertices, std::vector<Triangle> triangles) {
  // Weld corners at identical positions: the pseudo-normals need the mesh's connectivity.
  std::map<std::tuple<double, double, double>, int> welded;
  std::vector<int> remap(vertices.size());
  for (std::size_t v = 0; v < vertices.size(); ++v) {
    const Vec3& x = vertices[v];
    if (!x.allFinite()) {
      throw std::invalid_argument("vertex " + std::to_string(v) + " is not finite");
    }
    const auto key = std::make_tuple(x.x(), x.y(), x.z());
    const auto found = welded.find(key);
    if (found != welded.end()) {
      remap[v] = found->second;
    } else {
      remap[v] = static_cast<int>(vertices_.size());
      welded.emplace(key, remap[v]);
      vertices_.push_back(x);
    }
  }
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    Triangle tri = triangles[t];
    for (int& index : tri) {
      if (index < 0 || static_cast<std::size_t>(index) >= vertices.size()) {
        throw std::invalid_argument("triangle " + std::to_string(t) + " has vertex index " +
                                    std::to_string(index) + " out of range [0, " +
                                    std::to_string(vertices.size()) + ")");
      }
      index = remap[index];
    }
    const Vec3 n =
        (vertices_[tri[1]] - vertices_[tri[0]]).cross(vertices_[tri[2]] - vertices_[tri[0]]);
    // A zero-area triangle has no normal and no surface of its own: its edges belong to the
    // neighbours, which carry the distance.
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[2] == tri[0] || !(n.norm() > 0.0)) {
      ++degenerate_triangles_;
      continue;
    }
    triangles_.push_back(tri);
    face_normals_.push_back(n.normalized());
  }
  if (triangles_.empty()) {
    throw std::invalid_argument("no triangle with a non-zero area (of " +
                                std::to_string(triangles.size()) + ")");
  }

  // Pseudo-normals (Baerentzen and Aanaes 2005): an edge's is the sum of its faces' normals, a
  // vertex's the sum of its faces' normals weighted by the face's angle at the vertex.
  std::map<std::pair<int, int>, std::vector<std::pair<int, int>>> edge_faces;  // -> (tri, k)
  vertex_normals_.assign(vertices_.size(), Vec3::Zero());
  for (std::size_t t = 0; t < triangles_.size(); ++t) {
    const Triangle& tri = triangles_[t];
    for (int k = 0; k < 3; ++k) {
      const int a = tri[k], b = tri[(k + 1) % 3], c = tri[(k + 2) % 3];
      edge_faces[std::minmax(a, b)].emplace_back(static_cast<int>(t), k);
      const Vec3 u = (vertices_[b] - vertices_[a]).normalized();
      const Vec3 w = (vertices_[c] - vertices_[a]).normalized();
      const double angle = std::acos(std::clamp(u.dot(w), -1.0, 1.0));
      vertex_normals_[a] += angle * face_normals_[t];
    }
  }
  edge_normals_.assign(triangles_.size(), {Vec3::Zero(), Vec3::Zero(), Vec3::Zero()});
  for (const auto& entry : edge_faces) {
    Vec3 sum = Vec3::Zero();
    for (const auto& face : entry.second) sum += face_normals_[face.first];
    for (const auto& face : entry.second) edge_normals_[face.first][face.second] = sum;
    if (entry.second.size() == 1) ++boundary_edges_;
  }

  // The tree: top-down, split at the median centroid along the widest axis of the centroids.
  order_.resize(triangles_.size());
  std::iota(order_.begin(), order_.end(), 0);
  std::vector<Vec3> centroids(triangles_.size());
  for (std::size_t t = 0; t < triangles_.size(); ++t) {
    const Triangle& tri = triangles_[t];
    centroids[t] = (vertices_[tri[0]] + vertices_[tri[1]] + vertices_[tri[2]]) / 3.0;
  }
  nodes_.reserve(2 * triangles_.size() / kLeafSize + 2);
  build(0, static_cast<int>(triangles_.size()), centroids);
  lo_ = nodes_[0].lo;
  hi_ = nodes_[0].hi;
}

int TriangleMesh::build(int begin, int end, std::vector<Vec3>& centroids) {
  const int index = static_cast<int>(nodes_.size());
  nodes_.emplace_back();
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity());
  Vec3 hi = -lo;
  Vec3 c_lo = lo, c_hi = hi;
  for (int k = begin; k < end; ++k) {
    const Triangle& tri = triangles_[order_[k]];
    for (int v : tri) {
      lo = lo.cwiseMin(vertices_[v]);
      hi = hi.cwiseMax(vertices_[v]);
    }
    c_lo = c_lo.cwiseMin(centroids[order_[k]]);
    c_hi = c_hi.cwiseMax(centroids[order_[k]]);
  }
  nodes_[index].lo = lo;
  nodes_[index].hi = hi;
  if (end - begin <= kLeafSize) {
    nodes_[index].first = begin;
    nodes_[index].count = end - begin;
    return index;
  }
  int axis = 0;
  (c_hi - c_lo).maxCoeff(&axis);
  const int middle = begin + (end - begin) / 2;
  std::nth_element(order_.begin() + begin, order_.begin() + middle, order_.begin() + end,
                   [&](int a, int b) { return centroids[a][axis] < centroids[b][axis]; });
  const int left = build(begin, middle, centroids);
  const int right = build(middle, end, centroids);
  nodes_[index].first = left;
  nodes_[index].count = 0;
  nodes_[index].right = right;
  return index;
}

double TriangleMesh::signedDistance(const Vec3& x, Vec3& normal, int* hint) const {
  // Depth-first, nearer child first, pruning boxes farther than the best triangle so far. A fixed
  // stack: the tree is balanced (median splits), so its depth is log2 of the triangle count.
  int stack[64];
  int top = 0;
  stack[top++] = 0;
  double best = std::numeric_limits<double>::infinity();
  Vec3 closest = Vec3::Zero();
  int best_triangle = 0;
  TriangleFeature best_feature = TriangleFeature::kFace;
  int best_index = 0;
  const auto test_triangle = [&](int t) {
    const Triangle& tri = triangles_[t];
    TriangleFeature feature;
    int index;
    const Vec3 c = closestPointOnTriangle(x, vertices_[tri[0]], vertices_[tri[1]],
                                          vertices_[tri[2]], feature, index);
    const double d2 = (x - c).squaredNorm();
    if (d2 < best) {
      best = d2;
      closest = c;
      best_triangle = t;
      best_feature = feature;
      best_index = index;
    }
  };
  if (hint != nullptr && *hint >= 0 && *hint < static_cast<int>(triangles_.size())) {
    test_triangle(*hint);
  }
  while (top > 0) {
    const Node& node = nodes_[stack[--top]];
    if (boxDistanceSquared(x, node.lo, node.hi) >= best) continue;
    if (node.count > 0) {
      for (int k = node.first; k < node.first + node.count; ++k) test_triangle(order_[k]);
      continue;
    }
    const Node& left = nodes_[node.first];
    const Node& right = nodes_[node.right];
    const double dl = boxDistanceSquared(x, left.lo, left.hi);
    const double dr = boxDistanceSquared(x, right.lo, right.hi);
    // Push the farther child first so the nearer one is searched first.
    if (dl < dr) {
      if (dr < best) stack[top++] = node.right;
      if (dl < best) stack[top++] = node.first;
    } else {
      if (dl < best) stack[top++] = node.first;
      if (dr < best) stack[top++] = node.right;
    }
  }
  if (hint != nullptr) *hint = best_triangle;
  Vec3 pseudo_normal = Vec3::Zero();
  switch (best_feature) {
    case TriangleFeature::kFace:
      pseudo_normal = face_normals_[best_triangle];
      break;
    case TriangleFeature::kEdge:
      pseudo_normal = edge_normals_[best_triangle][best_index];
      break;
    case TriangleFeature::kVertex:
      pseudo_normal = vertex_normals_[triangles_[best_triangle][best_index]];
      break;
  }
  const Vec3 away = x - closest;
  const double distance = std::sqrt(best);
  // Outside when the point lies on the side the pseudo-normal points to (the theorem of
  // Baerentzen and Aanaes); an open shell has no inside, only two sides.
  const bool inside = closed() && away.dot(pseudo_normal) < 0.0;
  if (distance > 0.0) {
    normal = (inside ? -away : away) / distance;
  } else {
    normal = pseudo_normal.normalized();
  }
  return inside ? -distance : distance;
}

std::size_t TriangleMesh::memoryBytes() const {
  return vertices_.size() * sizeof(Vec3) + triangles_.size() * sizeof(Triangle) +
         face_normals_.size() * sizeof(Vec3) + edge_normals_.size() * sizeof(edge_normals_[0]) +
         vertex_normals_.size() * sizeof(Vec3) + nodes_.size() * sizeof(Node) +
         order_.size() * sizeof(int);
}

}  // namespace pbd_cloth
