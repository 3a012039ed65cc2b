// Checks on incoming poses that need no tf (PoseTransformer::checkPose), the scene-frame shortcut,
// and the rejection record (input_rejections.h).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include <ros/time.h>
#include <tf2_ros/buffer.h>

#include "pbd_cloth/ros/input_rejections.h"
#include "pbd_cloth/ros/pose_transformer.h"

namespace pbd_cloth {
namespace {

geometry_msgs::Pose identityPose() {
  geometry_msgs::Pose pose;
  pose.orientation.w = 1.0;
  return pose;
}

TEST(CheckPose, RefusesNaNAndInfinity) {
  PoseTransformer::Failure failure;
  geometry_msgs::Pose pose = identityPose();
  pose.position.y = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(PoseTransformer::checkPose(pose, failure));
  EXPECT_EQ(failure.reason, RejectReason::kNonFinite);
  pose = identityPose();
  pose.orientation.z = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(PoseTransformer::checkPose(pose, failure));
  EXPECT_EQ(failure.reason, RejectReason::kNonFinite);
}

TEST(CheckPose, RefusesAZeroQuaternionButNormalisesOthers) {
  PoseTransformer::Failure failure;
  geometry_msgs::Pose pose = identityPose();
  pose.orientation.w = 0.0;
  EXPECT_FALSE(PoseTransformer::checkPose(pose, failure));
  EXPECT_EQ(failure.reason, RejectReason::kZeroQuaternion);
  pose.orientation.w = 2.0;  // not unit length, but a direction: accepted and normalised
  EXPECT_TRUE(PoseTransformer::checkPose(pose, failure));
}

class SceneFrame : public testing::Test {
 protected:
  void SetUp() override { ros::Time::init(); }
};

TEST_F(SceneFrame, PosesInTheSceneFrameOrNoFrameNeedNoTf) {
  tf2_ros::Buffer buffer;
  const PoseTransformer transformer(buffer, PoseTransformer::Config{"world", 0.0});
  geometry_msgs::PoseStamped msg;
  msg.pose = identityPose();
  msg.pose.position.x = 0.5;
  msg.pose.orientation.w = 2.0;
  for (const char* frame : {"world", "/world", ""}) {
    msg.header.frame_id = frame;
    Pose pose;
    PoseTransformer::Failure failure;
    ASSERT_TRUE(transformer.toSceneFrame(msg, pose, failure)) << "'" << frame << "'";
    EXPECT_DOUBLE_EQ(pose.position.x(), 0.5);
    EXPECT_DOUBLE_EQ(pose.orientation.w(), 1.0);
  }
}

TEST_F(SceneFrame, AFrameTfNeverHeardOfIsUnknown) {
  tf2_ros::Buffer buffer;
  const PoseTransformer transformer(buffer, PoseTransformer::Config{"world", 0.0});
  geometry_msgs::PoseStamped msg;
  msg.header.frame_id = "elsewhere";
  msg.pose = identityPose();
  Pose pose;
  PoseTransformer::Failure failure;
  EXPECT_FALSE(transformer.toSceneFrame(msg, pose, failure));
  EXPECT_EQ(failure.reason, RejectReason::kUnknownFrame);
  EXPECT_NE(failure.detail.find("elsewhere"), std::string::npos);
}

TEST(InputRejections, CountsByReasonAndKeepsTheLast) {
  InputRejections rejections(1000.0);
  EXPECT_EQ(rejections.total(), 0u);
  EXPECT_TRUE(rejections.last().empty());
  rejections.reject("/a/pose", RejectReason::kNonFinite, "x is NaN");
  rejections.reject("/a/pose", RejectReason::kNonFinite, "y is NaN");  // throttled, still counted
  rejections.reject("/b/pose", RejectReason::kUnknownFrame, "no frame 'q'");
  EXPECT_EQ(rejections.total(), 3u);
  EXPECT_EQ(rejections.countsByReason().at(RejectReason::kNonFinite), 2u);
  EXPECT_EQ(rejections.countsByReason().at(RejectReason::kUnknownFrame), 1u);
  EXPECT_NE(rejections.last().find("/b/pose"), std::string::npos);
  EXPECT_NE(rejections.last().find("unknown frame"), std::string::npos);
}

}  // namespace
}  // namespace pbd_cloth
