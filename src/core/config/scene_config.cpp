// The one validation routine of the scene tree. Every message names the dotted key (list entries as
// `grippers[1].radius`) and the allowed range, so a user can fix a YAML file or a ROS parameter
// without reading the code. Every comparison is preceded by a finiteness check: NaN compares false
// with everything and would otherwise slip through a range test.
#include "pbd_cloth/config/scene_config.h"

#include "pbd_cloth/config/cloth_placement.h"
#include "pbd_cloth/geometry/polygon_mesh.h"

#include <cctype>
#include <cmath>
#include <cstdint>
#include <limits>
#include <set>
#include <sstream>

namespace pbd_cloth {

const char* toString(ShapeType shape) {
  switch (shape) {
    case ShapeType::kSphere:
      return "sphere";
    case ShapeType::kBox:
      return "box";
    case ShapeType::kCapsule:
      return "capsule";
    case ShapeType::kPlane:
      return "plane";
    case ShapeType::kCylinder:
      return "cylinder";
    case ShapeType::kMesh:
      return "mesh";
  }
  return "unknown";
}

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Upper limits that are not physics but protect the process: a typo like rows: 50000 would
// otherwise allocate gigabytes before anyone sees an error. (kMaxPasses: scene_config.h.)

std::string formatNumber(double value) {
  std::ostringstream out;
  out.precision(10);
  out << value;
  return out.str();
}

std::string formatVector(const Eigen::Vector3d& v) {
  return "[" + formatNumber(v.x()) + ", " + formatNumber(v.y()) + ", " + formatNumber(v.z()) + "]";
}

std::string indexed(const std::string& list, std::size_t index) {
  return list + "[" + std::to_string(index) + "]";
}

// A range of real numbers with open or closed ends; infinite ends are always open.
struct Range {
  double low;
  double high;
  bool low_open;
  bool high_open;

  bool contains(double v) const {
    return std::isfinite(v) && (low_open ? v > low : v >= low) &&
           (high_open ? v < high : v <= high);
  }
  // "> 0", ">= 0", "in (0, 2)" and the like.
  std::string text() const {
    if (std::isinf(high)) return (low_open ? "> " : ">= ") + formatNumber(low);
    return std::string("in ") + (low_open ? "(" : "[") + formatNumber(low) + ", " +
           formatNumber(high) + (high_open ? ")" : "]");
  }
};

const Range kPositive{0.0, kInf, true, true};
const Range kNonNegative{0.0, kInf, false, true};
const Range kUnit{0.0, 1.0, false, false};

void checkNumber(const std::string& key, double value, const Range& range) {
  if (!range.contains(value)) {
    throw ConfigError(key,
                      "must be a finite number " + range.text() + ", got " + formatNumber(value));
  }
}

void checkFinite(const std::string& key, double value) {
  if (!std::isfinite(value)) {
    throw ConfigError(key, "must be a finite number, got " + formatNumber(value));
  }
}

void checkFinite(const std::string& key, const Eigen::Vector3d& value) {
  if (!value.allFinite()) {
    throw ConfigError(key, "must be 3 finite numbers [x, y, z], got " + formatVector(value));
  }
}

void checkInteger(const std::string& key, std::int64_t value, std::int64_t low, std::int64_t high) {
  if (value < low || value > high) {
    throw ConfigError(key, "must be an integer in [" + std::to_string(low) + ", " +
                               std::to_string(high) + "], got " + std::to_string(value));
  }
}

// The quaternion is normalized by the reader; here only what the reader could not fix is refused.
void checkPose(const std::string& key, const Pose& pose) {
  checkFinite(key + " (position)", pose.position);
  const Eigen::Vector4d q = pose.orientation.coeffs();
  if (!q.allFinite() || q.norm() == 0.0) {
    throw ConfigError(key, "orientation (qx qy qz qw) must be finite and non-zero, got [" +
                               formatNumber(q.x()) + ", " + formatNumber(q.y()) + ", " +
                               formatNumber(q.z()) + ", " + formatNumber(q.w()) + "]");
  }
}

// tf2 refuses frame names with a leading '/' (a ROS 1 tf habit) at the first lookup, long after
// start-up; refuse them here where the key can be named.
void checkFrame(const std::string& key, const std::string& frame, bool may_be_empty) {
  if (frame.empty() && !may_be_empty) {
    throw ConfigError(key, "must be a non-empty tf frame name");
  }
  if (!frame.empty() && frame.front() == '/') {
    throw ConfigError(key, "must be a tf2 frame name without a leading '/', got '" + frame + "'");
  }
}

// Gripper and obstacle names become topic and service names (~<name>/pose), so they must be valid
// ROS graph name tokens; a bad one would otherwise throw inside the node's advertise().
void checkName(const std::string& key, const std::string& name, std::set<std::string>& used) {
  bool valid = !name.empty() && std::isalpha(static_cast<unsigned char>(name.front()));
  for (char c : name) {
    valid = valid && (std::isalnum(static_cast<unsigned char>(c)) || c == '_');
  }
  if (!valid) {
    throw ConfigError(key,
                      "must be a name of letters, digits and '_' starting with a letter (it "
                      "names the ~<name>/pose topic), got '" +
                          name + "'");
  }
  if (!used.insert(name).second) {
    throw ConfigError(key, "'" + name +
                               "' is used twice (gripper and obstacle names share the ~<name>/pose "
                               "topics and must all be different)");
  }
}

void checkParticleIndex(const std::string& key, int index, std::int64_t cloth_count) {
  if (index < 0 || index >= cloth_count) {
    throw ConfigError(key, "index " + std::to_string(index) + " out of range [0, " +
                               std::to_string(cloth_count - 1) + "]");
  }
}

void checkFriction(const std::string& key, const FrictionConfig& friction) {
  const double mu_s = friction.static_coefficient;
  checkNumber(key + ".static", mu_s, kNonNegative);
  // Kinetic friction above static would let a sliding contact stop and then be unable to start.
  checkNumber(key + ".kinetic", friction.kinetic_coefficient, Range{0.0, mu_s, false, false});
}

// A rope: a name, at least one segment each longer than the rope's diameter (its particles are
// contact spheres of its radius: neighbours must not touch), positive material constants.
void validateRope(const std::string& key, const RopeConfig& r, std::set<std::string>& names) {
  checkName(key + ".name", r.name, names);
  if (!r.points.empty()) {
    if (r.points.size() < 2) {
      throw ConfigError(key + ".points",
                        "at least 2 points, got " + std::to_string(r.points.size()));
    }
    for (std::size_t k = 0; k < r.points.size(); ++k)
      checkFinite(indexed(key + ".points", k), r.points[k]);
  } else {
    checkFinite(key + ".start", r.start);
    checkFinite(key + ".end", r.end);
    checkInteger(key + ".segments", r.segments, 1, 100000);
  }
  checkNumber(key + ".radius", r.radius, kPositive);
  checkNumber(key + ".density", r.density, kPositive);
  checkNumber(key + ".young_modulus", r.young_modulus, kPositive);
  checkNumber(key + ".shear_modulus", r.shear_modulus, kPositive);
  if (!std::isfinite(r.stretch_compliance)) {
    throw ConfigError(key + ".stretch_compliance", "a finite number (>= 0, or < 0: from E and G)");
  }
  const Vec3Array points = r.restPoints();
  for (std::size_t s = 0; s + 1 < points.size(); ++s) {
    const double length = (points[s + 1] - points[s]).norm();
    if (!(length > 2.0 * r.radius)) {
      throw ConfigError(key + (r.points.empty() ? ".segments" : ".points"),
                        "segment " + std::to_string(s) + " is " + std::to_string(length) +
                            " m long: each segment must be longer than the rope's diameter " +
                            std::to_string(2.0 * r.radius) +
                            " m (fewer segments, or a thinner rope)");
    }
  }
  const int last = static_cast<int>(points.size()) - 1;
  for (std::size_t k = 0; k < r.pinned.size(); ++k) {
    if (r.pinned[k] < 0 || r.pinned[k] > last) {
      throw ConfigError(indexed(key + ".pinned", k), "index " + std::to_string(r.pinned[k]) +
                                                         " out of range [0, " +
                                                         std::to_string(last) + "]");
    }
  }
}

void validateSolver(const SolverConfig& s) {
  checkInteger("solver.substeps", s.substeps, 1, kMaxPasses);
  checkInteger("solver.iterations", s.iterations, 1, kMaxPasses);
  checkNumber("solver.tolerance", s.tolerance, kNonNegative);
  // Over-relaxed Jacobi with averaging converges only for 0 < w < 2 (REFERENCE_CASES.md case 7).
  checkNumber("solver.relaxation", s.relaxation, Range{0.0, 2.0, true, true});
  checkFinite("solver.gravity", s.gravity);
  checkNumber("solver.damping", s.damping, kNonNegative);
  checkNumber("solver.stretch_stiffness", s.stretch_stiffness, kUnit);
  checkNumber("solver.bend_stiffness", s.bend_stiffness, kUnit);
  checkNumber("solver.spring_stiffness", s.spring_stiffness, kPositive);
  checkNumber("solver.spring_damping", s.spring_damping, kNonNegative);
  checkNumber("solver.bend_spring_stiffness", s.bend_spring_stiffness, kNonNegative);
  checkInteger("solver.levels", s.levels, 0, 16);
  checkNumber("solver.target_max_strain", s.target_max_strain, Range{0.0, 1.0, false, true});
  checkNumber("solver.target_penetration", s.target_penetration, Range{0.0, 1.0, false, true});
  checkInteger("solver.min_substeps", s.min_substeps, 1, kMaxPasses);
  checkInteger("solver.max_substeps", s.max_substeps, s.min_substeps, kMaxPasses);
  checkInteger("solver.threads", s.threads, 1, 64);
  checkInteger("solver.search_window", s.search_window, 0, kMaxPasses);
  checkNumber("solver.sleep_speed", s.sleep_speed, kNonNegative);
  checkNumber("solver.sleep_time", s.sleep_time, kPositive);
  checkNumber("solver.max_speed", s.max_speed, kPositive);
}

void validateCloth(const ClothConfig& c) {
  std::int64_t count = 0;
  if (!c.mesh.empty()) {
    // rows, cols and spacing are ignored with a mesh, so not checked.
    if (!c.mesh_data) {
      throw ConfigError("cloth.mesh",
                        "'" + c.mesh + "' is not loaded (the scene reader loads it: loadScene)");
    }
    checkNumber("cloth.mesh_scale", c.mesh_scale, kPositive);
    count = static_cast<std::int64_t>(c.mesh_data->vertices.size());
  } else {
    checkInteger("cloth.rows", c.rows, 1, kMaxParticles);
    checkInteger("cloth.cols", c.cols, 1, kMaxParticles);
    count = static_cast<std::int64_t>(c.rows) * c.cols;
    if (count < 2 || count > kMaxParticles) {
      throw ConfigError("cloth.rows", "rows * cols must be in [2, " +
                                          std::to_string(kMaxParticles) + "], got " +
                                          std::to_string(c.rows) + " * " + std::to_string(c.cols) +
                                          " = " + std::to_string(count));
    }
    checkNumber("cloth.spacing", c.spacing, kPositive);
    checkInteger("cloth.shear_diagonals", c.shear_diagonals, 1, 2);
  }
  checkNumber("cloth.mass", c.mass, kPositive);
  checkFinite("cloth.origin", c.origin);
  checkFinite("cloth.rpy", c.rpy);
  checkNumber("cloth.stretch_compliance", c.stretch_compliance, kNonNegative);
  checkFinite("cloth.bend_compliance", c.bend_compliance);
  checkNumber("cloth.thickness", c.thickness, kPositive);
  // A self-colliding grid thicker than its spacing: every particle's sphere reaches into its
  // neighbours', and every vertex lies within h of the triangles around it, so the self-collision
  // search lists most of the cloth against most of it (a step's work and memory grow with the
  // square of the particle count).
  if (c.self_collision && c.mesh.empty() && c.rows >= 2 && c.cols >= 2 &&
      !(c.thickness < c.spacing)) {
    throw ConfigError("cloth.thickness", "must be below cloth.spacing (" +
                                             std::to_string(c.spacing) +
                                             ") when cloth.self_collision is true, got " +
                                             std::to_string(c.thickness));
  }
  checkFriction("cloth.friction", c.friction);
  for (std::size_t k = 0; k < c.pinned.size(); ++k) {
    checkParticleIndex(indexed("cloth.pinned", k), c.pinned[k], count);
  }
  for (std::size_t k = 0; k < c.point_masses.size(); ++k) {
    const std::string key = indexed("cloth.point_masses", k);
    checkParticleIndex(key, c.point_masses[k].first, count);
    checkNumber(key + " (kg)", c.point_masses[k].second, kPositive);
  }
}

void validateGranular(const GranularConfig& g) {
  checkInteger("granular.count", g.count, 0, kMaxParticles);
  checkNumber("granular.radius", g.radius, kPositive);
  checkNumber("granular.mass", g.mass, kPositive);
  checkFinite("granular.region.min", g.region_min);
  checkFinite("granular.region.max", g.region_max);
  if ((g.region_min.array() > g.region_max.array()).any()) {
    throw ConfigError("granular.region", "min must be <= max in x, y and z, got min " +
                                             formatVector(g.region_min) + ", max " +
                                             formatVector(g.region_max));
  }
}

void validateGripper(const std::string& key, const GripperConfig& g, std::set<std::string>& names) {
  checkName(key + ".name", g.name, names);
  checkNumber(key + ".radius", g.radius, kPositive);
  checkFrame(key + ".tf_frame", g.tf_frame, true);
  double previous_t = 0.0;
  for (std::size_t k = 0; k < g.trajectory.size(); ++k) {
    const Waypoint& w = g.trajectory[k];
    const std::string wkey = indexed(key + ".trajectory", k);
    // Waypoints are searched in order; a time going backwards would make a segment unreachable.
    if (!std::isfinite(w.t) || w.t < previous_t) {
      throw ConfigError(wkey + ".t", "must be a finite time >= 0 and >= the previous waypoint's (" +
                                         formatNumber(previous_t) + " s), got " +
                                         formatNumber(w.t));
    }
    previous_t = w.t;
    checkPose(wkey + ".pose", w.pose);
    checkInteger(wkey + ".grasp", w.grasp, -1, 1);
  }
  if (g.repeat) {
    // The period is the last waypoint's t: the script must start at 0 and end where it starts,
    // or the gripper (and what it holds) would jump at each repeat.
    if (g.trajectory.size() < 2 || g.trajectory.front().t != 0.0 ||
        !(g.trajectory.back().t > 0.0)) {
      throw ConfigError(key + ".repeat",
                        "needs a trajectory of at least 2 waypoints from t = 0 to a "
                        "last t > 0 (the period)");
    }
    const Pose &first = g.trajectory.front().pose, &last = g.trajectory.back().pose;
    if ((first.position - last.position).norm() > 1e-9 ||
        first.orientation.angularDistance(last.orientation) > 1e-9) {
      throw ConfigError(key + ".repeat", "the last waypoint's pose (trajectory[" +
                                             std::to_string(g.trajectory.size() - 1) +
                                             "]) must be the first's: the trajectory starts "
                                             "again from it");
    }
  }
}

// The geometry of one shape: an obstacle (key "obstacles[i]") or a robot link's collision element
// (key "robot link 'x' collision i").
void validateShape(const std::string& key, const ObstacleConfig& o) {
  checkPose(key + ".pose", o.pose);
  checkNumber(key + ".padding", o.padding, kNonNegative);
  if (o.has_friction) checkFriction(key + ".friction", o.friction);
  switch (o.shape) {
    case ShapeType::kSphere:
      checkNumber(key + ".radius", o.radius, kPositive);
      break;
    case ShapeType::kCapsule:
      checkNumber(key + ".radius", o.radius, kPositive);
      checkNumber(key + ".length", o.length, kNonNegative);
      break;
    case ShapeType::kBox:
      checkFinite(key + ".size", o.size);
      if ((o.size.array() <= 0.0).any()) {
        throw ConfigError(key + ".size",
                          "every edge length must be > 0, got " + formatVector(o.size));
      }
      break;
    case ShapeType::kPlane:
      checkFinite(key + ".normal", o.normal);
      if (o.normal.norm() == 0.0) throw ConfigError(key + ".normal", "must be non-zero");
      checkFinite(key + ".offset", o.offset);
      break;
    case ShapeType::kCylinder:
      checkNumber(key + ".radius", o.radius, kPositive);
      checkNumber(key + ".length", o.length, kPositive);
      break;
    case ShapeType::kMesh:
      if (o.mesh.empty()) {
        throw ConfigError(key + ".mesh", "required: a mesh file path, file:// or package:// URI");
      }
      checkFinite(key + ".scale", o.scale);
      if ((o.scale.array() == 0.0).any()) {
        throw ConfigError(key + ".scale",
                          "every factor must be non-zero, got " + formatVector(o.scale));
      }
      // The scene reader loads it (scene_assets.h loadObstacleMeshes); a scene built in code must
      // load it too.
      if (!o.mesh_data) {
        throw ConfigError(key + ".mesh", "mesh '" + o.mesh + "' is not loaded");
      }
      break;
  }
}

void validateObstacle(const std::string& key, const ObstacleConfig& o,
                      std::set<std::string>& names) {
  checkName(key + ".name", o.name, names);
  checkFrame(key + ".tf_frame", o.tf_frame, true);
  validateShape(key, o);
}

// Image sizes are capped to protect the process, as kMaxPasses is: 4096 x 4096 floats is 64 MB.
constexpr int kMaxImageSide = 4096;

void validateCamera(const std::string& key, const CameraConfig& c, double step_rate,
                    std::set<std::string>& names) {
  checkName(key + ".name", c.name, names);
  checkFrame(key + ".frame", c.frame, false);
  if (c.has_pose) checkPose(key + ".pose", c.pose);
  checkInteger(key + ".width", c.width, 1, kMaxImageSide);
  checkInteger(key + ".height", c.height, 1, kMaxImageSide);
  checkNumber(key + ".fx", c.fx, kPositive);
  checkNumber(key + ".fy", c.fy, kPositive);
  checkFinite(key + ".cx", c.cx);
  checkFinite(key + ".cy", c.cy);
  // An image is rendered from the state after a step; faster than stepping would repeat states.
  checkNumber(key + ".rate", c.rate, Range{0.0, step_rate, true, false});
  checkNumber(key + ".range.min", c.range_min, kPositive);
  checkNumber(key + ".range.max", c.range_max, Range{c.range_min, kInf, true, true});
  checkNumber(key + ".noise", c.noise, kNonNegative);
  checkInteger(key + ".seed", c.seed, 0, std::numeric_limits<int>::max());
}

std::string jointNames(const RobotModel& model) {
  std::string out;
  for (const RobotJoint& joint : model.joints) {
    if (joint.type == JointType::kFixed || joint.mimic_joint >= 0) continue;
    out += (out.empty() ? "" : ", ") + joint.name;
  }
  return out.empty() ? "none that move" : out;
}

void validateRobot(const RobotConfig& r) {
  if (r.description.empty() && r.urdf_file.empty()) {
    throw ConfigError("robot.description",
                      "must name the URDF parameter (default robot_description) when "
                      "robot.urdf_file is empty");
  }
  for (std::size_t k = 0; k < r.links.size(); ++k) {
    if (r.links[k].empty()) throw ConfigError(indexed("robot.links", k), "must be a link name");
  }
  checkNumber("robot.padding", r.padding, kNonNegative);
  checkFriction("robot.friction", r.friction);
  checkPose("robot.pose", r.pose);
  const RobotModel& model = r.model;
  const bool loaded = !model.links.empty();
  double previous_t = 0.0;
  for (std::size_t k = 0; k < r.joint_trajectory.size(); ++k) {
    const JointWaypoint& w = r.joint_trajectory[k];
    const std::string wkey = indexed("robot.joint_trajectory", k);
    if (!std::isfinite(w.t) || w.t < previous_t) {
      throw ConfigError(wkey + ".t", "must be a finite time >= 0 and >= the previous waypoint's (" +
                                         formatNumber(previous_t) + " s), got " +
                                         formatNumber(w.t));
    }
    previous_t = w.t;
    for (const auto& position : w.positions) {
      const std::string pkey = wkey + ".positions." + position.first;
      checkFinite(pkey, position.second);
      if (!loaded) continue;  // the node checks again once robot_description is read
      const int j = model.jointIndex(position.first);
      if (j < 0) {
        throw ConfigError(pkey, "no joint '" + position.first +
                                    "' in the URDF (joints: " + jointNames(model) + ")");
      }
      if (model.joints[j].type == JointType::kFixed) {
        throw ConfigError(pkey, "joint '" + position.first +
                                    "' is fixed (joints that move: " + jointNames(model) + ")");
      }
      if (model.joints[j].mimic_joint >= 0) {
        throw ConfigError(pkey, "joint '" + position.first + "' mimics joint '" +
                                    model.joints[model.joints[j].mimic_joint].name +
                                    "': set that one (joints that move: " + jointNames(model) +
                                    ")");
      }
    }
  }
  for (const RobotLink& link : model.links) {
    for (std::size_t c = 0; c < link.collisions.size(); ++c) {
      validateShape("robot link '" + link.name + "' collision " + std::to_string(c),
                    link.collisions[c]);
    }
  }
}

// The cloth must start inside `bounds`: a particle outside is moved onto the box in the first
// step, and a cloth partly outside collapses there (a horizontal grid whose rows leave the box
// along y becomes a line of degenerate triangles, whose self-collision search then tests every
// pair: fuzz_scene_yaml found a 32 x 32 scene spending 1.8 s a step). A grid is an affine image of
// its indices, so its four corners decide; a mesh cloth checks every vertex. 1e-9 m of slack
// keeps a cloth laid exactly on a face of the box (rounding of origin + R x).
void checkClothInsideBounds(const SceneConfig& scene) {
  const ClothConfig& cloth = scene.cloth;
  const Eigen::Matrix3d rotation = rotationFromRpy(cloth.rpy);
  const Eigen::Vector3d lo = scene.bounds.min.array() - 1e-9, hi = scene.bounds.max.array() + 1e-9;
  auto check = [&](const Eigen::Vector3d& x, const std::string& which) {
    if ((x.array() >= lo.array()).all() && (x.array() <= hi.array()).all()) return;
    throw ConfigError("bounds", "the cloth must start inside the bounds: its " + which + " is at " +
                                    formatVector(x) + ", outside min " +
                                    formatVector(scene.bounds.min) + ", max " +
                                    formatVector(scene.bounds.max) +
                                    " (move cloth.origin or widen the bounds)");
  };
  if (cloth.mesh_data) {
    const Vec3Array& vertices = cloth.mesh_data->vertices;
    for (std::size_t i = 0; i < vertices.size(); ++i) {
      check(meshStartPosition(cloth, rotation, vertices[i]), "vertex " + std::to_string(i));
    }
    return;
  }
  for (const int r : {0, cloth.rows - 1}) {
    for (const int c : {0, cloth.cols - 1}) {
      check(gridStartPosition(cloth, rotation, r, c),
            "corner particle (row " + std::to_string(r) + ", col " + std::to_string(c) + ")");
    }
  }
}

// A rope outside the bounds would be pushed in at its first step, not where the scene put it.
void checkRopesInsideBounds(const SceneConfig& scene) {
  const Eigen::Vector3d lo = scene.bounds.min.array() - 1e-9, hi = scene.bounds.max.array() + 1e-9;
  for (std::size_t r = 0; r < scene.ropes.size(); ++r) {
    const Vec3Array points = scene.ropes[r].restPoints();
    for (std::size_t k = 0; k < points.size(); ++k) {
      const Eigen::Vector3d& x = points[k];
      if ((x.array() >= lo.array()).all() && (x.array() <= hi.array()).all()) continue;
      throw ConfigError(
          "bounds", "ropes[" + std::to_string(r) + "] must start inside the bounds: its particle " +
                        std::to_string(k) + " is at " + formatVector(x) + ", outside min " +
                        formatVector(scene.bounds.min) + ", max " + formatVector(scene.bounds.max) +
                        " (move the rope or widen the bounds)");
    }
  }
}

}  // namespace

void validate(const SceneConfig& scene) {
  checkFrame("frame_id", scene.frame_id, false);
  checkNumber("step_rate", scene.step_rate, Range{0.0, 10000.0, true, false});
  // Publishing faster than stepping would send the same state twice.
  checkNumber("publish_rate", scene.publish_rate, Range{0.0, scene.step_rate, true, false});
  validateSolver(scene.solver);
  validateCloth(scene.cloth);
  if (scene.solver.levels > 0 && !scene.cloth.mesh.empty()) {
    throw ConfigError("solver.levels",
                      "coarse levels need a grid cloth; cloth.mesh is set (use 0)");
  }
  if (scene.solver.levels > 0 && scene.cloth.stretch_compliance > 0.0) {
    throw ConfigError(
        "solver.levels",
        "coarse levels are inextensible: they need cloth.stretch_compliance = 0, got " +
            std::to_string(scene.cloth.stretch_compliance) + " (use 0 levels)");
  }
  validateGranular(scene.granular);
  std::set<std::string> names;
  for (std::size_t k = 0; k < scene.ropes.size(); ++k) {
    validateRope(indexed("ropes", k), scene.ropes[k], names);
  }
  if (!scene.ropes.empty() && scene.solver.method == Method::kMassSpring) {
    throw ConfigError(
        "solver.method",
        "ropes are solved as position-based rods: use xpbd, pbd or verlet with ropes");
  }
  for (std::size_t k = 0; k < scene.grippers.size(); ++k) {
    validateGripper(indexed("grippers", k), scene.grippers[k], names);
  }
  for (std::size_t k = 0; k < scene.obstacles.size(); ++k) {
    validateObstacle(indexed("obstacles", k), scene.obstacles[k], names);
  }
  validateRobot(scene.robot);
  // Camera names share the set: a camera called like a gripper would share its ~<name>/ namespace.
  for (std::size_t k = 0; k < scene.cameras.size(); ++k) {
    validateCamera(indexed("cameras", k), scene.cameras[k], scene.step_rate, names);
  }
  if (scene.bounds.enabled) {
    checkFinite("bounds.min", scene.bounds.min);
    checkFinite("bounds.max", scene.bounds.max);
    if ((scene.bounds.min.array() >= scene.bounds.max.array()).any()) {
      throw ConfigError("bounds", "min must be < max in x, y and z, got min " +
                                      formatVector(scene.bounds.min) + ", max " +
                                      formatVector(scene.bounds.max));
    }
    checkClothInsideBounds(scene);
    checkRopesInsideBounds(scene);
  }
}

}  // namespace pbd_cloth
