// RobotModel: the joint tree read from a URDF (test/data/planar_arm.urdf) and forward kinematics
// against poses worked out by hand: for the planar arm a heading and an (x, y) walk in the plane,
// for a hand-built model with a joint about x, the rotated offsets written out with cos and sin.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "pbd_cloth/scene/scene_assets.h"

namespace pbd_cloth {
namespace {

// Compositions of a few unit quaternions and vectors of size ~1: round-off is ~1e-16 per step.
constexpr double kTolerance = 1e-12;

std::string dataPath(const std::string& name) {
  return std::string(PBD_CLOTH_SOURCE_DIR) + "/test/data/" + name;
}

RobotModel planarArm() {
  SceneConfig scene;
  scene.robot.urdf_file = dataPath("planar_arm.urdf");
  loadRobotFile(scene);
  return scene.robot.model;
}

// A frame of the planar arm: (x, y) at height z, turned by `yaw` about +z.
struct Planar {
  double x, y, z, yaw;
  // The frame at offset (dx, dy, dz) in this frame, turned by a further `turn`.
  Planar then(double dx, double dy, double dz, double turn) const {
    return {x + std::cos(yaw) * dx - std::sin(yaw) * dy,
            y + std::sin(yaw) * dx + std::cos(yaw) * dy, z + dz, yaw + turn};
  }
};

void expectPose(const Pose& actual, const Eigen::Vector3d& position,
                const Eigen::Quaterniond& orientation, const std::string& what) {
  EXPECT_NEAR((actual.position - position).norm(), 0.0, kTolerance) << what;
  EXPECT_NEAR(actual.orientation.angularDistance(orientation), 0.0, kTolerance) << what;
}

void expectPlanar(const Pose& actual, const Planar& expected, const std::string& what) {
  expectPose(actual, Eigen::Vector3d(expected.x, expected.y, expected.z),
             Eigen::Quaterniond(Eigen::AngleAxisd(expected.yaw, Eigen::Vector3d::UnitZ())), what);
}

TEST(RobotModel, PlanarArmTreeFromUrdf) {
  const RobotModel model = planarArm();
  EXPECT_EQ(model.name, "planar_arm");
  ASSERT_EQ(model.links.size(), 6u);
  ASSERT_EQ(model.joints.size(), 5u);
  EXPECT_EQ(model.links[model.root_link].name, "base_link");
  EXPECT_EQ(model.links[model.root_link].parent_joint, -1);
  EXPECT_EQ(model.linkIndex("no_such_link"), -1);
  EXPECT_EQ(model.jointIndex("no_such_joint"), -1);

  const RobotJoint& shoulder = model.joints[model.jointIndex("shoulder")];
  EXPECT_EQ(shoulder.type, JointType::kRevolute);
  EXPECT_EQ(shoulder.parent_link, model.linkIndex("base_link"));
  EXPECT_EQ(shoulder.child_link, model.linkIndex("upper_arm"));
  EXPECT_EQ(model.links[model.linkIndex("upper_arm")].parent_joint, model.jointIndex("shoulder"));
  EXPECT_EQ(shoulder.origin.position, Eigen::Vector3d(0, 0, 0.1));
  EXPECT_EQ(shoulder.lower, -3.0);
  EXPECT_EQ(shoulder.upper, 3.0);

  const RobotJoint& elbow = model.joints[model.jointIndex("elbow")];
  EXPECT_EQ(elbow.axis, Eigen::Vector3d(0, 0, -1));
  EXPECT_EQ(model.joints[model.jointIndex("slide")].type, JointType::kPrismatic);
  EXPECT_EQ(model.joints[model.jointIndex("tool_mount")].type, JointType::kFixed);

  const RobotJoint& wrist = model.joints[model.jointIndex("wrist")];
  EXPECT_EQ(wrist.mimic_joint, model.jointIndex("elbow"));
  EXPECT_EQ(wrist.mimic_multiplier, 0.5);
  EXPECT_EQ(wrist.mimic_offset, 0.1);

  // Tree order: every joint's parent link comes before its child link.
  for (const RobotJoint& joint : model.joints) {
    EXPECT_LT(joint.parent_link, joint.child_link) << joint.name;
  }
}

TEST(RobotModel, PlanarArmPosesEqualTheAnalyticOnes) {
  const RobotModel model = planarArm();
  Pose root;
  root.position = Eigen::Vector3d(1.0, 2.0, 3.0);
  const double root_yaw = 0.3;
  root.orientation = Eigen::AngleAxisd(root_yaw, Eigen::Vector3d::UnitZ());

  const double configurations[][3] = {
      {0.0, 0.0, 0.0}, {0.3, -1.2, 0.15}, {2.5, 0.7, 0.3}, {-3.0, 3.0, -0.05}};
  for (const auto& q : configurations) {
    const double shoulder = q[0], elbow = q[1], slide = q[2];
    std::vector<double> positions(model.joints.size(), 0.0);
    positions[model.jointIndex("shoulder")] = shoulder;
    positions[model.jointIndex("elbow")] = elbow;
    positions[model.jointIndex("slide")] = slide;
    // Ignored: a fixed joint has no position, a mimic joint follows the elbow.
    positions[model.jointIndex("tool_mount")] = 42.0;
    positions[model.jointIndex("wrist")] = -7.0;

    std::vector<Pose> poses;
    model.linkPoses(root, positions, poses);
    ASSERT_EQ(poses.size(), model.links.size());

    const Planar base{1.0, 2.0, 3.0, root_yaw};
    const Planar upper_arm = base.then(0.0, 0.0, 0.1, shoulder);
    const Planar forearm = upper_arm.then(0.5, 0.0, 0.0, -elbow);  // axis -z
    const Planar slider = forearm.then(0.4 + slide, 0.0, 0.0, 0.0);
    const Planar tool = slider.then(0.1, 0.0, 0.0, M_PI / 2.0);
    const Planar hand = tool.then(0.05, 0.0, 0.0, 0.5 * elbow + 0.1);
    const std::string at = " at shoulder " + std::to_string(shoulder) + ", elbow " +
                           std::to_string(elbow) + ", slide " + std::to_string(slide);
    expectPlanar(poses[model.linkIndex("base_link")], base, "base_link" + at);
    expectPlanar(poses[model.linkIndex("upper_arm")], upper_arm, "upper_arm" + at);
    expectPlanar(poses[model.linkIndex("forearm")], forearm, "forearm" + at);
    expectPlanar(poses[model.linkIndex("slider")], slider, "slider" + at);
    expectPlanar(poses[model.linkIndex("tool")], tool, "tool" + at);
    expectPlanar(poses[model.linkIndex("hand")], hand, "hand" + at);
  }
}

// A model built in code, its links out of tree order (a child before its parent): a revolute
// joint about x, a fixed offset beyond it, and a floating joint, which the URDF gives no state.
TEST(RobotModel, JointAboutXAndLinksOutOfTreeOrder) {
  RobotModel model;
  model.links.resize(4);
  model.links[0].name = "c";
  model.links[1].name = "b";
  model.links[2].name = "a";
  model.links[3].name = "d";
  model.root_link = 2;
  model.joints.resize(3);
  RobotJoint& j1 = model.joints[0];  // a -> b
  j1.name = "j1";
  j1.type = JointType::kRevolute;
  j1.parent_link = 2;
  j1.child_link = 1;
  j1.origin.position = Eigen::Vector3d(0, 0, 1);
  j1.axis = Eigen::Vector3d::UnitX();
  RobotJoint& j2 = model.joints[1];  // b -> c
  j2.name = "j2";
  j2.type = JointType::kFixed;
  j2.parent_link = 1;
  j2.child_link = 0;
  j2.origin.position = Eigen::Vector3d(0, 1, 0);
  RobotJoint& j3 = model.joints[2];  // a -> d
  j3.name = "j3";
  j3.type = JointType::kFloating;
  j3.parent_link = 2;
  j3.child_link = 3;
  j3.origin.position = Eigen::Vector3d(0, 0, 0.5);
  model.links[1].parent_joint = 0;
  model.links[0].parent_joint = 1;
  model.links[3].parent_joint = 2;

  const double theta = 0.7;
  std::vector<Pose> poses(1);  // wrong size: resized
  model.linkPoses(Pose(), {theta, 5.0, 5.0}, poses);
  ASSERT_EQ(poses.size(), 4u);
  const Eigen::Quaterniond about_x(Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitX()));
  expectPose(poses[2], Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity(), "a (root)");
  expectPose(poses[1], Eigen::Vector3d(0, 0, 1), about_x, "b");
  expectPose(poses[0], Eigen::Vector3d(0, std::cos(theta), 1 + std::sin(theta)), about_x, "c");
  expectPose(poses[3], Eigen::Vector3d(0, 0, 0.5), Eigen::Quaterniond::Identity(), "d");

  // Positions missing at the end read as 0.
  model.linkPoses(Pose(), {}, poses);
  expectPose(poses[0], Eigen::Vector3d(0, 1, 1), Eigen::Quaterniond::Identity(), "c at 0");
}

}  // namespace
}  // namespace pbd_cloth
