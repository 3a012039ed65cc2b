// The scene description: one tree of Config structs with defaults, filled from YAML (cloth_bench,
// tests) or from the parameter server (cloth_node), and checked by one validation routine.
// Key names follow ../shared/INTERFACE.md; every field notes its YAML key.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace pbd_cloth {

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

struct Pose {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();

  // The pose `local`, given in this pose's frame, expressed in the frame this pose is given in.
  Pose compose(const Pose& local) const {
    Pose out;
    out.position = position + orientation * local.position;
    out.orientation = (orientation * local.orientation).normalized();
    return out;
  }
};

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
};

struct FrictionConfig {
  double static_coefficient = 0.5;   // cloth.friction.static (mu_s)
  double kinetic_coefficient = 0.4;  // cloth.friction.kinetic (mu_k), <= mu_s
};

struct ClothConfig {
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

enum class ShapeType { kSphere, kBox, kCapsule, kPlane };
const char* toString(ShapeType shape);

struct ObstacleConfig {
  std::string name;                       // obstacles[i].name
  ShapeType shape = ShapeType::kSphere;   // obstacles[i].shape
  double radius = 0.1;                    // sphere, capsule
  Eigen::Vector3d size{1.0, 1.0, 1.0};    // box: full edge lengths
  double length = 0.5;                    // capsule: distance between the end-sphere centres
  Eigen::Vector3d normal{0.0, 0.0, 1.0};  // plane: unit normal
  double offset = 0.0;                    // plane: free side is n.p - offset >= 0
  Pose pose;                              // obstacles[i].pose
};

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
};

// Checks every value; throws ConfigError naming the key and the allowed range.
void validate(const SceneConfig& scene);

}  // namespace pbd_cloth
