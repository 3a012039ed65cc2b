// The scene reader and validate(): every key of INTERFACE.md's example lands in its field, every
// bad value is refused with a message naming its key, unknown keys are refused, --set overrides
// work, and every shipped config/*.yaml loads.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "pbd_cloth/scene/scene_assets.h"
#include "pbd_cloth/scene/scene_yaml.h"
#include "pbd_cloth/sim/cloth_builder.h"
#include "pbd_cloth/sim/metrics.h"
#include "pbd_cloth/sim/simulation.h"

namespace pbd_cloth {
namespace {

// INTERFACE.md's scene YAML, verbatim.
const char kInterfaceExample[] = R"(
frame_id: world            # frame of all published state
step_rate: 120.0           # timer callbacks per second; each advances the simulation by 1/step_rate s
publish_rate: 30.0         # state and markers per second (<= step_rate)
solver:
  method: xpbd             # xpbd | pbd | verlet (the relaxation scheme of the seed) | mass_spring (explicit baseline)
  substeps: 10             # per step
  iterations: 1            # constraint passes per substep
  tolerance: 0.0           # > 0: stop iterating when the largest position change of a pass is below it (m)
  ordering: gauss_seidel   # gauss_seidel | jacobi
  relaxation: 1.0          # Jacobi over-relaxation factor (with averaging by constraint count)
  gravity: [0.0, 0.0, -9.81]
  damping: 0.0             # 1/s, velocity damping
cloth:                     # a rows x cols grid; rows or cols = 1 gives a rope/chain (no triangles)
  rows: 32
  cols: 32
  spacing: 0.03            # rest distance between grid neighbours (m)
  mass: 0.2                # total (kg), spread evenly
  origin: [0.0, 0.0, 1.0]  # position of particle (0,0)
  rpy: [0.0, 0.0, 0.0]     # orientation of the grid; particle (r,c) starts at origin + R*(c*spacing, -r*spacing, 0)
  stretch_compliance: 0.0  # m/N (XPBD); 0 = inextensible
  bend_compliance: 1.0e-3  # bending compliance; bending off when negative
  thickness: 0.005         # particle radius and self-collision thickness h (m)
  self_collision: true     # vertex-triangle self-collision per the seed
  friction: {static: 0.5, kinetic: 0.4}
  pinned: [0, 31]          # particle indices (index = r*cols + c) that never move
  point_masses: []         # [[index, kg], ...]: sets the mass of single particles (heavy ends, weights)
  tethers: false           # long-range attachments to pinned/grasped particles (Kim et al. 2012)
granular:                  # optional: loose particles for particle-particle contact (seed: granular materials)
  count: 0
  radius: 0.01
  mass: 0.001              # each (kg)
  region: {min: [0.0, 0.0, 1.0], max: [0.2, 0.2, 1.2]}   # dropped on a lattice inside this box
grippers:                  # each listens on ~<name>/pose and serves ~<name>/grasp
  - name: left
    radius: 0.02           # grasp radius (m)
    tf_frame: ""           # optional: follow this tf frame instead of ~left/pose
    trajectory:            # optional: scripted motion, used until a pose message arrives (and by cloth_bench)
      - {t: 0.0, pose: [0.0, 0.0, 1.0, 0, 0, 0, 1], grasp: true}    # x y z qx qy qz qw; grasp on/off at t
      - {t: 1.0, pose: [0.3, 0.0, 1.2, 0, 0, 0, 1]}                 # linear/slerp between waypoints, held after the last
bounds: {min: [-10, -10, -10], max: [10, 10, 10]}   # optional: particles are kept inside this box (the seed's C1)
obstacles:                 # sphere | box | capsule | plane; a static pose, or moved by ~<name>/pose
  - {name: ball, shape: sphere, radius: 0.2, pose: [0.5, -0.5, 0.5, 0, 0, 0, 1]}   # x y z qx qy qz qw
  - {name: table, shape: box, size: [1.0, 1.0, 0.05], pose: [0.5, -0.5, 0.0, 0, 0, 0, 1]}
  - {name: floor, shape: plane, normal: [0, 0, 1], offset: -0.5}
  - {name: rod, shape: capsule, radius: 0.01, length: 0.6, pose: [0.5, 0.0, 0.3, 0, 0, 0, 1]}
)";

YAML::Node example() { return YAML::Load(kInterfaceExample); }

// The scene after applying `assignments` to INTERFACE.md's example.
SceneConfig exampleWith(const std::vector<std::string>& assignments) {
  YAML::Node root = example();
  for (const std::string& assignment : assignments) applyOverride(root, assignment);
  return sceneFromYaml(root);
}

// The ConfigError message of parsing `yaml`, or "" when it parses.
std::string errorOf(const std::string& yaml) {
  try {
    sceneFromYaml(YAML::Load(yaml));
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

void expectVector(const Eigen::Vector3d& actual, double x, double y, double z) {
  EXPECT_EQ(actual, Eigen::Vector3d(x, y, z));
}

void expectPose(const Pose& pose, double x, double y, double z) {
  expectVector(pose.position, x, y, z);
  EXPECT_TRUE(pose.orientation.isApprox(Eigen::Quaterniond::Identity()));
}

TEST(SceneYaml, InterfaceExampleFillsEveryField) {
  const SceneConfig s = sceneFromYaml(example());
  EXPECT_EQ(s.frame_id, "world");
  EXPECT_EQ(s.step_rate, 120.0);
  EXPECT_EQ(s.publish_rate, 30.0);

  EXPECT_EQ(s.solver.method, Method::kXpbd);
  EXPECT_EQ(s.solver.substeps, 10);
  EXPECT_EQ(s.solver.iterations, 1);
  EXPECT_EQ(s.solver.tolerance, 0.0);
  EXPECT_EQ(s.solver.ordering, Ordering::kGaussSeidel);
  EXPECT_EQ(s.solver.relaxation, 1.0);
  expectVector(s.solver.gravity, 0.0, 0.0, -9.81);
  EXPECT_EQ(s.solver.damping, 0.0);

  const ClothConfig& c = s.cloth;
  EXPECT_EQ(c.rows, 32);
  EXPECT_EQ(c.cols, 32);
  EXPECT_EQ(c.spacing, 0.03);
  EXPECT_EQ(c.mass, 0.2);
  expectVector(c.origin, 0.0, 0.0, 1.0);
  expectVector(c.rpy, 0.0, 0.0, 0.0);
  EXPECT_EQ(c.stretch_compliance, 0.0);
  EXPECT_EQ(c.bend_compliance, 1.0e-3);
  EXPECT_EQ(c.thickness, 0.005);
  EXPECT_TRUE(c.self_collision);
  EXPECT_EQ(c.friction.static_coefficient, 0.5);
  EXPECT_EQ(c.friction.kinetic_coefficient, 0.4);
  EXPECT_EQ(c.pinned, (std::vector<int>{0, 31}));
  EXPECT_TRUE(c.point_masses.empty());
  EXPECT_FALSE(c.tethers);

  EXPECT_EQ(s.granular.count, 0);
  EXPECT_EQ(s.granular.radius, 0.01);
  EXPECT_EQ(s.granular.mass, 0.001);
  expectVector(s.granular.region_min, 0.0, 0.0, 1.0);
  expectVector(s.granular.region_max, 0.2, 0.2, 1.2);

  ASSERT_EQ(s.grippers.size(), 1u);
  const GripperConfig& g = s.grippers[0];
  EXPECT_EQ(g.name, "left");
  EXPECT_EQ(g.radius, 0.02);
  EXPECT_EQ(g.tf_frame, "");
  ASSERT_EQ(g.trajectory.size(), 2u);
  EXPECT_EQ(g.trajectory[0].t, 0.0);
  expectPose(g.trajectory[0].pose, 0.0, 0.0, 1.0);
  EXPECT_EQ(g.trajectory[0].grasp, 1);
  EXPECT_EQ(g.trajectory[1].t, 1.0);
  expectPose(g.trajectory[1].pose, 0.3, 0.0, 1.2);
  EXPECT_EQ(g.trajectory[1].grasp, -1);  // absent: no change

  EXPECT_TRUE(s.bounds.enabled);
  expectVector(s.bounds.min, -10, -10, -10);
  expectVector(s.bounds.max, 10, 10, 10);

  ASSERT_EQ(s.obstacles.size(), 4u);
  EXPECT_EQ(s.obstacles[0].name, "ball");
  EXPECT_EQ(s.obstacles[0].shape, ShapeType::kSphere);
  EXPECT_EQ(s.obstacles[0].radius, 0.2);
  expectPose(s.obstacles[0].pose, 0.5, -0.5, 0.5);
  EXPECT_EQ(s.obstacles[1].name, "table");
  EXPECT_EQ(s.obstacles[1].shape, ShapeType::kBox);
  expectVector(s.obstacles[1].size, 1.0, 1.0, 0.05);
  expectPose(s.obstacles[1].pose, 0.5, -0.5, 0.0);
  EXPECT_EQ(s.obstacles[2].name, "floor");
  EXPECT_EQ(s.obstacles[2].shape, ShapeType::kPlane);
  expectVector(s.obstacles[2].normal, 0, 0, 1);
  EXPECT_EQ(s.obstacles[2].offset, -0.5);
  EXPECT_EQ(s.obstacles[3].name, "rod");
  EXPECT_EQ(s.obstacles[3].shape, ShapeType::kCapsule);
  EXPECT_EQ(s.obstacles[3].radius, 0.01);
  EXPECT_EQ(s.obstacles[3].length, 0.6);
  expectPose(s.obstacles[3].pose, 0.5, 0.0, 0.3);
}

// Every value differs from its default, so a key that is not read fails the test.
TEST(SceneYaml, ExtensionKeysAndNonDefaults) {
  const SceneConfig s = sceneFromYaml(YAML::Load(R"(
frame_id: map
step_rate: 200
publish_rate: 50
solver: {method: pbd, substeps: 3, iterations: 7, tolerance: 1e-6, ordering: jacobi,
         relaxation: 1.5, jacobi_averaging: false, gravity: [1, 2, 3], damping: 0.25,
         stretch_stiffness: 0.9, bend_stiffness: 0.3, spring_stiffness: 500,
         spring_damping: 2, bend_spring_stiffness: 0.5}
cloth: {rows: 4, cols: 5, spacing: 0.1, mass: 2, origin: [1, 2, 3], rpy: [0.1, 0.2, 0.3],
        stretch_compliance: 1e-4, bend_compliance: -1, thickness: 0.02, self_collision: false,
        friction: {static: 0.8, kinetic: 0.8}, pinned: [0, 4, 19], point_masses: [[19, 1.5], [3, 0.25]],
        tethers: true, shear: false, shear_diagonals: 2}
granular: {count: 12, radius: 0.02, mass: 0.005, region: {min: [0, 0, 0], max: [0, 1, 2]}}
)"));
  EXPECT_EQ(s.frame_id, "map");
  EXPECT_EQ(s.step_rate, 200.0);
  EXPECT_EQ(s.publish_rate, 50.0);
  EXPECT_EQ(s.solver.method, Method::kPbd);
  EXPECT_EQ(s.solver.substeps, 3);
  EXPECT_EQ(s.solver.iterations, 7);
  EXPECT_EQ(s.solver.tolerance, 1e-6);
  EXPECT_EQ(s.solver.ordering, Ordering::kJacobi);
  EXPECT_EQ(s.solver.relaxation, 1.5);
  EXPECT_FALSE(s.solver.jacobi_averaging);
  expectVector(s.solver.gravity, 1, 2, 3);
  EXPECT_EQ(s.solver.damping, 0.25);
  EXPECT_EQ(s.solver.stretch_stiffness, 0.9);
  EXPECT_EQ(s.solver.bend_stiffness, 0.3);
  EXPECT_EQ(s.solver.spring_stiffness, 500.0);
  EXPECT_EQ(s.solver.spring_damping, 2.0);
  EXPECT_EQ(s.solver.bend_spring_stiffness, 0.5);
  EXPECT_EQ(s.cloth.rows, 4);
  EXPECT_EQ(s.cloth.cols, 5);
  EXPECT_EQ(s.cloth.spacing, 0.1);
  EXPECT_EQ(s.cloth.mass, 2.0);
  expectVector(s.cloth.origin, 1, 2, 3);
  expectVector(s.cloth.rpy, 0.1, 0.2, 0.3);
  EXPECT_EQ(s.cloth.stretch_compliance, 1e-4);
  EXPECT_EQ(s.cloth.bend_compliance, -1.0);
  EXPECT_EQ(s.cloth.thickness, 0.02);
  EXPECT_FALSE(s.cloth.self_collision);
  EXPECT_EQ(s.cloth.friction.static_coefficient, 0.8);
  EXPECT_EQ(s.cloth.friction.kinetic_coefficient, 0.8);
  EXPECT_EQ(s.cloth.pinned, (std::vector<int>{0, 4, 19}));
  ASSERT_EQ(s.cloth.point_masses.size(), 2u);
  EXPECT_EQ(s.cloth.point_masses[0], std::make_pair(19, 1.5));
  EXPECT_EQ(s.cloth.point_masses[1], std::make_pair(3, 0.25));
  EXPECT_TRUE(s.cloth.tethers);
  EXPECT_FALSE(s.cloth.shear);
  EXPECT_EQ(s.cloth.shear_diagonals, 2);
  EXPECT_EQ(s.granular.count, 12);
  EXPECT_EQ(s.granular.radius, 0.02);
  EXPECT_EQ(s.granular.mass, 0.005);
  expectVector(s.granular.region_min, 0, 0, 0);
  expectVector(s.granular.region_max, 0, 1, 2);
  EXPECT_FALSE(s.bounds.enabled);  // no bounds key
}

TEST(SceneYaml, EmptyDocumentGivesTheDefaults) {
  const SceneConfig s = sceneFromYaml(YAML::Load(""));
  const SceneConfig d;
  EXPECT_EQ(s.frame_id, d.frame_id);
  EXPECT_EQ(s.step_rate, d.step_rate);
  EXPECT_EQ(s.solver.substeps, d.solver.substeps);
  EXPECT_EQ(s.cloth.rows, d.cloth.rows);
  EXPECT_EQ(s.cloth.spacing, d.cloth.spacing);
  EXPECT_FALSE(s.bounds.enabled);
  EXPECT_TRUE(s.grippers.empty());
  EXPECT_TRUE(s.obstacles.empty());
}

TEST(SceneYaml, MethodAndOrderingWords) {
  for (Method m : {Method::kXpbd, Method::kPbd, Method::kVerlet, Method::kMassSpring}) {
    EXPECT_EQ(exampleWith({std::string("solver.method=") + toString(m)}).solver.method, m);
  }
  EXPECT_STREQ(toString(Method::kMassSpring), "mass_spring");
  EXPECT_STREQ(toString(Method::kVerlet), "verlet");
  EXPECT_EQ(exampleWith({"solver.ordering=jacobi"}).solver.ordering, Ordering::kJacobi);
  EXPECT_EQ(exampleWith({"solver.ordering=gauss_seidel"}).solver.ordering, Ordering::kGaussSeidel);
  EXPECT_STREQ(toString(Ordering::kGaussSeidel), "gauss_seidel");
  EXPECT_STREQ(toString(ShapeType::kCapsule), "capsule");
  // Words are exact: no case folding, so a message lists what is accepted.
  try {
    exampleWith({"solver.method=XPBD"});
    FAIL() << "XPBD accepted";
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.key(), "solver.method");
    EXPECT_NE(std::string(e.what()).find("xpbd, pbd, verlet, mass_spring"), std::string::npos)
        << e.what();
  }
  try {
    exampleWith({"solver.ordering=red_black"});
    FAIL() << "red_black accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("gauss_seidel, jacobi"), std::string::npos) << e.what();
  }
}

TEST(SceneYaml, QuaternionsAreNormalized) {
  const SceneConfig s = exampleWith(
      {"obstacles.0.pose=[1, 2, 3, 0, 0, 2, 0]", "obstacles.1.pose=[0, 0, 0, 1, 1, 1, 1]"});
  const Eigen::Quaterniond& q0 = s.obstacles[0].pose.orientation;
  EXPECT_NEAR(q0.norm(), 1.0, 1e-15);
  EXPECT_NEAR(q0.z(), 1.0, 1e-15);  // the 6th number is qz, not w
  EXPECT_NEAR(q0.w(), 0.0, 1e-15);
  expectVector(s.obstacles[0].pose.position, 1, 2, 3);
  const Eigen::Quaterniond& q1 = s.obstacles[1].pose.orientation;
  EXPECT_NEAR(q1.x(), 0.5, 1e-15);
  EXPECT_NEAR(q1.w(), 0.5, 1e-15);
  // A hand-written 90 degree turn about z.
  const SceneConfig t =
      exampleWith({"grippers.0.trajectory.1.pose=[0, 0, 1, 0, 0, 0.7071, 0.7071]"});
  const Eigen::Quaterniond& q2 = t.grippers[0].trajectory[1].pose.orientation;
  EXPECT_NEAR(q2.norm(), 1.0, 1e-15);
  EXPECT_TRUE((q2 * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitY(), 1e-12));
}

TEST(SceneYaml, IntegersWrittenAsRealsAreAccepted) {
  const SceneConfig s = exampleWith({"solver.substeps=20.0", "cloth.pinned=[0.0, 31]"});
  EXPECT_EQ(s.solver.substeps, 20);
  EXPECT_EQ(s.cloth.pinned, (std::vector<int>{0, 31}));
  EXPECT_THROW(exampleWith({"solver.substeps=2.5"}), ConfigError);
  EXPECT_THROW(exampleWith({"solver.substeps=1e20"}), ConfigError);
}

TEST(SceneYaml, WaypointGraspIsTriState) {
  const SceneConfig s = exampleWith({"grippers.0.trajectory.1.grasp=false"});
  EXPECT_EQ(s.grippers[0].trajectory[0].grasp, 1);
  EXPECT_EQ(s.grippers[0].trajectory[1].grasp, 0);
}

TEST(SceneYaml, BoundsArePresentOrNot) {
  YAML::Node root = example();
  root.remove("bounds");
  EXPECT_FALSE(sceneFromYaml(root).bounds.enabled);
  applyOverride(root, "bounds={}");
  EXPECT_TRUE(sceneFromYaml(root).bounds.enabled);
}

// The ROS node builds the tree from XmlRpc values with YAML::Node(int/double/bool/string); numbers
// must come back exactly (1/49 has no short decimal form).
TEST(SceneYaml, ProgrammaticTreeRoundTrips) {
  YAML::Node root(YAML::NodeType::Map);
  root["step_rate"] = 60.0;
  root["solver"]["substeps"] = 4;
  root["cloth"]["spacing"] = 1.0 / 49.0;
  root["cloth"]["self_collision"] = false;
  YAML::Node pinned(YAML::NodeType::Sequence);
  pinned.push_back(0);
  pinned.push_back(31);
  root["cloth"]["pinned"] = pinned;
  root["cloth"]["point_masses"] = YAML::Node(YAML::NodeType::Sequence);
  const SceneConfig s = sceneFromYaml(root);
  EXPECT_EQ(s.step_rate, 60.0);
  EXPECT_EQ(s.solver.substeps, 4);
  EXPECT_EQ(s.cloth.spacing, 1.0 / 49.0);
  EXPECT_FALSE(s.cloth.self_collision);
  EXPECT_EQ(s.cloth.pinned, (std::vector<int>{0, 31}));
}

// --- Bad values: one case per key, each must be refused naming the key ---------------------------

struct BadValue {
  const char* assignment;  // applied to INTERFACE.md's example
  const char* key;         // must appear in what()
  const char* fragment;    // must appear in what() too: the allowed range or the reason
};

void PrintTo(const BadValue& bad, std::ostream* os) { *os << bad.assignment; }

class SceneYamlBadValue : public ::testing::TestWithParam<BadValue> {};

TEST_P(SceneYamlBadValue, IsRefusedNamingTheKey) {
  const BadValue& bad = GetParam();
  try {
    exampleWith({bad.assignment});
    FAIL() << bad.assignment << " was accepted";
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind(bad.key, 0), 0u) << what;  // the message starts with the key
    EXPECT_NE(what.find(bad.fragment), std::string::npos) << what;
  }
}

INSTANTIATE_TEST_SUITE_P(
    EveryKey, SceneYamlBadValue,
    ::testing::Values(
        BadValue{"frame_id=''", "frame_id", "non-empty"},
        BadValue{"frame_id=/world", "frame_id", "leading '/'"},
        BadValue{"step_rate=0", "step_rate", "(0, 10000]"},
        BadValue{"step_rate=20000", "step_rate", "(0, 10000]"},
        BadValue{"step_rate=.nan", "step_rate", "(0, 10000]"},
        BadValue{"publish_rate=200", "publish_rate", "(0, 120]"},
        BadValue{"solver.substeps=0", "solver.substeps", "must be an integer in [1, 1000], got 0"},
        BadValue{"solver.substeps=ten", "solver.substeps", "must be an integer, got 'ten'"},
        BadValue{"solver.substeps=[1]", "solver.substeps", "must be an integer"},
        BadValue{"solver.iterations=1001", "solver.iterations", "[1, 1000]"},
        BadValue{"solver.tolerance=-1", "solver.tolerance", ">= 0"},
        BadValue{"solver.relaxation=2", "solver.relaxation", "(0, 2)"},
        BadValue{"solver.relaxation=0", "solver.relaxation", "(0, 2)"},
        BadValue{"solver.gravity=[0, 0, .inf]", "solver.gravity", "finite"},
        BadValue{"solver.gravity=[0, 0]", "solver.gravity", "3 numbers"},
        BadValue{"solver.damping=-0.1", "solver.damping", ">= 0"},
        BadValue{"solver.damping=.nan", "solver.damping", ">= 0"},
        BadValue{"solver.stretch_stiffness=1.5", "solver.stretch_stiffness", "[0, 1]"},
        BadValue{"solver.bend_stiffness=-0.5", "solver.bend_stiffness", "[0, 1]"},
        BadValue{"solver.spring_stiffness=0", "solver.spring_stiffness", "> 0"},
        BadValue{"solver.spring_damping=-1", "solver.spring_damping", ">= 0"},
        BadValue{"solver.jacobi_averaging=maybe", "solver.jacobi_averaging", "true or false"},
        BadValue{"cloth.rows=0", "cloth.rows", "[1, 1000000]"},
        BadValue{"cloth.cols=-3", "cloth.cols", "[1, 1000000]"},
        BadValue{"cloth.rows=40000", "cloth.rows", "rows * cols must be in [2, 1000000]"},
        BadValue{"cloth.spacing=-0.1", "cloth.spacing", "> 0"},
        BadValue{"cloth.mass=0", "cloth.mass", "> 0"},
        BadValue{"cloth.origin=[0, .nan, 1]", "cloth.origin", "finite"},
        BadValue{"cloth.rpy=1.57", "cloth.rpy", "3 numbers"},
        BadValue{"cloth.stretch_compliance=-1e-6", "cloth.stretch_compliance", ">= 0"},
        BadValue{"cloth.bend_compliance=.inf", "cloth.bend_compliance", "finite"},
        BadValue{"cloth.thickness=0", "cloth.thickness", "> 0"},
        BadValue{"cloth.thickness=0.5", "cloth.thickness", "below cloth.spacing"},
        BadValue{"cloth.self_collision=2", "cloth.self_collision", "true or false"},
        BadValue{"cloth.friction.static=-1", "cloth.friction.static", ">= 0"},
        BadValue{"cloth.friction.kinetic=0.6", "cloth.friction.kinetic", "[0, 0.5]"},
        BadValue{"cloth.friction=0.5", "cloth.friction", "a map"},
        BadValue{"cloth.pinned=[0, 5, 1024]", "cloth.pinned[2]",
                 "index 1024 out of range [0, 1023]"},
        BadValue{"cloth.pinned=[-1]", "cloth.pinned[0]", "out of range"},
        BadValue{"cloth.pinned=5", "cloth.pinned", "a list"},
        BadValue{"cloth.point_masses=[[0, 1], [2000, 1.0]]", "cloth.point_masses[1]",
                 "out of range"},
        BadValue{"cloth.point_masses=[[3, 0]]", "cloth.point_masses[0]", "> 0"},
        BadValue{"cloth.point_masses=[[3]]", "cloth.point_masses[0]", "[index, kg]"},
        BadValue{"cloth.shear_diagonals=3", "cloth.shear_diagonals", "[1, 2]"},
        BadValue{"solver.levels=17", "solver.levels", "[0, 16]"},
        BadValue{"solver.levels=-1", "solver.levels", "[0, 16]"},
        BadValue{"solver.search_window=-1", "solver.search_window", "[0, 1000]"},
        BadValue{"solver.search_window=1.5", "solver.search_window", "integer"},
        BadValue{"cloth.shear_diagonals=0", "cloth.shear_diagonals", "[1, 2]"},
        BadValue{"granular.count=-1", "granular.count", "[0, 1000000]"},
        BadValue{"granular.radius=0", "granular.radius", "> 0"},
        BadValue{"granular.mass=-1", "granular.mass", "> 0"},
        BadValue{"granular.region.min=[1, 0, 0]", "granular.region", "min must be <= max"},
        BadValue{"grippers.0.name=''", "grippers[0].name", "starting with a letter"},
        BadValue{"grippers.0.name=left hand", "grippers[0].name", "starting with a letter"},
        BadValue{"grippers.1={name: left}", "grippers[1].name", "used twice"},
        BadValue{"grippers.0.radius=0", "grippers[0].radius", "> 0"},
        BadValue{"grippers.0.tf_frame=/tool0", "grippers[0].tf_frame", "leading '/'"},
        BadValue{"grippers.0.trajectory.0.t=-1", "grippers[0].trajectory[0].t", ">= 0"},
        BadValue{"grippers.0.trajectory.1.t=-0.5", "grippers[0].trajectory[1].t",
                 "previous waypoint"},
        BadValue{"grippers.0.trajectory.0.pose=[0, 0, 1, 0, 0, 0, 0]",
                 "grippers[0].trajectory[0].pose", "non-zero"},
        BadValue{"grippers.0.trajectory.0.pose=[0, 0, 1]", "grippers[0].trajectory[0].pose",
                 "7 numbers"},
        BadValue{"grippers.0.trajectory.1={t: 2}", "grippers[0].trajectory[1].pose", "required"},
        BadValue{"grippers.0.trajectory.1.grasp=1.5", "grippers[0].trajectory[1].grasp",
                 "true or false"},
        // INTERFACE.md's gripper goes up and does not come back: it cannot repeat.
        BadValue{"grippers.0.repeat=true", "grippers[0].repeat", "must be the first's"},
        BadValue{"grippers.0.repeat=2", "grippers[0].repeat", "true or false"},
        BadValue{"obstacles.0.radius=0", "obstacles[0].radius", "> 0"},
        BadValue{"obstacles.0.shape=cone", "obstacles[0].shape",
                 "sphere, box, capsule, cylinder, plane, mesh"},
        BadValue{"obstacles.0.pose=[0, 0, .nan, 0, 0, 0, 1]", "obstacles[0].pose", "finite"},
        BadValue{"obstacles.1.name=ball", "obstacles[1].name", "used twice"},
        BadValue{"obstacles.1.name=left", "obstacles[1].name", "used twice"},  // a gripper's
        BadValue{"obstacles.1.size=[1, 0, 1]", "obstacles[1].size", "> 0"},
        BadValue{"obstacles.1.radius=0.3", "obstacles[1].radius", "not used by a box"},
        BadValue{"obstacles.2.normal=[0, 0, 0]", "obstacles[2].normal", "non-zero"},
        BadValue{"obstacles.2.offset=.inf", "obstacles[2].offset", "finite"},
        BadValue{"obstacles.3.length=-1", "obstacles[3].length", ">= 0"},
        BadValue{"obstacles.3.radius=-1", "obstacles[3].radius", "> 0"},
        BadValue{"bounds.min=[0, 0, 20]", "bounds", "min must be < max"},
        BadValue{"bounds=[1, 2]", "bounds", "a map"}));

// cloth.rows=1 alone is a valid rope; rows * cols = 1 is not.
TEST(SceneYaml, SingleParticleIsRefused) {
  EXPECT_NO_THROW(exampleWith({"cloth.rows=1", "cloth.pinned=[0]"}));
  EXPECT_THROW(exampleWith({"cloth.rows=1", "cloth.cols=1", "cloth.pinned=[0]"}), ConfigError);
}

TEST(SceneValidate, MessagesNameKeyAndRange) {
  SceneConfig scene;
  scene.cloth.rows = scene.cloth.cols = 50;
  scene.cloth.pinned = {0, 49, 5000};
  try {
    validate(scene);
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(), "cloth.pinned[2]: index 5000 out of range [0, 2499]");
    EXPECT_EQ(e.key(), "cloth.pinned[2]");
  }
  scene = SceneConfig();
  scene.solver.substeps = 0;
  try {
    validate(scene);
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(), "solver.substeps: must be an integer in [1, 1000], got 0");
  }
  EXPECT_NO_THROW(validate(SceneConfig()));
}

// --- Unknown and repeated keys -------------------------------------------------------------------

TEST(SceneYaml, UnknownKeysAreRefusedByName) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"colth: {rows: 3}", "colth"},
      {"solver: {substep: 3}", "solver.substep"},
      {"cloth: {friction: {statc: 0.1}}", "cloth.friction.statc"},
      {"granular: {region: {mn: [0, 0, 0]}}", "granular.region.mn"},
      {"grippers: [{name: a, radus: 0.1}]", "grippers[0].radus"},
      {"grippers: [{name: a, trajectory: [{t: 0, pose: [0,0,0,0,0,0,1], grab: true}]}]",
       "grippers[0].trajectory[0].grab"},
      {"obstacles: [{name: a, shape: sphere, colour: red}]", "obstacles[0].colour"},
      {"bounds: {min: [0,0,0], max: [1,1,1], margin: 0.1}", "bounds.margin"},
  };
  for (const auto& c : cases) {
    const std::string what = errorOf(c.first);
    EXPECT_EQ(what.rfind(c.second + ": unknown key", 0), 0u) << c.first << " -> " << what;
  }
}

// Keys that left the scene: one that is still there fails the load with a message naming it and
// what took its place (measured options removed; comparison switches moved to cloth_bench).
TEST(SceneYaml, RemovedKeysNameWhatReplacedThem) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"solver: {chebyshev: 0.9}",
       "solver.chebyshev: was removed (Chebyshev acceleration measured no cheaper than more "
       "substeps): raise solver.substeps instead"},
      {"solver: {levels: 3, levels_interpolate: false}",
       "solver.levels_interpolate: was removed (HPBD's interpolation between the levels measured "
       "unstable): solver.levels alone remains"},
      {"solver: {simd: true}",
       "solver.simd: moved to cloth_bench --no-simd (a switch for comparing code paths, not a "
       "scene key)"},
      {"solver: {avx512: false}",
       "solver.avx512: moved to cloth_bench --no-avx512 (a switch for comparing code paths, not a "
       "scene key)"},
      {"solver: {substeps: 20, taut_chains: true}",
       "solver.taut_chains: was removed (a special case of one geometry: it held a grid row "
       "straight only while its two held ends were exactly its rest length apart, so one "
       "micrometre of slack turned it off, and where it acted it turned a suspension from two "
       "corners into one from an edge): raise solver.substeps, or turn cloth.tethers on for a "
       "hanging cloth"},
      {"solver: {taut_chains: false}",
       "solver.taut_chains: was removed (a special case of one geometry: it held a grid row "
       "straight only while its two held ends were exactly its rest length apart, so one "
       "micrometre of slack turned it off, and where it acted it turned a suspension from two "
       "corners into one from an edge): raise solver.substeps, or turn cloth.tethers on for a "
       "hanging cloth"},
  };
  for (const auto& c : cases) EXPECT_EQ(errorOf(c.first), c.second) << c.first;
}

TEST(SceneYaml, TopLevelAllowListIsIgnored) {
  EXPECT_EQ(errorOf("description: a scene for the test\nstep_rate: 100"), "");
}

TEST(SceneYaml, RepeatedKeysAreRefused) {
  const std::string what = errorOf("solver: {substeps: 2, substeps: 3}");
  EXPECT_EQ(what.rfind("solver.substeps: given twice", 0), 0u) << what;
}

TEST(SceneYaml, ObstacleShapeIsRequired) {
  const std::string what = errorOf("obstacles: [{name: a, radius: 0.1}]");
  EXPECT_EQ(what.rfind("obstacles[0].shape: required", 0), 0u) << what;
}

// fuzz_scene_yaml's find: a grid whose rows left the bounds along y was squeezed onto the box's
// face in the first step, into a line of degenerate triangles whose self-collision search took
// 1.8 s a step. Refused at load, naming the corner; a cloth laid exactly on a face still loads.
TEST(SceneYaml, ClothOutsideTheBoundsIsRefused) {
  const std::string bounds = "\nbounds: {min: [-1, 0, 0], max: [1, 1, 2]}";
  const std::string what =
      errorOf("cloth: {rows: 4, cols: 4, spacing: 0.1, origin: [0, 0, 1]}" + bounds);
  EXPECT_EQ(what.rfind("bounds: the cloth must start inside the bounds: its corner particle "
                       "(row 3, col 0) is at [0, -0.3, 1]",
                       0),
            0u)
      << what;
  EXPECT_EQ(errorOf("cloth: {rows: 4, cols: 4, spacing: 0.1, origin: [0, 0.5, 1]}" + bounds), "");
  // Row 3 at y = 0.3 - 3 x 0.1, -5.6e-17 in doubles: on the face, within the slack.
  EXPECT_EQ(errorOf("cloth: {rows: 4, cols: 4, spacing: 0.1, origin: [0, 0.3, 1]}" + bounds), "");
  // Tilted out of the top of the box.
  EXPECT_NE(errorOf("cloth: {rows: 4, cols: 4, spacing: 0.1, origin: [0, 0.5, 1.9], rpy: [-1.5, "
                    "0, 0]}" +
                    bounds)
                .find("outside min"),
            std::string::npos);
}

TEST(SceneYaml, NullSectionsReadAsAbsent) {
  const SceneConfig s = sceneFromYaml(YAML::Load("solver:\ncloth:\n  pinned:\nbounds:\n"));
  EXPECT_EQ(s.solver.substeps, SolverConfig().substeps);
  EXPECT_TRUE(s.cloth.pinned.empty());
  EXPECT_FALSE(s.bounds.enabled);
}

// --- applyOverride -------------------------------------------------------------------------------

TEST(ApplyOverride, NestedKeysSequencesAndNewKeys) {
  YAML::Node root = example();
  applyOverride(root, "solver.substeps=20");
  applyOverride(root, "grippers.0.radius=0.03");
  applyOverride(root, "grippers.0.trajectory.1.pose=[1, 2, 3, 0, 0, 0, 1]");
  applyOverride(root, "cloth.pinned=[1, 2, 3]");
  applyOverride(root, "cloth.friction.kinetic=0.1");
  applyOverride(root, "frame_id=odom=1");  // the value may hold '='
  const SceneConfig s = sceneFromYaml(root);
  EXPECT_EQ(s.solver.substeps, 20);
  EXPECT_EQ(s.grippers[0].radius, 0.03);
  expectVector(s.grippers[0].trajectory[1].pose.position, 1, 2, 3);
  EXPECT_EQ(s.cloth.pinned, (std::vector<int>{1, 2, 3}));
  EXPECT_EQ(s.cloth.friction.kinetic_coefficient, 0.1);
  EXPECT_EQ(s.cloth.friction.static_coefficient, 0.5);  // its sibling is untouched
  EXPECT_EQ(s.frame_id, "odom=1");
  EXPECT_EQ(s.solver.iterations, 1);
}

TEST(ApplyOverride, CreatesMissingKeys) {
  YAML::Node root = YAML::Load("step_rate: 100");
  applyOverride(root, "granular.region.max=[1, 1, 2]");
  applyOverride(root, "bounds.min=[-1, -1, -1]");
  applyOverride(root, "grippers=[]");
  applyOverride(root, "grippers.0.name=right");  // index == size appends
  applyOverride(root, "grippers.0.radius=0.05");
  const SceneConfig s = sceneFromYaml(root);
  expectVector(s.granular.region_max, 1, 1, 2);
  EXPECT_TRUE(s.bounds.enabled);
  expectVector(s.bounds.min, -1, -1, -1);
  ASSERT_EQ(s.grippers.size(), 1u);
  EXPECT_EQ(s.grippers[0].name, "right");
  EXPECT_EQ(s.grippers[0].radius, 0.05);
  EXPECT_EQ(s.step_rate, 100.0);

  YAML::Node empty;
  applyOverride(empty, "solver.method=verlet");
  EXPECT_EQ(sceneFromYaml(empty).solver.method, Method::kVerlet);
}

TEST(ApplyOverride, MalformedAssignmentsThrow) {
  YAML::Node root = example();
  EXPECT_THROW(applyOverride(root, "solver.substeps"), ConfigError);         // no '='
  EXPECT_THROW(applyOverride(root, "=3"), ConfigError);                      // no key
  EXPECT_THROW(applyOverride(root, "solver..substeps=3"), ConfigError);      // empty part
  EXPECT_THROW(applyOverride(root, "grippers.5.radius=1"), ConfigError);     // past the end
  EXPECT_THROW(applyOverride(root, "grippers.left.radius=1"), ConfigError);  // not an index
  EXPECT_THROW(applyOverride(root, "frame_id.x=1"), ConfigError);            // through a scalar
  EXPECT_THROW(applyOverride(root, "cloth.pinned=[0, 1"), ConfigError);      // bad YAML
  // The misspelt key is created, then refused by the reader with its name.
  applyOverride(root, "solver.substepz=3");
  try {
    sceneFromYaml(root);
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.key(), "solver.substepz");
  }
}

// --- Files ---------------------------------------------------------------------------------------

TEST(LoadScene, FileErrorsNameTheFile) {
  try {
    loadScene("/nonexistent/scene.yaml");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.key(), "file");
    EXPECT_NE(std::string(e.what()).find("/nonexistent/scene.yaml"), std::string::npos);
  }
  const std::string path = ::testing::TempDir() + "pbd_cloth_bad_scene.yaml";
  std::ofstream(path) << "solver: {substeps: [1, 2}\n";
  try {
    loadScene(path);
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.key(), "file");
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
  std::remove(path.c_str());
}

// config/*.yaml and the benchmark variants in config/bench/*.yaml.
std::vector<std::string> shippedConfigs() {
  std::vector<std::string> paths;
  for (const char* folder :
       {PBD_CLOTH_SOURCE_DIR "/config", PBD_CLOTH_SOURCE_DIR "/config/bench"}) {
    for (const auto& entry : std::filesystem::directory_iterator(folder)) {
      if (entry.path().extension() == ".yaml") paths.push_back(entry.path().string());
    }
  }
  std::sort(paths.begin(), paths.end());
  return paths;
}

TEST(ShippedConfigs, EveryConfigLoadsAndSteps) {
  const std::vector<std::string> paths = shippedConfigs();
  EXPECT_GE(paths.size(), 3u);
  for (const std::string& path : paths) {
    SCOPED_TRACE(path);
    SceneConfig scene;
    ASSERT_NO_THROW(scene = loadScene(path));
    if (scene.robot.enabled && scene.robot.urdf_file.empty()) {
      // The node reads robot_description; the shipped robot scenes are for the demo arm.
      scene.robot.urdf_file = PBD_CLOTH_SOURCE_DIR "/urdf/demo_arm.urdf";
      ASSERT_NO_THROW(loadRobotFile(scene));
    }
    Simulation sim(scene);
    for (int k = 0; k < 5; ++k) sim.step();
    EXPECT_TRUE(allFinite(sim.particles()));
  }
}

// The default scene hangs in the x-z plane from its two top corners, rows going down.
TEST(ShippedConfigs, HangingSceneGeometry) {
  const SceneConfig scene = loadScene(PBD_CLOTH_SOURCE_DIR "/config/hanging.yaml");
  EXPECT_EQ(scene.cloth.rows, 50);
  EXPECT_EQ(scene.cloth.cols, 50);
  EXPECT_EQ(scene.cloth.pinned, (std::vector<int>{0, 49}));
  EXPECT_EQ(scene.solver.method, Method::kXpbd);
  Particles particles;
  ClothTopology topology;
  buildScene(scene, particles, topology);
  const auto at = [&](int r, int c) { return particles.position[r * 50 + c]; };
  EXPECT_TRUE(at(0, 0).isApprox(Eigen::Vector3d(0, 0, 1.5), 1e-12));
  EXPECT_TRUE(at(0, 49).isApprox(Eigen::Vector3d(1, 0, 1.5), 1e-12));
  EXPECT_TRUE(at(49, 0).isApprox(Eigen::Vector3d(0, 0, 0.5), 1e-12));
  EXPECT_TRUE(at(49, 49).isApprox(Eigen::Vector3d(1, 0, 0.5), 1e-12));
}

// The drape ball stands on the table and the cloth starts centred above it.
TEST(ShippedConfigs, DrapeSceneBallRestsOnTable) {
  const SceneConfig scene = loadScene(PBD_CLOTH_SOURCE_DIR "/config/drape.yaml");
  const ObstacleConfig* ball = nullptr;
  const ObstacleConfig* table = nullptr;
  for (const ObstacleConfig& o : scene.obstacles) {
    if (o.shape == ShapeType::kSphere) ball = &o;
    if (o.shape == ShapeType::kBox) table = &o;
  }
  ASSERT_TRUE(ball && table);
  const double table_top = table->pose.position.z() + 0.5 * table->size.z();
  EXPECT_NEAR(ball->pose.position.z() - ball->radius, table_top, 1e-12);
  const double half = 0.5 * (scene.cloth.cols - 1) * scene.cloth.spacing;
  const Eigen::Vector3d centre = scene.cloth.origin + Eigen::Vector3d(half, -half, 0.0);
  EXPECT_NEAR(centre.x(), ball->pose.position.x(), 1e-12);
  EXPECT_NEAR(centre.y(), ball->pose.position.y(), 1e-12);
  EXPECT_GT(centre.z(), ball->pose.position.z() + ball->radius);
}

}  // namespace
}  // namespace pbd_cloth
