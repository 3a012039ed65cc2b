// A cloth given as a triangle mesh (cloth.mesh): the checks that turn the polygons read from a file
// into the cloth's triangles, keeping the file's vertex ids (particle i = the file's vertex i).
// The file is read by the scene reader (scene_assets.h, tinyobjloader); everything here is
// ROS-free so a mesh built in code is checked the same way.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "pbd_cloth/geometry/polygon_mesh.h"
#include "pbd_cloth/model/particles.h"

namespace pbd_cloth {

// Checks `polygons` and builds the cloth mesh. Refused with ConfigError(key, reason naming the
// face or vertex): no faces, an index out of range, a vertex no kept triangle uses (it would be a
// particle without mass or constraints). Proceeds with a warning appended to `warnings` (naming the
// first faces or vertices and the count): faces with more than 3 vertices (split as a fan),
// degenerate triangles (repeated vertex or zero area: left out), vertices at identical
// coordinates (kept apart: ids matter, and the cloth is open there), non-manifold edges (shared by
// more than 2 triangles: no bending across them).
ClothMesh makeClothMesh(const PolygonMesh& polygons, const std::string& key,
                        std::vector<std::string>& warnings);

// Edges of the triangles shared by more than two of them (sorted vertex pairs, ascending).
std::vector<std::pair<unsigned, unsigned>> nonManifoldEdges(const std::vector<unsigned>& triangles);

}  // namespace pbd_cloth
