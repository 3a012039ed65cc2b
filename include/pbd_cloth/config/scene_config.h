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

#include "pbd_cloth/geometry/pose.h"
#include "pbd_cloth/geometry/shape_type.h"

namespace pbd_cloth {

class TriangleMesh;  // mesh_shape.h: a loaded mesh shape with its signed-distance queries
struct ClothMesh;    // mesh_cloth.h: the triangles of cloth.mesh with the file's vertex ids

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

enum class Method {
  kVerlet,      // the seed: Verlet integration, constraints projected rigidly, relaxation loop
  kPbd,         // Mueller et al. 2007: stiffness in [0,1], corrected for the iteration count
  kXpbd,        // Macklin et al. 2016: compliance, one Lagrange multiplier per constraint
  kMassSpring,  // explicit springs and dampers, symplectic Euler: the penalty baseline
};
enum class Ordering { kGaussSeidel, kJacobi };

const char* toString(Method method);
const char* toString(Ordering ordering);

// Upper limit of solver.substeps, solver.iterations and solver.search_window: not physics, but a
// typo like substeps: 50000 would otherwise stall the node before anyone sees an error.
constexpr int kMaxPasses = 1000;

struct SolverConfig {
  Method method = Method::kXpbd;               // solver.method
  int substeps = 10;                           // solver.substeps, per step
  int iterations = 1;                          // solver.iterations, passes per substep
  double tolerance = 0.0;                      // solver.tolerance (m); > 0: adaptive
  Ordering ordering = Ordering::kGaussSeidel;  // solver.ordering
  double relaxation = 1.0;                     // solver.relaxation, Jacobi factor in (0,2)
  bool jacobi_averaging = true;                // solver.jacobi_averaging (eq. 48 survey)
  Eigen::Vector3d gravity{0.0, 0.0, -9.81};    // solver.gravity (m/s^2)
  double damping = 0.0;                        // solver.damping (1/s)
  double stretch_stiffness = 1.0;              // solver.stretch_stiffness, pbd only, [0,1]
  double bend_stiffness = 0.1;                 // solver.bend_stiffness, pbd only, [0,1]
  double spring_stiffness = 1.0e4;             // solver.spring_stiffness (N/m), mass_spring
  double spring_damping = 0.0;                 // solver.spring_damping (N s/m), mass_spring
  // 0.01: on the 50 x 50 hanging cloth 1.0 already diverges at 240 substeps (scripts/method_table).
  double bend_spring_stiffness = 0.01;  // solver.bend_spring_stiffness, mass_spring
  // solver.levels: levels of long-range links of the grid cloth's stretch solve (coarse_levels.h,
  // after hierarchical PBD), each pass coarsest first. 0 = off (the default). Grid cloth and zero
  // stretch compliance only: the links are inextensible.
  int levels = 0;
  // solver.max_speed (m/s): a free particle faster than this after a step means the step blew up
  // (its kinetic energy m v^2 / 2 per particle is out of bounds). Where fault recovery is on (the
  // node), that step is undone: Simulation::step, "Faults". Nothing a robot handles moves a cloth
  // at 100 m/s; a gripper jumping 1 m in one 60 Hz step drags its neighbours at about 60 m/s.
  double max_speed = 100.0;
  // solver.simd: project the stretch links four at a time with AVX2 where the processor has it,
  // eight at a time with AVX-512 where it has that (stretch_links.h; bit-identical to the
  // portable loop). false: always the portable loop.
  bool simd = true;
  // solver.avx512: false keeps the stretch links and the flat hinges at AVX2 on a processor with
  // AVX-512 (the same results to the bit; for comparing the two, doc/performance.md "Eight links
  // a register" and "Flat hinges through masked accesses").
  bool avx512 = true;
  // solver.threads: threads that step the cloth (the calling one included): the stretch links of
  // a grid of 32 rows or more in blocks (stretch_links.h), prediction and velocity update in
  // ranges of particles. Bit-identical results for every count. 1 by default: a robot's computer
  // runs more than this node, and a spinning worker competes with it (doc/performance.md,
  // "Threads").
  int threads = 1;
  // solver.adaptive_threads: with threads > 1, run a step on the calling thread alone while that is
  // measured to be faster (another process holds a core), trying all threads again now and then
  // (thread_choice.h). The same results either way: the partition of the work does not change.
  bool adaptive_threads = true;
  // solver.taut_chains: a grid row or column of inextensible links whose two kinematic ends are as
  // far apart as its rest lengths add up to (the top row of a cloth pinned at both top corners)
  // is held straight, its one possible shape, instead of being swept towards it (taut_chains.h).
  // Only while the links are inextensible: cloth.stretch_compliance 0, and not pbd with
  // solver.stretch_stiffness < 1 nor mass_spring; and not with cloth.tethers, which hold such a
  // chain already (each of its particles is tethered to both ends).
  bool taut_chains = true;
  // solver.search_window: substeps one contact search (particle-particle and self-collision
  // candidates) covers. 0 (the default): chosen per step from the last one's candidates
  // (Collisions, "search window"); k >= 1: every k substeps, a search more wherever a particle
  // leaves its motion bounds; k >= substeps: once per step.
  int search_window = 0;
  // solver.sleep_speed (m/s) and solver.sleep_time (s): when every free particle has moved slower
  // than sleep_speed for sleep_time (stayed within sleep_speed x sleep_time of where it was when
  // that time began), the scene sleeps: steps cost a check instead of a solve until something
  // could move it (Simulation::step, "Sleeping"). 0 = never sleeps (the default,
  // so benchmarks and accuracy tests always solve).
  double sleep_speed = 0.0;
  double sleep_time = 0.5;
};

struct FrictionConfig {
  double static_coefficient = 0.5;   // cloth.friction.static (mu_s)
  double kinetic_coefficient = 0.4;  // cloth.friction.kinetic (mu_k), <= mu_s
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

enum class JointType { kFixed, kRevolute, kContinuous, kPrismatic, kFloating, kPlanar };

// A joint of the URDF's kinematic tree (floating and planar joints are held at their origin).
struct RobotJoint {
  std::string name;
  JointType type = JointType::kFixed;
  int parent_link = -1;  // index into RobotModel::links
  int child_link = -1;
  Pose origin;                          // child joint frame in the parent link frame at position 0
  Eigen::Vector3d axis{1.0, 0.0, 0.0};  // unit, in the joint frame
  double lower = 0.0, upper = 0.0;      // limits (revolute, prismatic); not enforced by FK
  int mimic_joint = -1;                 // position = multiplier * mimicked + offset
  double mimic_multiplier = 1.0, mimic_offset = 0.0;
};

struct RobotLink {
  std::string name;
  // Every <collision> element of the link, in file order; pose = its origin in the link frame.
  std::vector<ObstacleConfig> collisions;
  int parent_joint = -1;  // -1 for the root link
};

// The URDF as the simulation needs it: links with their collision shapes and the joint tree.
// Filled by the scene reader (scene_assets.h); forward kinematics in robot_model.cpp (core).
struct RobotModel {
  std::string name;
  std::vector<RobotLink> links;
  std::vector<RobotJoint> joints;
  int root_link = -1;

  int linkIndex(const std::string& link) const;    // -1 when absent
  int jointIndex(const std::string& joint) const;  // -1 when absent
  // Pose of every link in the scene frame with the root link at `root_pose`, for joint positions
  // indexed like `joints` (fixed joints ignore theirs; mimic joints follow their joint). `out` is
  // resized to links.size().
  void linkPoses(const Pose& root_pose, const std::vector<double>& joint_positions,
                 std::vector<Pose>& out) const;
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
