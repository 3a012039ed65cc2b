// The scene description: one tree of Config structs with defaults, filled from YAML (cloth_bench,
// tests) or from the parameter server (cloth_node), and checked by one validation routine.
// Key names follow ../shared/INTERFACE.md; every field notes its YAML key.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "pbd_cloth/config/obstacle_config.h"
#include "pbd_cloth/config/robot_model.h"
#include "pbd_cloth/config/rope_config.h"
#include "pbd_cloth/geometry/pose.h"
#include "pbd_cloth/solver/solver_settings.h"

namespace pbd_cloth {

struct ClothMesh;  // geometry/polygon_mesh.h: the triangles of cloth.mesh with the file's vertex
                   // ids

// Upper limit of cloth and granular particle counts: not physics but protection of the process
// (a typo like rows: 50000, or a 1e9-vertex mesh, would otherwise allocate gigabytes before
// anyone sees an error).
constexpr std::int64_t kMaxParticles = 1000000;

// A bad scene key. what() names the key and the allowed range.
class ConfigError : public std::runtime_error {
 public:
  ConfigError(const std::string& key, const std::string& message)
      : std::runtime_error(key + ": " + message), key_(key) {}
  const std::string& key() const { return key_; }

 private:
  std::string key_;
};

struct ClothConfig {
  // cloth.mesh: a triangle mesh file (OBJ) instead of the grid; rows, cols and spacing are then
  // ignored. particle i = the file's vertex i, placed at origin + R(rpy) * mesh_scale * v.
  std::string mesh;
  double mesh_scale = 1.0;  // cloth.mesh_scale
  // The loaded mesh (scene reader: scene_assets.h loadClothMesh). Shared, as obstacle meshes.
  std::shared_ptr<const ClothMesh> mesh_data;
  int rows = 32;                                     // cloth.rows
  int cols = 32;                                     // cloth.cols
  double spacing = 0.03;                             // cloth.spacing (m)
  double mass = 0.2;                                 // cloth.mass, total (kg)
  Eigen::Vector3d origin{0.0, 0.0, 1.0};             // cloth.origin, particle (0,0)
  Eigen::Vector3d rpy{0.0, 0.0, 0.0};                // cloth.rpy (rad)
  double stretch_compliance = 0.0;                   // cloth.stretch_compliance (m/N)
  double bend_compliance = 1.0e-3;                   // cloth.bend_compliance; < 0 disables bending
  double thickness = 0.005;                          // cloth.thickness (m)
  bool self_collision = true;                        // cloth.self_collision
  FrictionConfig friction;                           // cloth.friction
  std::vector<int> pinned;                           // cloth.pinned
  std::vector<std::pair<int, double>> point_masses;  // cloth.point_masses [[index, kg]]
  bool tethers = false;                              // cloth.tethers
  bool shear = true;                                 // cloth.shear: diagonal stretch constraints
  // cloth.shear_diagonals: 1 = each grid cell's triangle diagonal (the mesh edge, as Jolt), 2 =
  // both diagonals of every cell (Bullet's and Bender's cloth, the issue 12 benchmark). Grid only.
  int shear_diagonals = 1;
};

// What the solver reads of the cloth's configuration (Solver::configure).
inline ClothMaterial clothMaterial(const ClothConfig& cloth) {
  return ClothMaterial{cloth.stretch_compliance, cloth.bend_compliance, cloth.spacing};
}

struct GranularConfig {
  int count = 0;                              // granular.count
  double radius = 0.01;                       // granular.radius (m)
  double mass = 0.001;                        // granular.mass, each (kg)
  Eigen::Vector3d region_min{0.0, 0.0, 1.0};  // granular.region.min
  Eigen::Vector3d region_max{0.2, 0.2, 1.2};  // granular.region.max
};

struct Waypoint {
  double t = 0.0;  // s since start
  Pose pose;
  int grasp = -1;  // -1: no change, 0: release, 1: grasp
};

struct GripperConfig {
  std::string name;                  // grippers[i].name
  double radius = 0.02;              // grippers[i].radius (m)
  std::string tf_frame;              // grippers[i].tf_frame
  std::vector<Waypoint> trajectory;  // grippers[i].trajectory
  // grippers[i].repeat: after its last waypoint the trajectory starts again from its first, with
  // the last waypoint's t as its period (grasp events included), so a scripted motion can run for
  // as long as the node does.
  bool repeat = false;
};

struct JointWaypoint {
  double t = 0.0;                                         // s since start
  std::vector<std::pair<std::string, double>> positions;  // joint name -> rad or m
};

struct RobotConfig {
  bool enabled = false;                           // true when the scene has a `robot` key
  std::string description = "robot_description";  // robot.description (node: URDF parameter)
  std::string urdf_file;                          // robot.urdf_file
  std::vector<std::string> links;               // robot.links; empty = every link with <collision>
  double padding = 0.0;                         // robot.padding (m)
  FrictionConfig friction;                      // robot.friction
  std::vector<JointWaypoint> joint_trajectory;  // robot.joint_trajectory
  Pose pose;  // robot.pose: the root link in frame_id when posed by joint_trajectory (FK)
  // The parsed URDF (scene_assets.h); links not selected by `links` stay in the tree without
  // collisions.
  RobotModel model;
};

// cameras[i]: a simulated depth camera (depth_camera.h renders it, the node publishes it).
struct CameraConfig {
  std::string name;   // cameras[i].name: the node's topics ~<name>/depth/...
  std::string frame;  // cameras[i].frame: the optical frame (REP 103: z forward, x right, y down)
  // cameras[i].pose ([x y z qx qy qz qw] of the optical frame in frame_id). Given: the camera
  // stands there and the node broadcasts `frame`; empty ([]): the node follows `frame` in tf.
  bool has_pose = false;
  Pose pose;
  int width = 320;    // cameras[i].width (pixels)
  int height = 240;   // cameras[i].height
  double fx = 277.0;  // cameras[i].fx, fy: focal lengths in pixels
  double fy = 277.0;
  // cameras[i].cx, cy: principal point in pixels, pixel centres at integers (OpenCV, ROS
  // CameraInfo). Default: the image centre, (width - 1) / 2 and (height - 1) / 2.
  double cx = -1.0;
  double cy = -1.0;
  double rate = 15.0;      // cameras[i].rate: images per second (<= step_rate)
  double range_min = 0.1;  // cameras[i].range.min (m): nearer, or farther than max: NaN
  double range_max = 5.0;  // cameras[i].range.max (m)
  double noise = 0.0;      // cameras[i].noise: standard deviation (m) of Gaussian depth noise
  int seed = 0;            // cameras[i].seed: the noise's random stream (same seed, same noise)
};

// bounds: a box the particles are kept inside (the seed's C1). The cloth must start inside it:
// validate() refuses a cloth with a particle outside, naming it (a cloth squeezed onto the box in
// its first step would be a line of degenerate triangles).
struct BoundsConfig {
  bool enabled = false;  // true when the scene has a `bounds` key
  Eigen::Vector3d min{-10.0, -10.0, -10.0};
  Eigen::Vector3d max{10.0, 10.0, 10.0};
};

struct SceneConfig {
  std::string frame_id = "world";  // frame_id
  double step_rate = 120.0;        // step_rate (Hz)
  double publish_rate = 30.0;      // publish_rate (Hz)
  SolverConfig solver;
  ClothConfig cloth;
  GranularConfig granular;
  // ropes: Cosserat rods, their particles numbered after the cloth's (and before the granular
  // ones), each rope's in order.
  std::vector<RopeConfig> ropes;
  std::vector<GripperConfig> grippers;
  BoundsConfig bounds;
  std::vector<ObstacleConfig> obstacles;
  RobotConfig robot;
  std::vector<CameraConfig> cameras;
  // What loading found that is allowed but worth a warning (an open mesh, a link without
  // collision elements ...); cloth_bench prints them, the node logs them.
  std::vector<std::string> load_warnings;
};

// Checks every value; throws ConfigError naming the key and the allowed range.
void validate(const SceneConfig& scene);

}  // namespace pbd_cloth
