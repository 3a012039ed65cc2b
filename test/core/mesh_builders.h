// Closed triangle meshes built in code for the mesh-shape tests: an icosphere, a box, surfaces of
// revolution (a torus, a mug with a cavity), each with outward-facing triangles.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "pbd_cloth/config/scene_config.h"
#include "pbd_cloth/geometry/mesh_shape.h"

namespace pbd_cloth {
namespace test {

struct MeshGeometry {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::array<int, 3>> triangles;

  // Signed volume (divergence theorem): positive when the triangles face outward.
  double volume() const {
    double six_v = 0.0;
    for (const auto& t : triangles) {
      six_v += vertices[t[0]].dot(vertices[t[1]].cross(vertices[t[2]]));
    }
    return six_v / 6.0;
  }
  // Outward-facing: the tests must not depend on the order a builder happened to use.
  void orientOutward() {
    if (volume() < 0.0) {
      for (auto& t : triangles) std::swap(t[1], t[2]);
    }
  }
  std::shared_ptr<const TriangleMesh> build() const {
    return std::make_shared<TriangleMesh>(vertices, triangles);
  }
};

// An icosahedron subdivided `levels` times, its vertices on the sphere of radius r.
inline MeshGeometry icosphere(double r, int levels) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  MeshGeometry g;
  g.vertices = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  g.triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                 {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                 {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                 {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (auto& v : g.vertices) v.normalize();
  for (int level = 0; level < levels; ++level) {
    std::map<std::pair<int, int>, int> middle;
    const auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      const auto found = middle.find(key);
      if (found != middle.end()) return found->second;
      g.vertices.push_back((g.vertices[a] + g.vertices[b]).normalized());
      const int index = static_cast<int>(g.vertices.size()) - 1;
      middle.emplace(key, index);
      return index;
    };
    std::vector<std::array<int, 3>> finer;
    for (const auto& tri : g.triangles) {
      const int ab = midpoint(tri[0], tri[1]), bc = midpoint(tri[1], tri[2]),
                ca = midpoint(tri[2], tri[0]);
      finer.push_back({tri[0], ab, ca});
      finer.push_back({tri[1], bc, ab});
      finer.push_back({tri[2], ca, bc});
      finer.push_back({ab, bc, ca});
    }
    g.triangles = finer;
  }
  for (auto& v : g.vertices) v *= r;
  g.orientOutward();
  return g;
}

// A box centred at the origin with these half extents: 8 corners, 12 triangles.
inline MeshGeometry boxMesh(const Eigen::Vector3d& half) {
  MeshGeometry g;
  for (int k = 0; k < 8; ++k) {
    g.vertices.emplace_back((k & 1 ? 1 : -1) * half.x(), (k & 2 ? 1 : -1) * half.y(),
                            (k & 4 ? 1 : -1) * half.z());
  }
  g.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                 {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  g.orientOutward();
  return g;
}

// The surface swept by a profile (r, z) turned about the z axis in `segments` steps. An open
// profile must start and end on the axis (r = 0: one pole vertex each); a closed one (a circle
// for a torus) joins its last point to its first.
inline MeshGeometry revolve(const std::vector<Eigen::Vector2d>& profile, int segments,
                            bool closed_profile) {
  MeshGeometry g;
  const int n = static_cast<int>(profile.size());
  std::vector<std::vector<int>> index(n, std::vector<int>(segments));
  for (int i = 0; i < n; ++i) {
    const double r = profile[i].x(), z = profile[i].y();
    for (int s = 0; s < segments; ++s) {
      if (r == 0.0 && s > 0) {
        index[i][s] = index[i][0];  // a pole: one vertex
        continue;
      }
      const double phi = 2.0 * M_PI * s / segments;
      g.vertices.emplace_back(r * std::cos(phi), r * std::sin(phi), z);
      index[i][s] = static_cast<int>(g.vertices.size()) - 1;
    }
  }
  const int rings = closed_profile ? n : n - 1;
  for (int i = 0; i < rings; ++i) {
    const int j = (i + 1) % n;
    for (int s = 0; s < segments; ++s) {
      const int s2 = (s + 1) % segments;
      const int a = index[i][s], b = index[i][s2], c = index[j][s2], d = index[j][s];
      if (a != b) g.triangles.push_back({a, b, c});
      if (c != d) g.triangles.push_back({a, c, d});
    }
  }
  g.orientOutward();
  return g;
}

inline MeshGeometry torusMesh(double major, double minor, int segments, int sides) {
  std::vector<Eigen::Vector2d> circle;
  for (int k = 0; k < sides; ++k) {
    const double a = 2.0 * M_PI * k / sides;
    circle.emplace_back(major + minor * std::cos(a), minor * std::sin(a));
  }
  return revolve(circle, segments, true);
}

// A cup standing on z = 0: outer radius, height, wall and bottom thickness. Its cavity is the
// cylinder r < radius - wall, bottom < z < height.
inline MeshGeometry mugMesh(double radius, double height, double wall, double bottom,
                            int segments) {
  const std::vector<Eigen::Vector2d> profile = {{0.0, 0.0},
                                                {radius, 0.0},
                                                {radius, height},
                                                {radius - wall, height},
                                                {radius - wall, bottom},
                                                {0.0, bottom}};
  return revolve(profile, segments, false);
}

inline ObstacleConfig meshObstacle(const std::string& name, const MeshGeometry& geometry,
                                   const Pose& pose) {
  ObstacleConfig o;
  o.name = name;
  o.shape = ShapeType::kMesh;
  o.mesh = name + " (built in code)";
  o.mesh_data = geometry.build();
  o.pose = pose;
  return o;
}

}  // namespace test
}  // namespace pbd_cloth
