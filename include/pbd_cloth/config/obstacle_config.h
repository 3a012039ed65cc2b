// The description of one collision shape (a scene obstacle or a robot link's collision element)
// and of contact friction, as the scene gives them (scene_config.h). The runtime's shape is made
// from it once (sim/colliders.h).
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>

#include "pbd_cloth/geometry/pose.h"
#include "pbd_cloth/geometry/shape_type.h"

namespace pbd_cloth {

class TriangleMesh;  // geometry/mesh_shape.h: a loaded mesh shape with its signed-distance queries

struct FrictionConfig {
  double static_coefficient = 0.5;   // cloth.friction.static (mu_s)
  double kinetic_coefficient = 0.4;  // cloth.friction.kinetic (mu_k), <= mu_s
};

const char* toString(ShapeType shape);

// One collision shape: an obstacle of the scene, or one <collision> element of a robot link (then
// `pose` is the element's origin in the link frame and `name` is "<link>/<index>").
struct ObstacleConfig {
  std::string name;                      // obstacles[i].name
  ShapeType shape = ShapeType::kSphere;  // obstacles[i].shape
  double radius = 0.1;                   // sphere, capsule, cylinder
  Eigen::Vector3d size{1.0, 1.0, 1.0};   // box: full edge lengths
  double length = 0.5;  // capsule: between the end-sphere centres; cylinder: height
  Eigen::Vector3d normal{0.0, 0.0, 1.0};  // plane: unit normal
  double offset = 0.0;                    // plane: free side is n.p - offset >= 0
  std::string mesh;                       // mesh: file path, file:// or package:// URI
  Eigen::Vector3d scale{1.0, 1.0, 1.0};   // mesh: per-axis scale applied at load
  // mesh: the loaded, scaled mesh with its distance structure (scene reader: scene_assets.h).
  // Shared: copies of the scene (reset, live tuning) do not copy the mesh.
  std::shared_ptr<const TriangleMesh> mesh_data;
  Pose pose;             // obstacles[i].pose
  std::string tf_frame;  // obstacles[i].tf_frame: follow this frame (node)
  double padding = 0.0;  // m added around the shape (robot links: robot.padding)
  // Friction of contacts with this shape; cloth.friction when not set (robot links:
  // robot.friction).
  bool has_friction = false;
  FrictionConfig friction;
};

}  // namespace pbd_cloth
