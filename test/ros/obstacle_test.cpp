// Obstacles of cloth_node (obstacle.test, test/ros/interaction_scene.yaml): markers in their real
// shapes, and a ball moved through the hanging cloth by ~ball/pose that pushes it aside without any
// particle ending inside the ball.
#include <algorithm>
#include <cmath>
#include <string>

#include <gtest/gtest.h>
#include <ros/ros.h>
#include <visualization_msgs/MarkerArray.h>

#include "pbd_cloth/ClothState.h"
#include "ros_test_helpers.h"

namespace {

using pbd_cloth::ClothState;
using pbd_cloth_test::distance;
using pbd_cloth_test::node;
using pbd_cloth_test::point;
using pbd_cloth_test::PosePublisher;
using pbd_cloth_test::Recorder;
using pbd_cloth_test::StateRecorder;
using visualization_msgs::Marker;
using visualization_msgs::MarkerArray;

const Marker* findMarker(const MarkerArray& markers, const std::string& ns, int id) {
  for (const auto& marker : markers.markers) {
    if (marker.ns == ns && marker.id == id) return &marker;
  }
  return nullptr;
}

TEST(Obstacles, MarkersShowEachObstacleInItsShape) {
  // interaction_scene.yaml: ball (sphere r 0.1), post (capsule r 0.02, length 0.4), floor (z = 0),
  // grippers left (r 0.06) and follower (r 0.03).
  Recorder<MarkerArray> markers(node() + "/markers");
  MarkerArray msg;
  ASSERT_TRUE(markers.waitForNext(msg, 10.0));

  const Marker* ball = findMarker(msg, "obstacles", 0);
  ASSERT_NE(ball, nullptr);
  EXPECT_EQ(ball->type, Marker::SPHERE);
  EXPECT_NEAR(ball->scale.x, 0.2, 1e-9);

  const Marker* post = findMarker(msg, "obstacles", 3);
  const Marker* post_top = findMarker(msg, "obstacles", 4);
  const Marker* post_bottom = findMarker(msg, "obstacles", 5);
  ASSERT_TRUE(post && post_top && post_bottom);
  EXPECT_EQ(post->type, Marker::CYLINDER);
  EXPECT_NEAR(post->scale.x, 0.04, 1e-9);
  EXPECT_NEAR(post->scale.z, 0.4, 1e-9) << "cylinder length = distance between the end spheres";
  EXPECT_EQ(post_top->type, Marker::SPHERE);
  EXPECT_NEAR(post_top->scale.x, 0.04, 1e-9);
  EXPECT_NEAR(post_top->pose.position.z, 0.5 + 0.2, 1e-9);
  EXPECT_NEAR(post_bottom->pose.position.z, 0.5 - 0.2, 1e-9);

  const Marker* floor = findMarker(msg, "obstacles", 6);
  ASSERT_NE(floor, nullptr);
  EXPECT_EQ(floor->type, Marker::CUBE);
  EXPECT_GT(floor->scale.x, 1.0);
  EXPECT_LT(floor->scale.z, 0.01);
  EXPECT_NEAR(floor->pose.position.z + 0.5 * floor->scale.z, 0.0, 1e-9) << "top face on the plane";

  for (int g = 0; g < 2; ++g) {
    const Marker* gripper = findMarker(msg, "grippers", g);
    ASSERT_NE(gripper, nullptr) << "gripper " << g;
    EXPECT_EQ(gripper->type, Marker::SPHERE);
    EXPECT_NEAR(gripper->scale.x, g == 0 ? 0.12 : 0.06, 1e-9) << "diameter = 2 grasp radii";
  }
  for (const auto& marker : msg.markers) {
    const auto& q = marker.pose.orientation;
    EXPECT_NEAR(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w, 1.0, 1e-9)
        << marker.ns << " " << marker.id;
  }
}

TEST(Obstacles, AMovingBallPushesTheClothAndNoParticleEndsInside) {
  StateRecorder states(node() + "/state");
  Recorder<MarkerArray> markers(node() + "/markers");
  PosePublisher ball(node() + "/ball/pose");
  ASSERT_TRUE(ball.waitForSubscriber());
  ClothState state;
  ASSERT_TRUE(pbd_cloth_test::resetAndReceiveInitialState(node(), states, state));
  XmlRpc::XmlRpcValue obstacles;
  ASSERT_TRUE(ros::NodeHandle(node()).getParam("obstacles", obstacles));
  ASSERT_EQ(static_cast<std::string>(obstacles[0]["name"]), "ball");
  const double radius = obstacles[0]["radius"];

  // Through the cloth plane (y = 0) at its middle, 0.75 m/s, streamed at 30 Hz.
  const geometry_msgs::Point from = point(0.225, -0.5, 0.75);
  const geometry_msgs::Point to = point(0.225, 0.25, 0.75);
  ball.stream("world", from, to, 1.0);
  MarkerArray msg;
  ASSERT_TRUE(markers.waitForNext(msg, 5.0, [&](const MarkerArray& m) {
    const Marker* marker = findMarker(m, "obstacles", 0);
    return marker != nullptr && distance(marker->pose.position, to) < 1e-9;
  })) << "the ball did not arrive";
  // A few steps more at rest, then the state.
  ASSERT_TRUE(states.waitForNext(state, 5.0));
  ASSERT_TRUE(states.waitForNext(state, 5.0));
  ASSERT_TRUE(pbd_cloth_test::allFinite(state));

  double furthest = -1e9;
  for (std::size_t i = 0; i < state.positions.size(); ++i) {
    furthest = std::max(furthest, state.positions[i].y);
    EXPECT_GE(distance(state.positions[i], to), radius) << "particle " << i << " inside the ball";
  }
  EXPECT_GT(furthest, 0.1) << "the ball did not push the cloth";
}

}  // namespace

int main(int argc, char** argv) { return pbd_cloth_test::runTests(argc, argv, "obstacle_test"); }
