// A closed triangle mesh as a collision shape: exact signed distance by closest-triangle queries
// over an axis-aligned bounding-box tree (no grid, no convex hull), so non-convex cavities and
// holes are kept exactly: a particle inside a mug stays inside, a rope hangs through a torus's
// hole.
//
// Sign: the angle-weighted pseudo-normal of the closest feature (face, edge or vertex; Baerentzen
// and Aanaes 2005, "Signed distance computation using the angle weighted pseudonormal"): for a
// closed, consistently oriented mesh, sign(n_feature . (x - closest)) is the inside/outside test.
// The distance is the exact Euclidean distance to the surface, hence 1-Lipschitz, which the
// swept-sphere query of the collisions relies on (shapes.h sweepSphere).
//
// An open mesh (boundary edges) has no inside: it is handled as a two-sided shell of zero
// thickness (unsigned distance), so a particle stays on the side it came from; the loader warns.
// ROS-free: vertices and triangles come from the scene reader (scene_assets.h, assimp).
#pragma once

#include <array>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace pbd_cloth {

class TriangleMesh {
 public:
  using Vec3 = Eigen::Vector3d;
  using Triangle = std::array<int, 3>;

  // Welds vertices at identical positions (STL stores every triangle's corners on their own),
  // drops degenerate (zero-area) triangles, finds boundary edges and builds the tree. Throws
  // std::invalid_argument when no non-degenerate triangle remains or an index is out of range.
  TriangleMesh(std::vector<Vec3> vertices, std::vector<Triangle> triangles);

  // Signed distance of x (mesh frame) to the surface, negative inside (closed meshes only), and
  // the outward unit normal of the shortest way to the surface.
  // `hint` (optional, in and out): a triangle likely to be near x, e.g. the closest one of the same
  // particle's last query. Its distance bounds the search from the start, so the tree walk prunes
  // almost everything for a point that moved little (temporal coherence). Any value is safe: an
  // out-of-range hint is ignored; on return it holds the closest triangle.
  double signedDistance(const Vec3& x, Vec3& normal, int* hint = nullptr) const;

  bool closed() const { return boundary_edges_ == 0; }
  int boundaryEdges() const { return boundary_edges_; }
  int degenerateTriangles() const { return degenerate_triangles_; }
  int vertexCount() const { return static_cast<int>(vertices_.size()); }
  int triangleCount() const { return static_cast<int>(triangles_.size()); }
  const std::vector<Vec3>& vertices() const { return vertices_; }
  const std::vector<Triangle>& triangles() const { return triangles_; }
  const Vec3& boundsMin() const { return lo_; }
  const Vec3& boundsMax() const { return hi_; }
  // Bytes held by vertices, triangles, normals and the tree (doc/scenes.md "Shapes").
  std::size_t memoryBytes() const;

 private:
  struct Node {
    Vec3 lo, hi;
    int first = 0;   // leaf: first triangle in order_; inner: index of the left child
    int count = 0;   // leaf: triangle count; inner: 0
    int right = -1;  // inner: index of the right child
  };
  int build(int begin, int end, std::vector<Vec3>& centroids);

  std::vector<Vec3> vertices_;
  std::vector<Triangle> triangles_;
  std::vector<Vec3> face_normals_;
  std::vector<std::array<Vec3, 3>> edge_normals_;  // per triangle, edge k = (v_k, v_{k+1})
  std::vector<Vec3> vertex_normals_;               // angle-weighted
  std::vector<Node> nodes_;
  std::vector<int> order_;  // triangles in leaf order
  Vec3 lo_ = Vec3::Zero(), hi_ = Vec3::Zero();
  int boundary_edges_ = 0;
  int degenerate_triangles_ = 0;
};

}  // namespace pbd_cloth
