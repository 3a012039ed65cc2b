// Meshes as read from a file, before they become a cloth (sim/mesh_cloth.h checks and builds
// them): plain data, which the scene description holds (cloth.mesh) and validate() reads.
#pragma once

#include <string>
#include <vector>

#include "pbd_cloth/geometry/vector_types.h"

namespace pbd_cloth {

// Polygons as read from a file, with 0-based vertex indices (possibly out of range: checked here).
struct PolygonMesh {
  std::string source;             // the file, for messages
  Vec3Array vertices;             // file units, before cloth.mesh_scale
  std::vector<int> face_sizes;    // vertices of each face, in file order
  std::vector<int> face_indices;  // all faces' vertex indices, concatenated
  std::vector<int> face_lines;    // the file line of each face (0 when unknown)
};

// The cloth mesh: the file's vertices and its faces as triangles, in file order (polygons split
// as a fan from their first vertex; degenerate triangles left out).
struct ClothMesh {
  std::string source;
  Vec3Array vertices;               // file units, before cloth.mesh_scale
  std::vector<unsigned> triangles;  // 3 vertex indices per triangle
  std::vector<int> triangle_face;   // 1-based face number (f line) each triangle comes from
};

}  // namespace pbd_cloth
