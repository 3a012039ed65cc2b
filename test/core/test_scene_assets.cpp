// The scene reader's new keys (cylinder and mesh obstacles, tf_frame, the robot section) and the
// files they name: meshes in every format through assimp, URDFs through urdf/urdfdom, paths
// relative to the scene file, file:// and package:// URIs, and every bad input refused with a
// message naming the key, the file or the link. Test data: test/data/ (written by hand, described
// in each file).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <string>
#include <vector>

#include "pbd_cloth/scene/scene_assets.h"
#include "pbd_cloth/scene/scene_yaml.h"

namespace pbd_cloth {
namespace {

const std::string kDataDirectory = std::string(PBD_CLOTH_SOURCE_DIR) + "/test/data";

std::string dataPath(const std::string& name) { return kDataDirectory + "/" + name; }

// The ConfigError message of reading `yaml` with test/data as the base directory, or "".
std::string errorOf(const std::string& yaml) {
  try {
    sceneFromYaml(YAML::Load(yaml), kDataDirectory);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

// The ConfigError message of loadRobot on `urdf`, or "".
std::string robotErrorOf(const std::string& urdf, const std::string& source = "test urdf") {
  SceneConfig scene;
  try {
    loadRobot(scene, urdf, source);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

// A one-link URDF whose collision geometry is `geometry`.
std::string oneLinkUrdf(const std::string& geometry) {
  return "<robot name='one'><link name='arm'><collision><geometry>" + geometry +
         "</geometry></collision></link></robot>";
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

void expectBounds(const TriangleMesh& mesh, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                  const std::string& what) {
  // The files hold these numbers exactly; float storage in assimp rounds to ~1e-7 relative.
  EXPECT_NEAR((mesh.boundsMin() - lo).norm(), 0.0, 1e-6) << what;
  EXPECT_NEAR((mesh.boundsMax() - hi).norm(), 0.0, 1e-6) << what;
}

// --- Mesh files
// -----------------------------------------------------------------------------------

TEST(SceneAssets, EveryMeshFormatLoadsWithItsBoundsTimesTheScale) {
  struct Case {
    std::string file;
    Eigen::Vector3d hi;  // lo is the origin in every file
    int triangles;
    int vertices;
  };
  const Case cases[] = {
      {"box_1x2x3.stl", {1, 2, 3}, 12, 8},
      {"tetra.obj", {2, 3, 4}, 4, 4},
      {"tetra.ply", {2, 3, 4}, 4, 4},
      // Corners (0,0,0) (2,0,0) (0,3,0) (0,0,4) in units of 0.5 m, Z up (not rotated to Y up).
      {"tetra_half_unit.dae", {1, 1.5, 2}, 4, 4},
  };
  const Eigen::Vector3d scale(0.5, 2.0, 3.0);
  for (const Case& c : cases) {
    std::vector<std::string> warnings;
    const auto mesh = loadMesh(dataPath(c.file), scale, "test", warnings);
    ASSERT_TRUE(mesh) << c.file;
    EXPECT_EQ(mesh->triangleCount(), c.triangles) << c.file;
    EXPECT_EQ(mesh->vertexCount(), c.vertices) << c.file;
    EXPECT_TRUE(mesh->closed()) << c.file;
    EXPECT_TRUE(warnings.empty()) << c.file << ": " << (warnings.empty() ? "" : warnings[0]);
    expectBounds(*mesh, Eigen::Vector3d::Zero(), c.hi.cwiseProduct(scale), c.file);
  }
}

TEST(SceneAssets, MeshUrisThroughResourceRetriever) {
  std::vector<std::string> warnings;
  const auto by_file_uri =
      loadMesh("file://" + dataPath("tetra.obj"), Eigen::Vector3d::Ones(), "test", warnings);
  expectBounds(*by_file_uri, Eigen::Vector3d::Zero(), Eigen::Vector3d(2, 3, 4), "file://");

  // package:// resolves through ROS_PACKAGE_PATH; the source directory is the package itself.
  const char* previous = std::getenv("ROS_PACKAGE_PATH");
  const std::string saved = previous != nullptr ? previous : "";
  setenv("ROS_PACKAGE_PATH", PBD_CLOTH_SOURCE_DIR, 1);
  std::string error;
  std::shared_ptr<const TriangleMesh> by_package;
  try {
    by_package = loadMesh("package://pbd_cloth/test/data/box_1x2x3.stl", Eigen::Vector3d::Ones(),
                          "test", warnings);
  } catch (const ConfigError& e) {
    error = e.what();
  }
  if (previous != nullptr) {
    setenv("ROS_PACKAGE_PATH", saved.c_str(), 1);
  } else {
    unsetenv("ROS_PACKAGE_PATH");
  }
  ASSERT_TRUE(by_package) << error;
  expectBounds(*by_package, Eigen::Vector3d::Zero(), Eigen::Vector3d(1, 2, 3), "package://");
}

TEST(SceneAssets, OpenMeshLoadsWithAWarning) {
  std::vector<std::string> warnings;
  const auto mesh =
      loadMesh(dataPath("open_square.obj"), Eigen::Vector3d::Ones(), "obstacles[3].mesh", warnings);
  EXPECT_FALSE(mesh->closed());
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0], "obstacles[3].mesh: mesh '" + dataPath("open_square.obj") +
                             "' has 4 open boundary edges: handled as a two-sided shell (no "
                             "inside)");
}

TEST(SceneAssets, BadMeshFilesNameTheKeyAndTheFile) {
  struct Case {
    std::string file;
    std::string expected;
  };
  const Case cases[] = {
      {"missing.stl", "not found"},
      {"empty.stl", "is empty"},
      {"no_triangles.obj", "has no triangles"},
      {"not_a_mesh.stl", "is not a mesh file assimp can read"},
      {"", "is a directory"},  // the data directory itself
      {"file:///no/such/dir/x.stl", "cannot be read"},
  };
  for (const Case& c : cases) {
    const std::string uri = c.file.rfind("file://", 0) == 0 ? c.file : dataPath(c.file);
    std::vector<std::string> warnings;
    std::string message;
    try {
      loadMesh(uri, Eigen::Vector3d::Ones(), "obstacles[1].mesh", warnings);
    } catch (const ConfigError& e) {
      message = e.what();
    }
    EXPECT_TRUE(contains(message, "obstacles[1].mesh: mesh file '" + uri + "'")) << message;
    EXPECT_TRUE(contains(message, c.expected)) << message;
  }
}

// --- YAML keys
// ------------------------------------------------------------------------------------

// Files that make assimp 5.2 itself hang or abort (found by test/fuzz/fuzz_mesh_obstacle) end as
// a ConfigError naming the file: assimp reads in a child process (scene_assets.cpp
// importIsolated), so the caller survives. assimp_hang.ply costs the import timeout (20 s).
TEST(SceneAssets, FilesThatBreakAssimpAreRefusedNotFatal) {
  std::vector<std::string> warnings;
  for (const char* file : {"ply_without_end_header.ply", "assimp_hang.ply"}) {
    try {
      loadMesh(dataPath(file), Eigen::Vector3d::Ones(), "obstacles[0].mesh", warnings);
      ADD_FAILURE() << file << " was accepted";
    } catch (const ConfigError& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find("obstacles[0].mesh"), std::string::npos) << message;
      EXPECT_NE(message.find(file), std::string::npos) << message;
    }
  }
  // A good file still loads through the child.
  EXPECT_EQ(
      loadMesh(dataPath("tetra.ply"), Eigen::Vector3d::Ones(), "t", warnings)->triangleCount(), 4);
}

TEST(SceneAssets, NewYamlKeysAreRead) {
  const SceneConfig s = sceneFromYaml(YAML::Load(R"(
obstacles:
  - {name: post, shape: cylinder, radius: 0.03, length: 0.5, tf_frame: post_link}
  - {name: block, shape: mesh, mesh: box_1x2x3.stl, scale: [0.1, 0.2, 0.3], tf_frame: ""}
  - {name: tetra, shape: mesh, mesh: ../data/tetra.obj, scale: 2}
  - {name: plain, shape: mesh, mesh: tetra.ply}
robot:
  description: my_robot/robot_description
  urdf_file: every_geometry.urdf
  links: [body, mesh_link]
  padding: 0.02
  friction: {static: 0.7, kinetic: 0.2}
  pose: [1, 2, 3, 0, 0, 1, 0]
  joint_trajectory:
    - {t: 0.5, positions: {body_joint: 0.25, mesh_joint: 0.1}}
    - {t: 0.5, positions: {body_joint: -0.5}}
    - {t: 2, positions: {}}
)"),
                                      kDataDirectory);
  ASSERT_EQ(s.obstacles.size(), 4u);
  const ObstacleConfig& post = s.obstacles[0];
  EXPECT_EQ(post.shape, ShapeType::kCylinder);
  EXPECT_EQ(post.radius, 0.03);
  EXPECT_EQ(post.length, 0.5);
  EXPECT_EQ(post.tf_frame, "post_link");

  const ObstacleConfig& block = s.obstacles[1];
  EXPECT_EQ(block.shape, ShapeType::kMesh);
  EXPECT_EQ(block.mesh, dataPath("box_1x2x3.stl"));  // stored resolved
  EXPECT_EQ(block.scale, Eigen::Vector3d(0.1, 0.2, 0.3));
  EXPECT_EQ(block.tf_frame, "");
  ASSERT_TRUE(block.mesh_data);
  expectBounds(*block.mesh_data, Eigen::Vector3d::Zero(), Eigen::Vector3d(0.1, 0.4, 0.9), "block");
  // A relative path with directories, resolved against the base directory too.
  EXPECT_EQ(s.obstacles[2].mesh, dataPath("tetra.obj"));
  EXPECT_EQ(s.obstacles[2].scale, Eigen::Vector3d(2, 2, 2));
  EXPECT_EQ(s.obstacles[3].scale, Eigen::Vector3d(1, 1, 1));
  ASSERT_TRUE(s.obstacles[3].mesh_data);

  const RobotConfig& r = s.robot;
  EXPECT_TRUE(r.enabled);
  EXPECT_EQ(r.description, "my_robot/robot_description");
  EXPECT_EQ(r.urdf_file, dataPath("every_geometry.urdf"));
  EXPECT_EQ(r.links, (std::vector<std::string>{"body", "mesh_link"}));
  EXPECT_EQ(r.padding, 0.02);
  EXPECT_EQ(r.friction.static_coefficient, 0.7);
  EXPECT_EQ(r.friction.kinetic_coefficient, 0.2);
  EXPECT_EQ(r.pose.position, Eigen::Vector3d(1, 2, 3));
  EXPECT_TRUE(r.pose.orientation.isApprox(Eigen::Quaterniond(0, 0, 0, 1)));
  ASSERT_EQ(r.joint_trajectory.size(), 3u);
  EXPECT_EQ(r.joint_trajectory[0].t, 0.5);
  using Positions = std::vector<std::pair<std::string, double>>;
  EXPECT_EQ(r.joint_trajectory[0].positions,
            (Positions{{"body_joint", 0.25}, {"mesh_joint", 0.1}}));
  EXPECT_EQ(r.joint_trajectory[1].positions, (Positions{{"body_joint", -0.5}}));
  EXPECT_EQ(r.joint_trajectory[2].t, 2.0);
  EXPECT_TRUE(r.joint_trajectory[2].positions.empty());

  // robot.links: the listed links keep their collisions (with padding and friction), the others
  // keep their place in the tree without collisions.
  const RobotModel& model = r.model;
  ASSERT_EQ(model.links.size(), 4u);
  EXPECT_TRUE(model.links[model.linkIndex("base_link")].collisions.empty());
  ASSERT_EQ(model.links[model.linkIndex("body")].collisions.size(), 3u);
  for (const ObstacleConfig& o : model.links[model.linkIndex("body")].collisions) {
    EXPECT_EQ(o.padding, 0.02);
    EXPECT_TRUE(o.has_friction);
    EXPECT_EQ(o.friction.static_coefficient, 0.7);
    EXPECT_EQ(o.friction.kinetic_coefficient, 0.2);
  }
  EXPECT_EQ(model.links[model.linkIndex("mesh_link")].collisions.size(), 1u);
  EXPECT_TRUE(s.load_warnings.empty());
}

TEST(SceneAssets, RobotSectionDefaults) {
  const SceneConfig absent = sceneFromYaml(YAML::Load("frame_id: world"));
  EXPECT_FALSE(absent.robot.enabled);
  const SceneConfig null_robot = sceneFromYaml(YAML::Load("robot:"));
  EXPECT_FALSE(null_robot.robot.enabled);
  const SceneConfig empty = sceneFromYaml(YAML::Load("robot: {}"));
  EXPECT_TRUE(empty.robot.enabled);
  EXPECT_EQ(empty.robot.description, "robot_description");
  EXPECT_EQ(empty.robot.urdf_file, "");
  EXPECT_TRUE(empty.robot.links.empty());
  EXPECT_EQ(empty.robot.padding, 0.0);
  EXPECT_EQ(empty.robot.pose.position, Eigen::Vector3d::Zero());
  EXPECT_TRUE(empty.robot.model.links.empty());  // nothing loaded without urdf_file
}

TEST(SceneAssets, BadValuesNameTheirKey) {
  struct Case {
    std::string yaml;
    std::string expected;  // the message starts with this
  };
  const Case cases[] = {
      {"obstacles: [{name: a, shape: cylinder, radius: 0}]", "obstacles[0].radius: must be"},
      {"obstacles: [{name: a, shape: cylinder, length: -1}]", "obstacles[0].length: must be"},
      {"obstacles: [{name: a, shape: cylinder, size: [1, 1, 1]}]",
       "obstacles[0].size: not used by a cylinder"},
      {"obstacles: [{name: a, shape: sphere, mesh: box_1x2x3.stl}]",
       "obstacles[0].mesh: not used by a sphere"},
      {"obstacles: [{name: a, shape: box, scale: 2}]", "obstacles[0].scale: not used by a box"},
      {"obstacles: [{name: a, shape: mesh, radius: 1, mesh: box_1x2x3.stl}]",
       "obstacles[0].radius: not used by a mesh"},
      {"obstacles: [{name: a, shape: mesh}]", "obstacles[0].mesh: required"},
      {"obstacles: [{name: a, shape: mesh, mesh: }]", "obstacles[0].mesh: required"},
      {"obstacles: [{name: a, shape: mesh, mesh: [a]}]", "obstacles[0].mesh: must be a string"},
      {"obstacles: [{name: a, shape: mesh, mesh: box_1x2x3.stl, scale: [1, 0, 1]}]",
       "obstacles[0].scale: must be 3 finite non-zero"},
      {"obstacles: [{name: a, shape: mesh, mesh: box_1x2x3.stl, scale: .nan}]",
       "obstacles[0].scale: must be 3 finite non-zero"},
      {"obstacles: [{name: a, shape: mesh, mesh: box_1x2x3.stl, scale: [1, 2]}]",
       "obstacles[0].scale: must be a list of 3 numbers"},
      {"obstacles: [{name: a, shape: mesh, mesh: box_1x2x3.stl, scale: [1, x, 2]}]",
       "obstacles[0].scale[1]: must be a number"},
      {"obstacles: [{name: a, shape: mesh, mesh: missing.stl}]",
       "obstacles[0].mesh: mesh file '" + dataPath("missing.stl") + "' not found"},
      {"obstacles: [{name: a, shape: mesh, mesh: empty.stl}]",
       "obstacles[0].mesh: mesh file '" + dataPath("empty.stl") + "' is empty"},
      {"obstacles: [{name: a, shape: sphere, tf_frame: /base}]",
       "obstacles[0].tf_frame: must be a tf2 frame name without a leading '/'"},
      {"obstacles: [{name: a, shape: sphere, tf_frame: [a]}]",
       "obstacles[0].tf_frame: must be a string"},
      {"robot: {links: [[a]]}", "robot.links[0]: must be a name"},
      {"robot: {links: ['']}", "robot.links[0]: must be a link name"},
      {"robot: {links: body}", "robot.links: must be a list of link names"},
      {"robot: {padding: -0.1}", "robot.padding: must be a finite number >= 0"},
      {"robot: {padding: .inf}", "robot.padding: must be a finite number >= 0"},
      {"robot: {friction: {static: 0.3, kinetic: 0.5}}", "robot.friction.kinetic: must be"},
      {"robot: {friction: {static: -1, kinetic: 0}}", "robot.friction.static: must be"},
      {"robot: {friction: {dynamic: 0.1}}", "robot.friction.dynamic: unknown key"},
      {"robot: {pose: [0, 0, 0, 0, 0, 0, 0]}", "robot.pose: the quaternion"},
      {"robot: {pose: [0, 0, 0]}", "robot.pose: must be a list of 7 numbers"},
      {"robot: {description: '', urdf_file: ''}", "robot.description: must name"},
      {"robot: {joints: []}", "robot.joints: unknown key"},
      {"robot: {joint_trajectory: [{t: -1, positions: {a: 0}}]}",
       "robot.joint_trajectory[0].t: must be a finite time >= 0"},
      {"robot: {joint_trajectory: [{t: 1, positions: {a: 0}}, {t: 0.5, positions: {a: 1}}]}",
       "robot.joint_trajectory[1].t: must be a finite time >= 0 and >= the previous"},
      {"robot: {joint_trajectory: [{t: .nan, positions: {a: 0}}]}",
       "robot.joint_trajectory[0].t: must be a finite time"},
      {"robot: {joint_trajectory: [{t: 0, positions: {a: .inf}}]}",
       "robot.joint_trajectory[0].positions.a: must be a finite number"},
      {"robot: {joint_trajectory: [{t: 0, positions: {a: x}}]}",
       "robot.joint_trajectory[0].positions.a: must be a number"},
      {"robot: {joint_trajectory: [{t: 0, positions: [0.1]}]}",
       "robot.joint_trajectory[0].positions: must be a map"},
      {"robot: {joint_trajectory: [{t: 0}]}", "robot.joint_trajectory[0].positions: required"},
      {"robot: {joint_trajectory: [{positions: {}}]}", "robot.joint_trajectory[0].t: required"},
      {"robot: {joint_trajectory: [{t: 0, positions: {}, grasp: true}]}",
       "robot.joint_trajectory[0].grasp: unknown key"},
      {"robot: {joint_trajectory: [0.5]}", "robot.joint_trajectory[0]: must be a map"},
      {"robot: {urdf_file: missing.urdf}",
       "robot.urdf_file: URDF file '" + dataPath("missing.urdf") + "' not found"},
      {"robot: {urdf_file: tetra.obj}",
       "robot.urdf_file '" + dataPath("tetra.obj") + "': does not parse as URDF"},
      // With the URDF loaded: names checked against it.
      {"robot: {urdf_file: every_geometry.urdf, links: [body, elbow]}",
       "robot.links[1]: no link 'elbow' in the URDF (links with collision elements: base_link, "
       "body, mesh_link)"},
      {"robot: {urdf_file: every_geometry.urdf, joint_trajectory: [{t: 0, positions: {elbow: 1}}]}",
       "robot.joint_trajectory[0].positions.elbow: no joint 'elbow' in the URDF (joints: "
       "body_joint, mesh_joint)"},
      {"robot: {urdf_file: every_geometry.urdf, joint_trajectory: [{t: 0, positions: {}}, "
       "{t: 1, positions: {body_joint: 0, tool_joint: 1}}]}",
       "robot.joint_trajectory[1].positions.tool_joint: joint 'tool_joint' is fixed"},
      {"robot: {urdf_file: planar_arm.urdf, joint_trajectory: [{t: 0, positions: {wrist: 1}}]}",
       "robot.joint_trajectory[0].positions.wrist: joint 'wrist' mimics joint 'elbow'"},
  };
  for (const Case& c : cases) {
    const std::string message = errorOf(c.yaml);
    EXPECT_EQ(message.rfind(c.expected, 0), 0u)
        << "yaml: " << c.yaml << "\nexpected: " << c.expected << "...\ngot: " << message;
  }
}

// --- URDF
// -----------------------------------------------------------------------------------------

// The scene file names the URDF and a mesh relative to itself (not to the working directory).
TEST(SceneAssets, UrdfWithEveryGeometryKind) {
  const SceneConfig s = loadScene(dataPath("robot_scene.yaml"));
  EXPECT_TRUE(s.load_warnings.empty());
  ASSERT_EQ(s.obstacles.size(), 1u);
  ASSERT_TRUE(s.obstacles[0].mesh_data);
  expectBounds(*s.obstacles[0].mesh_data, Eigen::Vector3d::Zero(), Eigen::Vector3d(0.1, 0.2, 0.3),
               "block");

  const RobotModel& model = s.robot.model;
  EXPECT_EQ(model.name, "every_geometry");
  ASSERT_EQ(model.links.size(), 4u);
  EXPECT_EQ(model.links[model.root_link].name, "base_link");

  const std::vector<ObstacleConfig>& base = model.links[model.linkIndex("base_link")].collisions;
  ASSERT_EQ(base.size(), 1u);
  EXPECT_EQ(base[0].name, "base_link/0");
  EXPECT_EQ(base[0].shape, ShapeType::kBox);
  EXPECT_EQ(base[0].size, Eigen::Vector3d(0.4, 0.3, 0.1));
  EXPECT_EQ(base[0].pose.position, Eigen::Vector3d(0, 0, 0.05));

  // All three collision elements, in file order, each with its origin.
  const std::vector<ObstacleConfig>& body = model.links[model.linkIndex("body")].collisions;
  ASSERT_EQ(body.size(), 3u);
  EXPECT_EQ(body[0].name, "body/0");
  EXPECT_EQ(body[0].shape, ShapeType::kBox);
  EXPECT_EQ(body[0].size, Eigen::Vector3d(0.1, 0.2, 0.3));
  EXPECT_EQ(body[0].pose.position, Eigen::Vector3d(0.1, 0, 0));
  EXPECT_EQ(body[1].name, "body/1");
  EXPECT_EQ(body[1].shape, ShapeType::kSphere);
  EXPECT_EQ(body[1].radius, 0.05);
  EXPECT_EQ(body[1].pose.position, Eigen::Vector3d(0, 0.2, 0));
  EXPECT_EQ(body[2].name, "body/2");
  EXPECT_EQ(body[2].shape, ShapeType::kCylinder);
  EXPECT_EQ(body[2].radius, 0.04);
  EXPECT_EQ(body[2].length, 0.25);
  EXPECT_EQ(body[2].pose.position, Eigen::Vector3d(0, 0, 0.3));
  const Eigen::Quaterniond roll_90(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX()));
  EXPECT_NEAR(body[2].pose.orientation.angularDistance(roll_90), 0.0, 1e-12);
  for (const ObstacleConfig& o : body) {
    EXPECT_EQ(o.padding, 0.01);
    EXPECT_TRUE(o.has_friction);
    EXPECT_EQ(o.friction.static_coefficient, 0.6);
    EXPECT_EQ(o.friction.kinetic_coefficient, 0.3);
  }

  // The mesh: relative to the URDF's directory, scaled per axis (a negative factor mirrors).
  const std::vector<ObstacleConfig>& mesh = model.links[model.linkIndex("mesh_link")].collisions;
  ASSERT_EQ(mesh.size(), 1u);
  EXPECT_EQ(mesh[0].shape, ShapeType::kMesh);
  EXPECT_EQ(mesh[0].mesh, dataPath("box_1x2x3.stl"));
  EXPECT_EQ(mesh[0].scale, Eigen::Vector3d(0.1, 0.2, -0.3));
  EXPECT_EQ(mesh[0].pose.position, Eigen::Vector3d(0, 0, 0.1));
  ASSERT_TRUE(mesh[0].mesh_data);
  EXPECT_TRUE(mesh[0].mesh_data->closed());
  expectBounds(*mesh[0].mesh_data, Eigen::Vector3d(0, 0, -0.9), Eigen::Vector3d(0.1, 0.4, 0),
               "mesh_link");
  EXPECT_TRUE(model.links[model.linkIndex("tool")].collisions.empty());

  ASSERT_EQ(model.joints.size(), 3u);
  const RobotJoint& prismatic = model.joints[model.jointIndex("mesh_joint")];
  EXPECT_EQ(prismatic.type, JointType::kPrismatic);
  EXPECT_EQ(prismatic.axis, Eigen::Vector3d(0, 0, 1));  // "0 0 2" normalized
  EXPECT_EQ(prismatic.lower, 0.0);
  EXPECT_EQ(prismatic.upper, 0.2);
  EXPECT_EQ(s.robot.pose.position, Eigen::Vector3d(0, 0, 0.5));
  ASSERT_EQ(s.robot.joint_trajectory.size(), 2u);
}

TEST(SceneAssets, SelectedLinkWithoutCollisionWarns) {
  SceneConfig scene;
  scene.robot.links = {"tool", "body"};
  scene.robot.urdf_file = dataPath("every_geometry.urdf");
  loadRobotFile(scene);
  ASSERT_EQ(scene.load_warnings.size(), 1u);
  EXPECT_EQ(scene.load_warnings[0],
            "robot.links[0]: link 'tool' has no collision element: it cannot touch the cloth");
  EXPECT_EQ(scene.robot.model.links[scene.robot.model.linkIndex("body")].collisions.size(), 3u);
  EXPECT_TRUE(scene.robot.model.links[scene.robot.model.linkIndex("mesh_link")].collisions.empty());
}

TEST(SceneAssets, BadUrdfInputNamesSourceLinkAndFile) {
  // Does not parse: the message names the source (and urdfdom's reason).
  const std::string unparsed =
      robotErrorOf("<robot name='r'><link name='a'></robot>", "robot_description");
  EXPECT_EQ(unparsed.rfind("robot_description: does not parse as URDF", 0), 0u) << unparsed;
  const std::string not_xml = robotErrorOf("this is not xml", "robot_description");
  EXPECT_EQ(not_xml.rfind("robot_description: does not parse as URDF", 0), 0u) << not_xml;
  const std::string empty = robotErrorOf("", "robot_description");
  EXPECT_EQ(empty.rfind("robot_description: does not parse as URDF", 0), 0u) << empty;

  // Mimic joints in a cycle (test/fuzz/fuzz_urdf found one that reached the forward kinematics
  // and ended the process): refused at load, naming the joints. Two joints that mimic each
  // other, and one that mimics itself.
  auto twoJoints = [](const std::string& mimic_of_a, const std::string& mimic_of_b) {
    auto joint = [](const std::string& name, const std::string& child, const std::string& mimic) {
      return "<joint name='" + name + "' type='revolute'><parent link='base'/><child link='" +
             child + "'/><axis xyz='0 0 1'/><limit lower='-1' upper='1' effort='1' velocity='1'/>" +
             (mimic.empty() ? "" : "<mimic joint='" + mimic + "'/>") + "</joint>";
    };
    return "<robot name='r'><link name='base'/><link name='l1'/><link name='l2'/>" +
           joint("a", "l1", mimic_of_a) + joint("b", "l2", mimic_of_b) + "</robot>";
  };
  const std::string mutual = robotErrorOf(twoJoints("b", "a"), "robot_description");
  EXPECT_EQ(mutual.rfind("robot_description: mimic joints form a cycle: a -> b -> a", 0), 0u)
      << mutual;
  const std::string itself = robotErrorOf(twoJoints("", "b"), "robot_description");
  EXPECT_EQ(itself.rfind("robot_description: mimic joints form a cycle: b -> b", 0), 0u) << itself;

  // Mesh files: missing, empty, unreadable, without triangles: the link and the file are named.
  struct Case {
    std::string file;
    std::string expected;
  };
  const Case cases[] = {
      {dataPath("missing.stl"), "not found"},
      {dataPath("empty.stl"), "is empty"},
      {dataPath("no_triangles.obj"), "has no triangles"},
      {dataPath("not_a_mesh.stl"), "is not a mesh file assimp can read"},
      {"package://no_such_package_xyz/mesh.stl", "cannot be read"},
  };
  for (const Case& c : cases) {
    const std::string message = robotErrorOf(oneLinkUrdf("<mesh filename='" + c.file + "'/>"));
    EXPECT_EQ(message.rfind("robot link 'arm' collision 0 mesh: mesh file '" + c.file + "'", 0), 0u)
        << message;
    EXPECT_TRUE(contains(message, c.expected)) << message;
  }
  const std::string zero_scale =
      robotErrorOf(oneLinkUrdf("<mesh filename='" + dataPath("tetra.obj") + "' scale='1 0 1'/>"));
  EXPECT_EQ(zero_scale.rfind("robot link 'arm' collision 0 mesh: scale", 0), 0u) << zero_scale;

  // A geometry urdfdom does not know: it drops the element with a logged error; refused here.
  const std::string capsule = robotErrorOf(oneLinkUrdf("<capsule radius='1' length='2'/>"));
  EXPECT_EQ(capsule,
            "robot link 'arm' collision 0: unsupported geometry 'capsule' (supported: box, "
            "sphere, cylinder, mesh)");

  // A degenerate primitive is refused by validate(), naming the link.
  SceneConfig scene;
  loadRobot(scene, oneLinkUrdf("<sphere radius='0'/>"), "test urdf");
  try {
    validate(scene);
    ADD_FAILURE() << "a zero radius passed validation";
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("robot link 'arm' collision 0.radius: must be", 0), 0u)
        << e.what();
  }
}

// An unsupported geometry on a link robot.links leaves out does not stop the load; urdfdom's
// complaint becomes a load warning.
TEST(SceneAssets, UnsupportedGeometryOnAnUnselectedLinkWarns) {
  SceneConfig scene;
  scene.robot.links = {"b"};
  loadRobot(scene,
            "<robot name='r'><link name='a'><collision><geometry><capsule radius='1' "
            "length='2'/></geometry></collision></link><link name='b'><collision><geometry>"
            "<sphere radius='0.1'/></geometry></collision></link><joint name='j' type='fixed'>"
            "<parent link='a'/><child link='b'/></joint></robot>",
            "test urdf");
  ASSERT_EQ(scene.load_warnings.size(), 1u);
  EXPECT_TRUE(contains(scene.load_warnings[0], "test urdf: urdfdom: ")) << scene.load_warnings[0];
  EXPECT_TRUE(contains(scene.load_warnings[0], "capsule")) << scene.load_warnings[0];
  EXPECT_EQ(scene.robot.model.links[scene.robot.model.linkIndex("b")].collisions.size(), 1u);
}

TEST(SceneAssets, OpenRobotMeshWarnsNamingLinkAndFile) {
  SceneConfig scene;
  const std::string file = dataPath("open_square.obj");
  loadRobot(scene, oneLinkUrdf("<mesh filename='" + file + "'/>"), "test urdf");
  ASSERT_EQ(scene.load_warnings.size(), 1u);
  EXPECT_EQ(scene.load_warnings[0], "robot link 'arm' collision 0 mesh: mesh '" + file +
                                        "' has 4 open boundary edges: handled as a two-sided "
                                        "shell (no inside)");
  validate(scene);  // an open mesh is allowed
}

TEST(SceneAssets, LinksSharingAMeshFileShareItsData) {
  const std::string mesh = "<mesh filename='" + dataPath("tetra.obj") + "'/>";
  SceneConfig scene;
  loadRobot(scene,
            "<robot name='r'><link name='a'><collision><geometry>" + mesh +
                "</geometry></collision></link><link name='b'><collision><geometry>" + mesh +
                "</geometry></collision></link><joint name='j' type='fixed'><parent link='a'/>"
                "<child link='b'/></joint></robot>",
            "test urdf");
  const RobotModel& model = scene.robot.model;
  ASSERT_EQ(model.links.size(), 2u);
  EXPECT_EQ(model.links[0].collisions[0].mesh_data, model.links[1].collisions[0].mesh_data);
}

}  // namespace
}  // namespace pbd_cloth
