#include "pbd_cloth/sim/mesh_cloth.h"

#include <algorithm>
#include <map>
#include <tuple>

#include "pbd_cloth/config/scene_config.h"

namespace pbd_cloth {

namespace {

// A warning names at most this many faces or vertices, then the count: a quad mesh of 10,000
// faces gives one line, not 10,000.
constexpr std::size_t kNamed = 5;

std::string faceName(const PolygonMesh& polygons, int face) {
  std::string name = "face " + std::to_string(face + 1);
  const int line =
      face < static_cast<int>(polygons.face_lines.size()) ? polygons.face_lines[face] : 0;
  if (line > 0) name += " (line " + std::to_string(line) + ")";
  return name;
}

// "face 3 (line 9), face 7 (line 13) and 12 more"
std::string listNames(const std::vector<std::string>& names) {
  std::string out;
  for (std::size_t k = 0; k < names.size() && k < kNamed; ++k) {
    out += (k == 0 ? "" : ", ") + names[k];
  }
  if (names.size() > kNamed) out += " and " + std::to_string(names.size() - kNamed) + " more";
  return out;
}

// The sine of the triangle's angle at a below ~1e-8: no area, no normal, no hinge.
bool degenerate(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 e1 = b - a, e2 = c - a;
  return !(e1.cross(e2).squaredNorm() > 1e-16 * e1.squaredNorm() * e2.squaredNorm());
}

}  // namespace

std::vector<std::pair<unsigned, unsigned>> nonManifoldEdges(
    const std::vector<unsigned>& triangles) {
  std::vector<std::pair<unsigned, unsigned>> edges;
  edges.reserve(triangles.size());
  for (std::size_t k = 0; k + 2 < triangles.size(); k += 3) {
    for (int e = 0; e < 3; ++e) {
      const unsigned a = triangles[k + e], b = triangles[k + (e + 1) % 3];
      edges.emplace_back(std::min(a, b), std::max(a, b));
    }
  }
  std::sort(edges.begin(), edges.end());
  std::vector<std::pair<unsigned, unsigned>> out;
  for (std::size_t k = 0; k + 2 < edges.size(); ++k) {
    if (edges[k] == edges[k + 2] && (out.empty() || out.back() != edges[k])) {
      out.push_back(edges[k]);
    }
  }
  return out;
}

ClothMesh makeClothMesh(const PolygonMesh& polygons, const std::string& key,
                        std::vector<std::string>& warnings) {
  const std::string file = "'" + polygons.source + "'";
  const int vertex_count = static_cast<int>(polygons.vertices.size());
  if (static_cast<std::int64_t>(vertex_count) > kMaxParticles) {
    throw ConfigError(key, file + " has " + std::to_string(vertex_count) +
                               " vertices, more than the " + std::to_string(kMaxParticles) +
                               " particles a cloth may have");
  }
  for (int v = 0; v < vertex_count; ++v) {
    if (!polygons.vertices[v].allFinite()) {
      throw ConfigError(key, file + ": vertex " + std::to_string(v + 1) + " (particle " +
                                 std::to_string(v) + ") has a non-finite coordinate");
    }
  }
  if (polygons.face_sizes.empty()) {
    throw ConfigError(key, file + " has no faces (f lines): a cloth needs triangles");
  }
  ClothMesh mesh;
  mesh.source = polygons.source;
  mesh.vertices = polygons.vertices;
  std::vector<std::string> polygon_faces, degenerate_faces;
  std::size_t offset = 0;
  const int faces = static_cast<int>(polygons.face_sizes.size());
  for (int f = 0; f < faces; ++f) {
    const int size = polygons.face_sizes[f];
    if (size < 3 || offset + size > polygons.face_indices.size()) {
      throw ConfigError(key, file + ": " + faceName(polygons, f) + " has " + std::to_string(size) +
                                 " vertices; a face needs at least 3");
    }
    const int* index = polygons.face_indices.data() + offset;
    offset += size;
    for (int k = 0; k < size; ++k) {
      if (index[k] < 0 || index[k] >= vertex_count) {
        throw ConfigError(key, file + ": " + faceName(polygons, f) + " uses vertex " +
                                   std::to_string(index[k] + 1) + ", but the file has " +
                                   std::to_string(vertex_count) + " vertices");
      }
    }
    // Quads and polygons: a fan from the first vertex, which is exact for convex planar polygons
    // (what exporters write); the warning says the triangles are not the file's faces.
    if (size > 3) polygon_faces.push_back(faceName(polygons, f));
    for (int k = 1; k + 1 < size; ++k) {
      const int a = index[0], b = index[k], c = index[k + 1];
      const Vec3Array& x = mesh.vertices;
      if (a == b || b == c || a == c || degenerate(x[a], x[b], x[c])) {
        degenerate_faces.push_back(faceName(polygons, f) +
                                   (size > 3 ? " triangle " + std::to_string(k) : ""));
        continue;
      }
      mesh.triangles.insert(
          mesh.triangles.end(),
          {static_cast<unsigned>(a), static_cast<unsigned>(b), static_cast<unsigned>(c)});
      mesh.triangle_face.push_back(f + 1);
    }
  }
  if (!polygon_faces.empty()) {
    warnings.push_back(key + ": " + file + ": " + std::to_string(polygon_faces.size()) +
                       " faces with more than 3 vertices split into triangles as a fan from their "
                       "first vertex: " +
                       listNames(polygon_faces));
  }
  if (!degenerate_faces.empty()) {
    warnings.push_back(key + ": " + file + ": " + std::to_string(degenerate_faces.size()) +
                       " degenerate triangles (repeated vertex or zero area) left out: " +
                       listNames(degenerate_faces));
  }
  if (mesh.triangles.empty()) {
    throw ConfigError(key, file + " has no triangle with an area: every face is degenerate");
  }
  // Every particle needs mass (a share of the triangles' area) and constraints: a vertex no
  // triangle uses would be a massless particle falling alone. Refused rather than dropped, since
  // dropping it would renumber the particles after it.
  std::vector<char> used(vertex_count, 0);
  for (unsigned v : mesh.triangles) used[v] = 1;
  std::vector<std::string> unused;
  for (int v = 0; v < vertex_count; ++v) {
    if (!used[v]) {
      unused.push_back("vertex " + std::to_string(v + 1) + " (particle " + std::to_string(v) + ")");
    }
  }
  if (!unused.empty()) {
    throw ConfigError(key,
                      file + ": " + std::to_string(unused.size()) +
                          " vertices are used by no (non-degenerate) face: " + listNames(unused) +
                          "; remove them from the file (ids would shift if they were dropped)");
  }
  // Unwelded copies: kept as separate particles (ids are the file's), so the cloth is open along
  // them; said, since it usually means an exporter split the mesh at a UV or material seam.
  std::vector<int> order(vertex_count);
  for (int v = 0; v < vertex_count; ++v) order[v] = v;
  const Vec3Array& x = mesh.vertices;
  auto less = [&x](int a, int b) {
    return std::make_tuple(x[a].x(), x[a].y(), x[a].z(), a) <
           std::make_tuple(x[b].x(), x[b].y(), x[b].z(), b);
  };
  std::sort(order.begin(), order.end(), less);
  std::vector<std::string> duplicates;
  for (int k = 1; k < vertex_count; ++k) {
    if (x[order[k]] == x[order[k - 1]]) {
      duplicates.push_back("vertex " + std::to_string(order[k] + 1) + " = vertex " +
                           std::to_string(order[k - 1] + 1));
    }
  }
  if (!duplicates.empty()) {
    warnings.push_back(key + ": " + file + ": " + std::to_string(duplicates.size()) +
                       " vertices duplicate another's coordinates and are kept as separate "
                       "particles (not welded: ids are the file's), so the cloth is open there: " +
                       listNames(duplicates));
  }
  const auto non_manifold = nonManifoldEdges(mesh.triangles);
  if (!non_manifold.empty()) {
    std::vector<std::string> names;
    for (const auto& [a, b] : non_manifold) {
      names.push_back("vertices " + std::to_string(a + 1) + "-" + std::to_string(b + 1));
    }
    warnings.push_back(key + ": " + file + ": " + std::to_string(non_manifold.size()) +
                       " edges are shared by more than 2 triangles (non-manifold): no bending "
                       "across them, stretch kept: " +
                       listNames(names));
  }
  return mesh;
}

}  // namespace pbd_cloth
