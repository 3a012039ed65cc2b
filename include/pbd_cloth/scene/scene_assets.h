// Loading the files a scene refers to, beside the YAML reader: mesh files of obstacles and robot
// links (STL, OBJ, DAE, PLY through assimp; paths, file:// and package:// URIs through
// resource_retriever) and the robot's URDF (ROS's urdf package, which parses with urdfdom). No ROS
// master is needed, so cloth_bench and the core tests use it as the node does.
#pragma once

#include <memory>
#include <string>

#include "pbd_cloth/config/scene_config.h"
#include "pbd_cloth/geometry/mesh_shape.h"

namespace pbd_cloth {

// Loads a mesh file (`uri`: a path, file:// or package://), scaled per axis. Throws ConfigError
// with `key` (e.g. "obstacles[2].mesh" or "robot link 'forearm' collision 0 mesh") naming the
// file when it is missing, unreadable, not a mesh, or has no triangles. An open mesh loads (as a
// two-sided shell) and appends a warning naming the file and its boundary edge count to
// `warnings`.
std::shared_ptr<const TriangleMesh> loadMesh(const std::string& uri, const Eigen::Vector3d& scale,
                                             const std::string& key,
                                             std::vector<std::string>& warnings);

// Loads cloth.mesh (an OBJ file, path or file:// / package:// URI; tinyobjloader) into
// scene.cloth.mesh_data, keeping the file's vertex ids, and checks it (mesh_cloth.h
// makeClothMesh: what is refused and what only warns). The file is first scanned line by line for
// its v and f lines, so a file with more than kMaxParticles vertices is refused before anything
// grows with it. Throws ConfigError "cloth.mesh" naming the file (and face or vertex).
void loadClothMesh(SceneConfig& scene);

// Loads every obstacle mesh of the scene (shape: mesh) into its mesh_data.
void loadObstacleMeshes(SceneConfig& scene);

// Parses `urdf_xml` (the text of a URDF) into scene.robot.model: links, every <collision> element
// (box, sphere, cylinder, mesh with scale; origin), joints. Applies robot.links (a name the URDF
// lacks throws ConfigError "robot.links[i]"), robot.padding and robot.friction, and loads the
// link meshes. `source` names where the text came from (the parameter or file) in messages.
// Throws ConfigError naming `source` when the URDF does not parse, and naming the link for a bad
// mesh or an unsupported geometry.
void loadRobot(SceneConfig& scene, const std::string& urdf_xml, const std::string& source);

// loadRobot with the text of scene.robot.urdf_file (ConfigError "robot.urdf_file" when it cannot
// be read). Relative mesh paths inside the URDF are relative to the URDF file's directory (with
// loadRobot: to the current directory); package:// and file:// URIs are the usual form.
void loadRobotFile(SceneConfig& scene);

// `location` with a relative path resolved against `base_directory` ("" = the current directory:
// unchanged). Absolute paths and file:// / package:// URIs are returned unchanged.
std::string resolveScenePath(const std::string& location, const std::string& base_directory);

}  // namespace pbd_cloth
