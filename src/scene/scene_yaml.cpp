// Scene YAML -> SceneConfig with yaml-cpp. The reader is strict on purpose: a misspelt key that is
// silently ignored leaves a default in place and costs a user an afternoon, so every map is checked
// against its known keys before anything is read, and every conversion names the dotted key.
#include "pbd_cloth/scene/scene_yaml.h"

#include "pbd_cloth/scene/scene_assets.h"

#include <algorithm>
#include <cctype>
#include <climits>
#include <cmath>
#include <filesystem>
#include <set>
#include <vector>

namespace pbd_cloth {
namespace {

using Names = std::vector<std::string>;

std::string joinNames(const Names& names) {
  std::string out;
  for (const std::string& name : names) out += (out.empty() ? "" : ", ") + name;
  return out;
}

std::string indexed(const std::string& key, std::size_t index) {
  return key + "[" + std::to_string(index) + "]";
}

// What a node is, for "expected X, got Y" messages.
std::string describe(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Scalar:
      return "'" + node.Scalar() + "'";
    case YAML::NodeType::Sequence:
      return "a list of " + std::to_string(node.size());
    case YAML::NodeType::Map:
      return "a map";
    default:
      return "nothing (null)";
  }
}

[[noreturn]] void wrongType(const YAML::Node& node, const std::string& key,
                            const std::string& expected) {
  throw ConfigError(key, "must be " + expected + ", got " + describe(node));
}

// --- Scalars and small lists -------------------------------------------------------------------
// convert<T>::decode reports failure instead of throwing, so each failure is reported once, here,
// with the key. It also rejects trailing text ("1.5 m") and accepts .inf/.nan, left to validate().

double toDouble(const YAML::Node& node, const std::string& key) {
  double value = 0.0;
  if (!node.IsScalar() || !YAML::convert<double>::decode(node, value)) {
    wrongType(node, key, "a number");
  }
  return value;
}

// Integers written as 10.0 (or by a tool that stores every number as a double) are accepted when
// they are integral.
int toInt(const YAML::Node& node, const std::string& key) {
  long long integer = 0;
  if (node.IsScalar() && YAML::convert<long long>::decode(node, integer)) {
    if (integer < INT_MIN || integer > INT_MAX) wrongType(node, key, "an integer of int range");
    return static_cast<int>(integer);
  }
  double real = 0.0;
  if (!node.IsScalar() || !YAML::convert<double>::decode(node, real) || real != std::floor(real)) {
    wrongType(node, key, "an integer");
  }
  if (real < INT_MIN || real > INT_MAX) wrongType(node, key, "an integer of int range");
  return static_cast<int>(real);
}

bool toBool(const YAML::Node& node, const std::string& key) {
  bool value = false;
  if (!node.IsScalar() || !YAML::convert<bool>::decode(node, value)) {
    wrongType(node, key, "true or false");
  }
  return value;
}

// `tf_frame:` with nothing after it reads as null; it means the empty string.
std::string toText(const YAML::Node& node, const std::string& key) {
  if (node.IsNull()) return std::string();
  if (!node.IsScalar()) wrongType(node, key, "a string");
  return node.Scalar();
}

// The numbers of a fixed-length list; element errors name the element (cloth.origin[1]).
std::vector<double> toNumbers(const YAML::Node& node, const std::string& key, std::size_t count,
                              const char* layout) {
  if (!node.IsSequence() || node.size() != count) {
    wrongType(node, key, "a list of " + std::to_string(count) + " numbers " + layout);
  }
  std::vector<double> out(count);
  for (std::size_t k = 0; k < count; ++k) out[k] = toDouble(node[k], indexed(key, k));
  return out;
}

Eigen::Vector3d toVector3(const YAML::Node& node, const std::string& key) {
  const std::vector<double> v = toNumbers(node, key, 3, "[x, y, z]");
  return Eigen::Vector3d(v[0], v[1], v[2]);
}

Pose toPose(const YAML::Node& node, const std::string& key) {
  const std::vector<double> v = toNumbers(node, key, 7, "[x, y, z, qx, qy, qz, qw]");
  Pose pose;
  pose.position = Eigen::Vector3d(v[0], v[1], v[2]);
  // Eigen's constructor takes w first; the YAML layout is ROS's (x, y, z, w).
  pose.orientation = Eigen::Quaterniond(v[6], v[3], v[4], v[5]);
  const double norm = pose.orientation.norm();
  // Written as !(norm > 0) so that a NaN quaternion is refused here too.
  if (!(norm > 0.0) || !std::isfinite(norm)) {
    throw ConfigError(key, "the quaternion (qx, qy, qz, qw) must be finite and non-zero");
  }
  // Hand-written quaternions (0.707 instead of sqrt(0.5)) are slightly off unit length; rotations
  // and slerp assume unit length.
  pose.orientation.normalize();
  return pose;
}

// One of the words toString(E) gives for `values`.
template <typename E>
E toWord(const YAML::Node& node, const std::string& key, std::initializer_list<E> values) {
  Names words;
  for (E value : values) words.push_back(toString(value));
  const std::string word = node.IsScalar() ? node.Scalar() : std::string();
  for (E value : values) {
    if (word == toString(value)) return value;
  }
  wrongType(node, key, "one of " + joinNames(words));
}

// --- Maps ----------------------------------------------------------------------------------------

// One map of the scene tree and its dotted key. The constructor refuses unknown and repeated keys
// (yaml-cpp keeps both copies of a repeated key and lookups see only the first), so the reads below
// only look up known names. A null or absent map reads as an empty one: its keys keep defaults.
class MapReader {
 public:
  MapReader(const YAML::Node& node, std::string key, Names allowed, const Names& ignored = {})
      : node_(node), key_(std::move(key)), allowed_(std::move(allowed)) {
    if (!node_ || node_.IsNull()) return;
    if (!node_.IsMap()) wrongType(node_, where(), "a map with keys " + joinNames(allowed_));
    std::set<std::string> seen;
    for (const auto& entry : node_) {
      if (!entry.first.IsScalar()) wrongType(entry.first, where(), "a map with plain-text keys");
      const std::string& name = entry.first.Scalar();
      if (!seen.insert(name).second) throw ConfigError(keyOf(name), "given twice");
      if (std::find(ignored.begin(), ignored.end(), name) != ignored.end()) continue;
      if (std::find(allowed_.begin(), allowed_.end(), name) == allowed_.end()) {
        throw ConfigError(keyOf(name), "unknown key (known here: " + joinNames(allowed_) + ")");
      }
    }
  }

  std::string keyOf(const std::string& name) const {
    return key_.empty() ? name : key_ + "." + name;
  }
  // The node of `name`; an undefined node when the key is absent.
  YAML::Node get(const std::string& name) const {
    // A default YAML::Node() is a defined null, so absence is a lookup in an empty const map.
    static const YAML::Node kEmpty(YAML::NodeType::Map);
    const YAML::Node& map = node_ && node_.IsMap() ? node_ : kEmpty;
    return map[name];
  }
  bool has(const std::string& name) const { return static_cast<bool>(get(name)); }
  YAML::Node require(const std::string& name) const {
    if (!has(name)) throw ConfigError(keyOf(name), "required");
    return get(name);
  }
  // Names present here, for the per-shape key check of obstacles.
  Names present() const {
    Names names;
    if (node_ && node_.IsMap()) {
      for (const auto& entry : node_) names.push_back(entry.first.Scalar());
    }
    return names;
  }

  void read(const std::string& name, double& out) const { readWith(name, out, toDouble); }
  void read(const std::string& name, int& out) const { readWith(name, out, toInt); }
  void read(const std::string& name, bool& out) const { readWith(name, out, toBool); }
  void read(const std::string& name, std::string& out) const { readWith(name, out, toText); }
  void read(const std::string& name, Eigen::Vector3d& out) const { readWith(name, out, toVector3); }
  void read(const std::string& name, Pose& out) const { readWith(name, out, toPose); }

 private:
  std::string where() const { return key_.empty() ? "scene" : key_; }

  template <typename T, typename Convert>
  void readWith(const std::string& name, T& out, Convert convert) const {
    if (const YAML::Node node = get(name)) out = convert(node, keyOf(name));
  }

  YAML::Node node_;
  std::string key_;
  Names allowed_;
};

// A list value; null or absent reads as an empty list.
YAML::Node listOf(const MapReader& map, const std::string& name, const char* expected) {
  const YAML::Node node = map.get(name);
  if (!node || node.IsNull()) return YAML::Node(YAML::NodeType::Sequence);
  if (!node.IsSequence()) wrongType(node, map.keyOf(name), expected);
  return node;
}

// --- Sections ------------------------------------------------------------------------------------

// Keys the solver section offered once, and what a scene that still has one does instead: it
// fails to load with this message rather than as an unknown key. Options measured as buying
// nothing left the product (their measurements: doc/journal.md); the switches that only
// compare code paths moved to cloth_bench's command line.
struct RemovedKey {
  const char* name;
  const char* message;
};
const RemovedKey kRemovedSolverKeys[] = {
    {"chebyshev",
     "was removed (Chebyshev acceleration measured no cheaper than more substeps): raise "
     "solver.substeps instead"},
    {"levels_interpolate",
     "was removed (HPBD's interpolation between the levels measured unstable): solver.levels "
     "alone remains"},
    {"simd", "moved to cloth_bench --no-simd (a switch for comparing code paths, not a scene key)"},
    {"avx512",
     "moved to cloth_bench --no-avx512 (a switch for comparing code paths, not a scene key)"},
    {"taut_chains",
     "was removed (a special case of one geometry: it held a grid row straight only while its two "
     "held ends were exactly its rest length apart, so one micrometre of slack turned it off, and "
     "where it acted it turned a suspension from two corners into one from an edge): raise "
     "solver.substeps, or turn cloth.tethers on for a hanging cloth"},
};

void readSolver(const YAML::Node& node, SolverConfig& s) {
  if (node && node.IsMap()) {
    for (const RemovedKey& removed : kRemovedSolverKeys) {
      if (node[removed.name]) {
        throw ConfigError(std::string("solver.") + removed.name, removed.message);
      }
    }
  }
  const MapReader map(node, "solver",
                      {"method",
                       "substeps",
                       "iterations",
                       "tolerance",
                       "ordering",
                       "relaxation",
                       "jacobi_averaging",
                       "gravity",
                       "damping",
                       "stretch_stiffness",
                       "bend_stiffness",
                       "spring_stiffness",
                       "spring_damping",
                       "bend_spring_stiffness",
                       "levels",
                       "max_speed",
                       "threads",
                       "sleep_speed",
                       "sleep_time",
                       "search_window",
                       "adaptive_threads",
                       "target_max_strain",
                       "target_penetration",
                       "min_substeps",
                       "max_substeps"});
  if (map.has("method")) {
    s.method = toWord(map.get("method"), map.keyOf("method"),
                      {Method::kXpbd, Method::kPbd, Method::kVerlet, Method::kMassSpring});
  }
  if (map.has("ordering")) {
    s.ordering = toWord(map.get("ordering"), map.keyOf("ordering"),
                        {Ordering::kGaussSeidel, Ordering::kJacobi});
  }
  map.read("substeps", s.substeps);
  map.read("iterations", s.iterations);
  map.read("tolerance", s.tolerance);
  map.read("relaxation", s.relaxation);
  map.read("jacobi_averaging", s.jacobi_averaging);
  map.read("gravity", s.gravity);
  map.read("damping", s.damping);
  map.read("stretch_stiffness", s.stretch_stiffness);
  map.read("bend_stiffness", s.bend_stiffness);
  map.read("spring_stiffness", s.spring_stiffness);
  map.read("spring_damping", s.spring_damping);
  map.read("bend_spring_stiffness", s.bend_spring_stiffness);
  map.read("levels", s.levels);
  map.read("max_speed", s.max_speed);
  map.read("threads", s.threads);
  map.read("adaptive_threads", s.adaptive_threads);
  map.read("sleep_speed", s.sleep_speed);
  map.read("sleep_time", s.sleep_time);
  map.read("search_window", s.search_window);
  map.read("target_max_strain", s.target_max_strain);
  map.read("target_penetration", s.target_penetration);
  map.read("min_substeps", s.min_substeps);
  map.read("max_substeps", s.max_substeps);
}

void readCloth(const YAML::Node& node, ClothConfig& c) {
  const MapReader map(
      node, "cloth",
      {"mesh", "mesh_scale", "rows", "cols", "spacing", "mass", "origin", "rpy",
       "stretch_compliance", "bend_compliance", "thickness", "self_collision", "friction", "pinned",
       "point_masses", "tethers", "shear", "shear_diagonals"});
  map.read("mesh", c.mesh);
  map.read("mesh_scale", c.mesh_scale);
  map.read("rows", c.rows);
  map.read("cols", c.cols);
  map.read("spacing", c.spacing);
  map.read("mass", c.mass);
  map.read("origin", c.origin);
  map.read("rpy", c.rpy);
  map.read("stretch_compliance", c.stretch_compliance);
  map.read("bend_compliance", c.bend_compliance);
  map.read("thickness", c.thickness);
  map.read("self_collision", c.self_collision);
  map.read("tethers", c.tethers);
  map.read("shear", c.shear);
  map.read("shear_diagonals", c.shear_diagonals);

  const MapReader friction(map.get("friction"), map.keyOf("friction"), {"static", "kinetic"});
  friction.read("static", c.friction.static_coefficient);
  friction.read("kinetic", c.friction.kinetic_coefficient);

  if (map.has("pinned")) {
    const YAML::Node pinned = listOf(map, "pinned", "a list of particle indices");
    c.pinned.clear();
    for (std::size_t k = 0; k < pinned.size(); ++k) {
      c.pinned.push_back(toInt(pinned[k], indexed("cloth.pinned", k)));
    }
  }
  if (map.has("point_masses")) {
    const YAML::Node masses = listOf(map, "point_masses", "a list of [index, kg] pairs");
    c.point_masses.clear();
    for (std::size_t k = 0; k < masses.size(); ++k) {
      const std::string key = indexed("cloth.point_masses", k);
      const YAML::Node pair = masses[k];
      if (!pair.IsSequence() || pair.size() != 2) wrongType(pair, key, "a pair [index, kg]");
      c.point_masses.emplace_back(toInt(pair[0], indexed(key, 0)),
                                  toDouble(pair[1], indexed(key, 1)));
    }
  }
}

RopeConfig readRope(const YAML::Node& node, const std::string& key) {
  const MapReader map(node, key,
                      {"name", "points", "start", "end", "segments", "radius", "density",
                       "young_modulus", "shear_modulus", "stretch_compliance", "pinned"});
  RopeConfig r;
  map.read("name", r.name);
  if (map.has("points")) {
    const YAML::Node points = listOf(map, "points", "a list of [x, y, z] points");
    for (std::size_t k = 0; k < points.size(); ++k) {
      r.points.push_back(toVector3(points[k], indexed(map.keyOf("points"), k)));
    }
  }
  map.read("start", r.start);
  map.read("end", r.end);
  map.read("segments", r.segments);
  map.read("radius", r.radius);
  map.read("density", r.density);
  map.read("young_modulus", r.young_modulus);
  map.read("shear_modulus", r.shear_modulus);
  map.read("stretch_compliance", r.stretch_compliance);
  if (map.has("pinned")) {
    const YAML::Node pinned = listOf(map, "pinned", "a list of the rope's particle indices");
    for (std::size_t k = 0; k < pinned.size(); ++k) {
      r.pinned.push_back(toInt(pinned[k], indexed(map.keyOf("pinned"), k)));
    }
  }
  return r;
}

void readGranular(const YAML::Node& node, GranularConfig& g) {
  const MapReader map(node, "granular", {"count", "radius", "mass", "region"});
  map.read("count", g.count);
  map.read("radius", g.radius);
  map.read("mass", g.mass);
  const MapReader region(map.get("region"), map.keyOf("region"), {"min", "max"});
  region.read("min", g.region_min);
  region.read("max", g.region_max);
}

Waypoint readWaypoint(const YAML::Node& node, const std::string& key) {
  const MapReader map(node, key, {"t", "pose", "grasp"});
  if (!node || node.IsNull()) wrongType(node, key, "a map {t, pose, grasp}");
  Waypoint w;
  w.t = toDouble(map.require("t"), map.keyOf("t"));
  w.pose = toPose(map.require("pose"), map.keyOf("pose"));
  if (map.has("grasp")) w.grasp = toBool(map.get("grasp"), map.keyOf("grasp")) ? 1 : 0;
  return w;
}

GripperConfig readGripper(const YAML::Node& node, const std::string& key) {
  const MapReader map(node, key, {"name", "radius", "tf_frame", "trajectory", "repeat"});
  if (!node || node.IsNull()) {
    wrongType(node, key, "a map {name, radius, tf_frame, trajectory, repeat}");
  }
  GripperConfig g;
  map.read("name", g.name);
  map.read("radius", g.radius);
  map.read("tf_frame", g.tf_frame);
  map.read("repeat", g.repeat);
  const YAML::Node trajectory = listOf(map, "trajectory", "a list of waypoints {t, pose, grasp}");
  for (std::size_t k = 0; k < trajectory.size(); ++k) {
    g.trajectory.push_back(readWaypoint(trajectory[k], indexed(map.keyOf("trajectory"), k)));
  }
  return g;
}

// The keys each shape takes besides name, shape and pose. A key of another shape (a radius on a
// box) is refused: it would otherwise be ignored while the user believes it acts.
Names shapeKeys(ShapeType shape) {
  switch (shape) {
    case ShapeType::kSphere:
      return {"radius"};
    case ShapeType::kBox:
      return {"size"};
    case ShapeType::kCapsule:
      return {"radius", "length"};
    case ShapeType::kPlane:
      return {"normal", "offset"};
    case ShapeType::kCylinder:
      return {"radius", "length"};
    case ShapeType::kMesh:
      return {"mesh", "scale"};
  }
  return {};
}

// A mesh scale: [sx, sy, sz], or one number for all three axes.
Eigen::Vector3d toScale(const YAML::Node& node, const std::string& key) {
  if (node.IsScalar()) return Eigen::Vector3d::Constant(toDouble(node, key));
  if (!node.IsSequence() || node.size() != 3) {
    wrongType(node, key, "a list of 3 numbers [sx, sy, sz] or one number");
  }
  return toVector3(node, key);
}

ObstacleConfig readObstacle(const YAML::Node& node, const std::string& key) {
  const Names common = {"name", "shape", "pose", "tf_frame"};
  const MapReader map(node, key,
                      {"name", "shape", "pose", "tf_frame", "radius", "size", "length", "normal",
                       "offset", "mesh", "scale"});
  if (!node || node.IsNull()) wrongType(node, key, "a map {name, shape, ...}");
  ObstacleConfig o;
  o.shape = toWord(map.require("shape"), map.keyOf("shape"),
                   {ShapeType::kSphere, ShapeType::kBox, ShapeType::kCapsule, ShapeType::kCylinder,
                    ShapeType::kPlane, ShapeType::kMesh});
  Names allowed = common;
  for (const std::string& name : shapeKeys(o.shape)) allowed.push_back(name);
  for (const std::string& name : map.present()) {
    if (std::find(allowed.begin(), allowed.end(), name) == allowed.end()) {
      throw ConfigError(map.keyOf(name), std::string("not used by a ") + toString(o.shape) +
                                             " (it takes " + joinNames(allowed) + ")");
    }
  }
  map.read("name", o.name);
  map.read("pose", o.pose);
  map.read("radius", o.radius);
  map.read("size", o.size);
  map.read("length", o.length);
  map.read("normal", o.normal);
  map.read("offset", o.offset);
  map.read("tf_frame", o.tf_frame);
  if (o.shape == ShapeType::kMesh) {
    o.mesh = toText(map.require("mesh"), map.keyOf("mesh"));
    if (map.has("scale")) o.scale = toScale(map.get("scale"), map.keyOf("scale"));
  }
  return o;
}

// A name in a list (a link name): a plain non-null string.
std::string toName(const YAML::Node& node, const std::string& key) {
  if (!node.IsScalar()) wrongType(node, key, "a name");
  return node.Scalar();
}

JointWaypoint readJointWaypoint(const YAML::Node& node, const std::string& key) {
  const MapReader map(node, key, {"t", "positions"});
  if (!node || node.IsNull()) wrongType(node, key, "a map {t, positions: {joint: value, ...}}");
  JointWaypoint w;
  w.t = toDouble(map.require("t"), map.keyOf("t"));
  const YAML::Node positions = map.require("positions");
  const std::string positions_key = map.keyOf("positions");
  if (positions.IsNull()) return w;
  if (!positions.IsMap()) wrongType(positions, positions_key, "a map {joint_name: value, ...}");
  std::set<std::string> seen;
  for (const auto& entry : positions) {
    if (!entry.first.IsScalar()) wrongType(entry.first, positions_key, "a map with joint names");
    const std::string& joint = entry.first.Scalar();
    const std::string joint_key = positions_key + "." + joint;
    if (!seen.insert(joint).second) throw ConfigError(joint_key, "given twice");
    w.positions.emplace_back(joint, toDouble(entry.second, joint_key));
  }
  return w;
}

void readRobot(const YAML::Node& node, RobotConfig& r) {
  r.enabled = node && !node.IsNull();
  const MapReader map(
      node, "robot",
      {"description", "urdf_file", "links", "padding", "friction", "pose", "joint_trajectory"});
  map.read("description", r.description);
  map.read("urdf_file", r.urdf_file);
  const YAML::Node links = listOf(map, "links", "a list of link names");
  for (std::size_t k = 0; k < links.size(); ++k) {
    r.links.push_back(toName(links[k], indexed(map.keyOf("links"), k)));
  }
  map.read("padding", r.padding);
  const MapReader friction(map.get("friction"), map.keyOf("friction"), {"static", "kinetic"});
  friction.read("static", r.friction.static_coefficient);
  friction.read("kinetic", r.friction.kinetic_coefficient);
  map.read("pose", r.pose);
  const YAML::Node trajectory =
      listOf(map, "joint_trajectory", "a list of waypoints {t, positions: {joint: value}}");
  for (std::size_t k = 0; k < trajectory.size(); ++k) {
    r.joint_trajectory.push_back(
        readJointWaypoint(trajectory[k], indexed(map.keyOf("joint_trajectory"), k)));
  }
}

CameraConfig readCamera(const YAML::Node& node, const std::string& key) {
  const MapReader map(node, key,
                      {"name", "frame", "pose", "width", "height", "fx", "fy", "cx", "cy", "rate",
                       "range", "noise", "seed"});
  if (!node || node.IsNull()) wrongType(node, key, "a map {name, frame, width, height, ...}");
  CameraConfig c;
  map.read("name", c.name);
  map.read("frame", c.frame);
  // `pose: []` (as INTERFACE.md writes it) or no pose: the camera follows its frame in tf.
  const YAML::Node pose = map.get("pose");
  c.has_pose = pose && !pose.IsNull() && !(pose.IsSequence() && pose.size() == 0);
  if (c.has_pose) c.pose = toPose(pose, map.keyOf("pose"));
  map.read("width", c.width);
  map.read("height", c.height);
  map.read("fx", c.fx);
  map.read("fy", c.fy);
  c.cx = (c.width - 1) / 2.0;
  c.cy = (c.height - 1) / 2.0;
  map.read("cx", c.cx);
  map.read("cy", c.cy);
  map.read("rate", c.rate);
  const MapReader range(map.get("range"), map.keyOf("range"), {"min", "max"});
  range.read("min", c.range_min);
  range.read("max", c.range_max);
  map.read("noise", c.noise);
  map.read("seed", c.seed);
  return c;
}

// Top-level keys accepted and ignored: see scene_yaml.h.
const Names kIgnoredTopLevelKeys = {"description"};

SceneConfig readScene(const YAML::Node& root) {
  const MapReader map(root, "",
                      {"frame_id", "step_rate", "publish_rate", "solver", "cloth", "granular",
                       "ropes", "grippers", "bounds", "obstacles", "robot", "cameras"},
                      kIgnoredTopLevelKeys);
  SceneConfig scene;
  map.read("frame_id", scene.frame_id);
  map.read("step_rate", scene.step_rate);
  map.read("publish_rate", scene.publish_rate);
  readSolver(map.get("solver"), scene.solver);
  readCloth(map.get("cloth"), scene.cloth);
  readGranular(map.get("granular"), scene.granular);

  const YAML::Node ropes = listOf(map, "ropes", "a list of ropes");
  for (std::size_t k = 0; k < ropes.size(); ++k) {
    scene.ropes.push_back(readRope(ropes[k], indexed("ropes", k)));
  }
  const YAML::Node grippers = listOf(map, "grippers", "a list of grippers");
  for (std::size_t k = 0; k < grippers.size(); ++k) {
    scene.grippers.push_back(readGripper(grippers[k], indexed("grippers", k)));
  }
  const YAML::Node obstacles = listOf(map, "obstacles", "a list of obstacles");
  for (std::size_t k = 0; k < obstacles.size(); ++k) {
    scene.obstacles.push_back(readObstacle(obstacles[k], indexed("obstacles", k)));
  }

  const YAML::Node bounds = map.get("bounds");
  scene.bounds.enabled = bounds && !bounds.IsNull();
  const MapReader bounds_map(bounds, "bounds", {"min", "max"});
  bounds_map.read("min", scene.bounds.min);
  bounds_map.read("max", scene.bounds.max);
  readRobot(map.get("robot"), scene.robot);
  const YAML::Node cameras = listOf(map, "cameras", "a list of cameras");
  for (std::size_t k = 0; k < cameras.size(); ++k) {
    scene.cameras.push_back(readCamera(cameras[k], indexed("cameras", k)));
  }
  return scene;
}

// Splits "a.b.c" into its parts; empty parts ("a..b", ".a") are refused.
Names splitKey(const std::string& key) {
  Names parts;
  std::size_t begin = 0;
  while (true) {
    const std::size_t end = key.find('.', begin);
    parts.push_back(key.substr(begin, end - begin));
    if (parts.back().empty()) throw ConfigError(key, "empty part in the dotted key");
    if (end == std::string::npos) return parts;
    begin = end + 1;
  }
}

bool parseIndex(const std::string& part, std::size_t& index) {
  if (part.empty() || !std::all_of(part.begin(), part.end(), ::isdigit)) return false;
  index = std::stoul(part);
  return true;
}

}  // namespace

SceneConfig sceneFromYaml(const YAML::Node& root, const std::string& base_directory) {
  SceneConfig scene;
  try {
    scene = readScene(root);
  } catch (const YAML::Exception& e) {
    // Every conversion above names its key; this is the backstop for yaml-cpp surprises.
    throw ConfigError("scene", e.what());
  }
  // Paths are stored resolved, so messages, warnings and later reloads name the file actually read.
  for (ObstacleConfig& o : scene.obstacles) {
    if (o.shape == ShapeType::kMesh) o.mesh = resolveScenePath(o.mesh, base_directory);
  }
  scene.robot.urdf_file = resolveScenePath(scene.robot.urdf_file, base_directory);
  scene.cloth.mesh = resolveScenePath(scene.cloth.mesh, base_directory);
  if (!scene.cloth.mesh.empty()) loadClothMesh(scene);
  loadObstacleMeshes(scene);
  if (!scene.robot.urdf_file.empty()) loadRobotFile(scene);
  validate(scene);
  return scene;
}

YAML::Node loadSceneYaml(const std::string& path) {
  try {
    return YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw ConfigError("file", "cannot read '" + path + "'");
  } catch (const YAML::Exception& e) {
    throw ConfigError("file", path + ": " + e.what());
  }
}

SceneConfig loadScene(const std::string& path) {
  return sceneFromYaml(loadSceneYaml(path), sceneFileDirectory(path));
}

std::string sceneFileDirectory(const std::string& path) {
  // "scene.yaml" has no directory part: "", the current directory.
  return std::filesystem::path(path).parent_path().string();
}

void applyOverride(YAML::Node& root, const std::string& assignment) {
  const std::size_t equals = assignment.find('=');
  if (equals == std::string::npos || equals == 0) {
    throw ConfigError("--set",
                      "expected key=value (e.g. solver.substeps=20), got '" + assignment + "'");
  }
  const std::string key = assignment.substr(0, equals);
  YAML::Node value;
  try {
    value = YAML::Load(assignment.substr(equals + 1));
  } catch (const YAML::Exception& e) {
    throw ConfigError(key, std::string("cannot parse the value as YAML: ") + e.what());
  }

  const Names parts = splitKey(key);
  if (!root || root.IsNull()) root = YAML::Node(YAML::NodeType::Map);
  // yaml-cpp nodes are references: `node = x` would overwrite the referenced value, reset()
  // rebinds.
  YAML::Node node;
  node.reset(root);
  std::string path;
  for (std::size_t k = 0; k < parts.size(); ++k) {
    const std::string& part = parts[k];
    const bool last = k + 1 == parts.size();
    YAML::Node child;
    std::size_t index = 0;
    if (node.IsSequence()) {
      // Index == size appends, so "grippers.1.name=right" can add a second gripper.
      if (!parseIndex(part, index) || index > node.size()) {
        throw ConfigError(path + "." + part,
                          "'" + path + "' is a list of " + std::to_string(node.size()) +
                              ": use an index in [0, " + std::to_string(node.size()) + "]");
      }
      if (last) {
        node[index] = value;
        return;
      }
      child.reset(node[index]);
    } else if (node.IsMap() || node.IsNull() || !node.IsDefined()) {
      // Missing (undefined) maps are created by the assignment at the end of the path.
      if (last) {
        node[part] = value;
        return;
      }
      child.reset(node[part]);
    } else {
      throw ConfigError(key, "'" + path + "' is a value, not a map or list");
    }
    path += (path.empty() ? "" : ".") + part;
    node.reset(child);
  }
}

}  // namespace pbd_cloth
