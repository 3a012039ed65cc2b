// Bad input to cloth_node (bad_input.test, test/ros/interaction_scene.yaml): each kind is refused
// and counted in ~state.stats.rejected_inputs and the diagnostics, the node keeps stepping, every
// position stays finite and the body keeps its last good pose.
#include <atomic>
#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <thread>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <diagnostic_msgs/KeyValue.h>
#include <geometry_msgs/TransformStamped.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <tf2_ros/transform_broadcaster.h>
#include <visualization_msgs/MarkerArray.h>

#include "pbd_cloth/ClothState.h"
#include "ros_test_helpers.h"

namespace {

using pbd_cloth::ClothState;
using pbd_cloth_test::distance;
using pbd_cloth_test::point;
using pbd_cloth_test::PosePublisher;
using pbd_cloth_test::poseStamped;
using pbd_cloth_test::Recorder;
using pbd_cloth_test::StateRecorder;

const double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();
using pbd_cloth_test::node;

// Sends one bad input and checks the node's reaction: rejected_inputs grows, the simulation steps
// on, and every position stays finite.
void expectRejected(const std::function<void()>& send) {
  StateRecorder states(node() + "/state");
  ClothState before;
  ASSERT_TRUE(states.waitForNext(before, 10.0)) << "the node is not publishing";
  send();
  ClothState after;
  ASSERT_TRUE(states.waitForNext(
      after, 5.0,
      [&](const ClothState& s) { return s.stats.rejected_inputs > before.stats.rejected_inputs; }))
      << "rejected_inputs stayed at " << before.stats.rejected_inputs;
  EXPECT_TRUE(pbd_cloth_test::allFinite(after));
  ClothState later;
  ASSERT_TRUE(states.waitForNext(later, 5.0, [&](const ClothState& s) {
    return s.stats.sim_time > after.stats.sim_time + 0.2;
  })) << "the simulation stopped stepping";
  EXPECT_TRUE(pbd_cloth_test::allFinite(later));
}

// A publisher of ~left/pose that has put the gripper at a known good pose first.
class BadPoseTest : public testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(gripper_.waitForSubscriber());
    ASSERT_TRUE(ball_.waitForSubscriber());
    gripper_.publish(poseStamped("world", good_));
    ASSERT_TRUE(gripperAt(good_)) << "the good pose was not taken";
  }

  // Waits until the gripper's marker shows `position`.
  bool gripperAt(const geometry_msgs::Point& position) {
    visualization_msgs::MarkerArray msg;
    return markers_.waitForNext(msg, 5.0, [&](const visualization_msgs::MarkerArray& m) {
      for (const auto& marker : m.markers) {
        if (marker.ns == "grippers" && marker.id == 0) {
          return distance(marker.pose.position, position) < 1e-9;
        }
      }
      return false;
    });
  }

  // After the bad input the gripper is still where the last good pose put it.
  void expectGripperKeptItsPose() { EXPECT_TRUE(gripperAt(good_)); }

  const geometry_msgs::Point good_ = point(0.3, -0.4, 0.4);
  Recorder<visualization_msgs::MarkerArray> markers_{node() + "/markers"};
  PosePublisher gripper_{node() + "/left/pose"};
  PosePublisher ball_{node() + "/ball/pose"};
};

TEST_F(BadPoseTest, NaNPosition) {
  expectRejected([this] { gripper_.publish(poseStamped("world", point(kNaN, 0.0, 0.5))); });
  expectGripperKeptItsPose();
}

TEST_F(BadPoseTest, InfiniteOrientation) {
  expectRejected([this] {
    geometry_msgs::PoseStamped msg = poseStamped("world", point(0.0, 0.0, 0.5));
    msg.pose.orientation.x = kInf;
    gripper_.publish(msg);
  });
  expectGripperKeptItsPose();
}

TEST_F(BadPoseTest, ZeroQuaternion) {
  expectRejected([this] {
    geometry_msgs::PoseStamped msg = poseStamped("world", point(0.0, 0.0, 0.5));
    msg.pose.orientation.w = 0.0;
    gripper_.publish(msg);
  });
  expectGripperKeptItsPose();
}

// Finite but absurd: 1e300 m would overflow the step's squares; anything beyond 10 km of the scene
// origin is refused as "far from the origin" (simulation.h kMaxPoseCoordinate).
TEST_F(BadPoseTest, PoseFarFromTheOrigin) {
  expectRejected([this] { gripper_.publish(poseStamped("world", point(0.0, 1e300, 0.5))); });
  expectGripperKeptItsPose();
  expectRejected([this] { ball_.publish(poseStamped("world", point(2e4, 0.0, 0.5))); });
}

TEST_F(BadPoseTest, UnknownFrame) {
  expectRejected([this] { gripper_.publish(poseStamped("no_such_frame", point(0.0, 0.0, 0.5))); });
  expectGripperKeptItsPose();
}

TEST_F(BadPoseTest, TfLookupThatTimesOut) {
  // A frame tf knows (broadcast at 30 Hz here), asked for at a time it has no transform for yet:
  // the lookup waits out ~tf_timeout and gives up.
  std::atomic<bool> running{true};
  std::thread broadcaster_thread([&running] {
    tf2_ros::TransformBroadcaster broadcaster;
    while (running && ros::ok()) {
      geometry_msgs::TransformStamped transform;
      transform.header.stamp = ros::Time::now();
      transform.header.frame_id = "world";
      transform.child_frame_id = "moving";
      transform.transform.rotation.w = 1.0;
      broadcaster.sendTransform(transform);
      ros::WallDuration(1.0 / 30.0).sleep();
    }
  });
  ros::WallDuration(1.0).sleep();  // the node hears of `moving`
  expectRejected([this] {
    geometry_msgs::PoseStamped msg = poseStamped("moving", point(0.0, 0.0, 0.5));
    msg.header.stamp = ros::Time::now() + ros::Duration(60.0);
    gripper_.publish(msg);
  });
  expectGripperKeptItsPose();
  running = false;
  broadcaster_thread.join();
}

TEST_F(BadPoseTest, MessageOlderThanTheLastOne) {
  geometry_msgs::PoseStamped newer = poseStamped("world", good_);
  gripper_.publish(newer);
  ros::WallDuration(0.3).sleep();
  expectRejected([&] {
    geometry_msgs::PoseStamped older = poseStamped("world", point(0.0, 0.0, 0.5));
    older.header.stamp = newer.header.stamp - ros::Duration(1.0);
    gripper_.publish(older);
  });
  expectGripperKeptItsPose();
}

TEST_F(BadPoseTest, NaNObstaclePose) {
  expectRejected([this] { ball_.publish(poseStamped("world", point(0.2, kNaN, 0.75))); });
}

TEST(BadGrasp, UnknownGripperByName) {
  ros::NodeHandle nh;
  ros::Publisher grasp_by_name =
      nh.advertise<diagnostic_msgs::KeyValue>(node() + "/grasp_by_name", 10);
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(10.0);
  while (grasp_by_name.getNumSubscribers() == 0 && ros::WallTime::now() < deadline) {
    ros::WallDuration(0.01).sleep();
  }
  diagnostic_msgs::KeyValue command;
  command.key = "nobody";
  command.value = "true";
  expectRejected([&] { grasp_by_name.publish(command); });
  command.key = "left";
  command.value = "maybe";
  expectRejected([&] { grasp_by_name.publish(command); });
}

TEST(Diagnostics, ReportTheRejectedInputs) {
  // The earlier tests rejected inputs; one more, then the "inputs" status must warn and count.
  Recorder<diagnostic_msgs::DiagnosticArray> diagnostics("/diagnostics");
  PosePublisher gripper(node() + "/left/pose");
  ASSERT_TRUE(gripper.waitForSubscriber());
  StateRecorder states(node() + "/state");
  gripper.publish(poseStamped("world", point(kNaN, kNaN, kNaN)));
  ClothState state;
  ASSERT_TRUE(states.waitForNext(state, 5.0,
                                 [](const ClothState& s) { return s.stats.rejected_inputs >= 1; }));

  // The status warns when inputs were rejected since its last report: a NaN pose is sent again
  // before each wait, so a report that went out between the send and the wait cannot hide it.
  const std::string name = node().substr(1) + ": inputs";
  const auto warns = [&](const diagnostic_msgs::DiagnosticArray& m) {
    for (const auto& status : m.status) {
      if (status.name != name || status.level != diagnostic_msgs::DiagnosticStatus::WARN) continue;
      for (const auto& value : status.values) {
        if (value.key == "rejected inputs" &&
            std::stoul(value.value) >= state.stats.rejected_inputs) {
          return true;
        }
      }
    }
    return false;
  };
  diagnostic_msgs::DiagnosticArray msg;
  bool warned = false;
  for (int attempt = 0; attempt < 5 && !warned; ++attempt) {
    gripper.publish(poseStamped("world", point(kNaN, kNaN, kNaN)));
    warned = diagnostics.waitForNext(msg, 3.0, warns);
  }
  EXPECT_TRUE(warned) << "no WARN status '" << name << "' on /diagnostics counting "
                      << state.stats.rejected_inputs << " rejected inputs";
}

}  // namespace

int main(int argc, char** argv) { return pbd_cloth_test::runTests(argc, argv, "bad_input_test"); }
