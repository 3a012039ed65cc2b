// Grippers of cloth_node (gripper.test, test/ros/interaction_scene.yaml): grasp a corner through
// ~left/grasp, move it by poses on ~left/pose, read the pull on ~left/wrench, release it; poses in
// another tf frame; a gripper that follows a tf frame; grasping through ~grasp_by_name.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <string>
#include <vector>

#include <diagnostic_msgs/KeyValue.h>
#include <geometry_msgs/TransformStamped.h>
#include <geometry_msgs/WrenchStamped.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_broadcaster.h>
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

// The bottom-left corner (row 9, column 0) of the 10 x 10 cloth, hanging free.
constexpr int kCorner = 90;
constexpr int kOtherCorner = 99;

// Indices in `state.kinematic` that are not pinned by the scene: the grasped particles.
std::vector<unsigned> grasped(const ClothState& state) {
  std::vector<int> pinned;
  ros::NodeHandle(node()).getParam("cloth/pinned", pinned);
  std::vector<unsigned> out;
  for (unsigned i : state.kinematic) {
    if (std::find(pinned.begin(), pinned.end(), static_cast<int>(i)) == pinned.end()) {
      out.push_back(i);
    }
  }
  return out;
}

// The `id`-th marker of namespace `ns`, or nullptr.
const visualization_msgs::Marker* findMarker(const visualization_msgs::MarkerArray& markers,
                                             const std::string& ns, int id) {
  for (const auto& marker : markers.markers) {
    if (marker.ns == ns && marker.id == id) return &marker;
  }
  return nullptr;
}

// Waits until the gripper's marker sits at `position` (the follower has arrived).
bool waitForGripperAt(Recorder<visualization_msgs::MarkerArray>& markers, int gripper,
                      const geometry_msgs::Point& position, double tolerance = 1e-6,
                      double timeout = 5.0) {
  visualization_msgs::MarkerArray msg;
  return markers.waitForNext(msg, timeout, [&](const visualization_msgs::MarkerArray& m) {
    const auto* marker = findMarker(m, "grippers", gripper);
    return marker != nullptr && distance(marker->pose.position, position) < tolerance;
  });
}

TEST(Gripper, GraspedParticlesFollowWithinAMillimetreAndFallWhenReleased) {
  StateRecorder states(node() + "/state");
  Recorder<visualization_msgs::MarkerArray> markers(node() + "/markers");
  Recorder<geometry_msgs::WrenchStamped> wrenches(node() + "/left/wrench");
  PosePublisher gripper(node() + "/left/pose");
  ASSERT_TRUE(gripper.waitForSubscriber());
  ClothState state;
  ASSERT_TRUE(pbd_cloth_test::resetAndReceiveInitialState(node(), states, state));
  // Let the cloth settle a little, then put the gripper on the free corner.
  ASSERT_TRUE(
      states.waitForNext(state, 10.0, [](const ClothState& s) { return s.stats.sim_time > 0.5; }));
  const geometry_msgs::Point start = state.positions[kCorner];
  gripper.publish(pbd_cloth_test::poseStamped("world", start));
  ASSERT_TRUE(waitForGripperAt(markers, 0, start));

  std_srvs::SetBool::Response response;
  ASSERT_TRUE(pbd_cloth_test::callGrasp(node() + "/left/grasp", true, &response))
      << response.message;
  ASSERT_TRUE(states.waitForNext(state, 5.0, [](const ClothState& s) {
    return std::count(s.kinematic.begin(), s.kinematic.end(), kCorner) > 0;
  }));
  const std::vector<unsigned> held = grasped(state);
  ASSERT_GE(held.size(), 1u);
  std::vector<geometry_msgs::Point> held_start;
  for (unsigned i : held) held_start.push_back(state.positions[i]);

  // 0.2 m up in one second, streamed at 30 Hz like a robot driver (the node steps at 120 Hz).
  const geometry_msgs::Point end = point(start.x, start.y, start.z + 0.2);
  gripper.stream("world", start, end, 1.0);
  ASSERT_TRUE(waitForGripperAt(markers, 0, end));
  ASSERT_TRUE(states.waitForNext(state, 5.0));
  for (std::size_t k = 0; k < held.size(); ++k) {
    const geometry_msgs::Point expected =
        point(held_start[k].x, held_start[k].y, held_start[k].z + 0.2);
    EXPECT_LT(distance(state.positions[held[k]], expected), 1e-3) << "particle " << held[k];
  }

  // The cloth pulls the gripper down. Its size here is not the weight of a part of the cloth: the
  // held corner clamps the bending cloth, whose hinges push back much harder than it weighs (the
  // pins take the opposite). gripper_wrench.test checks the size against a cloth that hangs from
  // a gripper alone.
  geometry_msgs::WrenchStamped wrench;
  ASSERT_TRUE(wrenches.waitForNext(wrench, 5.0));
  EXPECT_EQ(wrench.header.frame_id, "world");
  const geometry_msgs::Vector3& force = wrench.wrench.force;
  ASSERT_TRUE(std::isfinite(force.x) && std::isfinite(force.y) && std::isfinite(force.z));
  double mass = 0.0;
  ASSERT_TRUE(ros::NodeHandle(node()).getParam("cloth/mass", mass));
  EXPECT_LT(force.z, -0.01 * mass * 9.81) << "the cloth does not pull the gripper down";

  ASSERT_TRUE(pbd_cloth_test::callGrasp(node() + "/left/grasp", false, &response))
      << response.message;
  const std::size_t released_at = states.count();
  const double release_time = state.stats.sim_time;
  ASSERT_TRUE(states.waitForNext(state, 10.0, [&](const ClothState& s) {
    return grasped(s).empty() && s.stats.sim_time > release_time + 1.0;
  }));
  double lowest = end.z;
  for (const ClothState& s : states.since(released_at)) {
    lowest = std::min(lowest, s.positions[kCorner].z);
    ASSERT_TRUE(pbd_cloth_test::allFinite(s));
  }
  EXPECT_LT(lowest, end.z - 0.1) << "the released corner did not fall";
}

TEST(Gripper, GraspWithNothingInReachFailsWithAReason) {
  StateRecorder states(node() + "/state");
  Recorder<visualization_msgs::MarkerArray> markers(node() + "/markers");
  PosePublisher gripper(node() + "/left/pose");
  ASSERT_TRUE(gripper.waitForSubscriber());
  ClothState before;
  ASSERT_TRUE(pbd_cloth_test::resetAndReceiveInitialState(node(), states, before));
  const geometry_msgs::Point away = point(0.225, -0.6, 0.3);
  gripper.publish(pbd_cloth_test::poseStamped("world", away));
  ASSERT_TRUE(waitForGripperAt(markers, 0, away));

  std_srvs::SetBool::Response response;
  EXPECT_FALSE(pbd_cloth_test::callGrasp(node() + "/left/grasp", true, &response));
  EXPECT_FALSE(response.message.empty());
  ClothState after;
  ASSERT_TRUE(states.waitForNext(after, 5.0));
  EXPECT_TRUE(grasped(after).empty());
  // A valid request that found nothing is answered, not counted as a bad input.
  EXPECT_EQ(after.stats.rejected_inputs, before.stats.rejected_inputs);
}

TEST(Gripper, PoseInAnotherFrameIsTransformedIntoTheSceneFrame) {
  // The frame `offset`: at (0.5, 0, 0.3) in world, turned 90 degrees about z.
  tf2_ros::StaticTransformBroadcaster broadcaster;
  geometry_msgs::TransformStamped offset;
  offset.header.stamp = ros::Time::now();
  offset.header.frame_id = "world";
  offset.child_frame_id = "offset";
  offset.transform.translation.x = 0.5;
  offset.transform.translation.z = 0.3;
  offset.transform.rotation.z = std::sqrt(0.5);
  offset.transform.rotation.w = std::sqrt(0.5);
  broadcaster.sendTransform(offset);
  Recorder<visualization_msgs::MarkerArray> markers(node() + "/markers");
  PosePublisher gripper(node() + "/left/pose");
  ASSERT_TRUE(gripper.waitForSubscriber());
  ASSERT_TRUE(pbd_cloth_test::callReset(node()));
  // Stamp 0: the latest transform. The node waits up to ~tf_timeout for it; on a loaded machine
  // the static transform may take longer to arrive, so the pose is repeated until it is taken.
  geometry_msgs::PoseStamped msg = pbd_cloth_test::poseStamped("offset", point(0.1, 0.0, 0.0));
  msg.header.stamp = ros::Time();
  const geometry_msgs::Point expected = point(0.5, 0.1, 0.3);
  bool arrived = false;
  for (int attempt = 0; attempt < 10 && !arrived; ++attempt) {
    gripper.publish(msg);
    arrived = waitForGripperAt(markers, 0, expected, 1e-6, 1.0);
  }
  ASSERT_TRUE(arrived) << "the gripper did not arrive at the transformed pose";
  visualization_msgs::MarkerArray array;
  ASSERT_TRUE(markers.waitForNext(array, 5.0));
  const auto* marker = findMarker(array, "grippers", 0);
  ASSERT_NE(marker, nullptr);
  // Yaw 90 degrees: (x, y, z, w) = (0, 0, sin 45, cos 45).
  EXPECT_NEAR(std::abs(marker->pose.orientation.z), std::sqrt(0.5), 1e-6);
  EXPECT_NEAR(std::abs(marker->pose.orientation.w), std::sqrt(0.5), 1e-6);
}

TEST(Gripper, FollowsItsTfFrameAndCarriesWhatItHolds) {
  StateRecorder states(node() + "/state");
  Recorder<visualization_msgs::MarkerArray> markers(node() + "/markers");
  ClothState state;
  ASSERT_TRUE(pbd_cloth_test::resetAndReceiveInitialState(node(), states, state));
  ASSERT_TRUE(
      states.waitForNext(state, 10.0, [](const ClothState& s) { return s.stats.sim_time > 0.3; }));
  const geometry_msgs::Point corner = state.positions[kOtherCorner];

  // A robot driver's tf at 30 Hz: world -> hand at `where`.
  tf2_ros::TransformBroadcaster broadcaster;
  const auto broadcast = [&broadcaster](const geometry_msgs::Point& where, double seconds) {
    const int count = static_cast<int>(std::ceil(seconds * 30.0));
    for (int k = 0; k < count && ros::ok(); ++k) {
      geometry_msgs::TransformStamped transform;
      transform.header.stamp = ros::Time::now();
      transform.header.frame_id = "world";
      transform.child_frame_id = "hand";
      transform.transform.translation.x = where.x;
      transform.transform.translation.y = where.y;
      transform.transform.translation.z = where.z;
      transform.transform.rotation.w = 1.0;
      broadcaster.sendTransform(transform);
      ros::WallDuration(1.0 / 30.0).sleep();
    }
  };
  broadcast(corner, 1.0);
  ASSERT_TRUE(waitForGripperAt(markers, 1, corner, 1e-6, 1.0));
  ASSERT_TRUE(pbd_cloth_test::callGrasp(node() + "/follower/grasp", true));
  ASSERT_TRUE(states.waitForNext(state, 5.0, [](const ClothState& s) {
    return std::count(s.kinematic.begin(), s.kinematic.end(), kOtherCorner) > 0;
  }));
  const geometry_msgs::Point held_start = state.positions[kOtherCorner];

  const geometry_msgs::Point raised = point(corner.x, corner.y + 0.05, corner.z + 0.1);
  broadcast(raised, 1.0);
  ASSERT_TRUE(waitForGripperAt(markers, 1, raised, 1e-6, 1.0));
  ASSERT_TRUE(states.waitForNext(state, 5.0));
  EXPECT_LT(distance(state.positions[kOtherCorner],
                     point(held_start.x, held_start.y + 0.05, held_start.z + 0.1)),
            1e-3);
  EXPECT_TRUE(pbd_cloth_test::callGrasp(node() + "/follower/grasp", false));
}

// A frame broadcast about once a step (100 Hz; the node steps at 120 Hz), as robot_state_publisher
// does for a robot's links, moving at 0.2 m/s: the gripper keeps up, a sample period or two
// behind. Measured here: 6-9 mm with tf samples timed by their stamps, 13 mm when they were timed
// by the poll that saw them (every step bringing a new sample then left the gripper where it was;
// in the robot demo, 50 Hz tf at 60 Hz steps under load, the hand missed its grasp). The bound
// guards against that kind of lag with room for a loaded machine.
TEST(Gripper, KeepsUpWithAFrameBroadcastAboutOnceAStep) {
  StateRecorder states(node() + "/state");
  Recorder<visualization_msgs::MarkerArray> markers(node() + "/markers");
  ClothState state;
  ASSERT_TRUE(pbd_cloth_test::resetAndReceiveInitialState(node(), states, state));
  const geometry_msgs::Point start = point(0.5, 0.5, 1.5);  // clear of the cloth
  const double speed = 0.2, rate = 100.0;
  tf2_ros::TransformBroadcaster broadcaster;
  const auto send = [&broadcaster](double x, double y, double z) {
    geometry_msgs::TransformStamped transform;
    transform.header.stamp = ros::Time::now();
    transform.header.frame_id = "world";
    transform.child_frame_id = "hand";
    transform.transform.translation.x = x;
    transform.transform.translation.y = y;
    transform.transform.translation.z = z;
    transform.transform.rotation.w = 1.0;
    broadcaster.sendTransform(transform);
  };
  for (int k = 0; k < 30; ++k) {
    send(start.x, start.y, start.z);
    ros::WallDuration(1.0 / rate).sleep();
  }
  ASSERT_TRUE(waitForGripperAt(markers, 1, start, 1e-6, 2.0));
  const std::size_t first = markers.count();
  const ros::Time t0 = ros::Time::now();
  while (ros::ok() && (ros::Time::now() - t0).toSec() < 1.5) {
    send(start.x + speed * (ros::Time::now() - t0).toSec(), start.y, start.z);
    ros::WallDuration(1.0 / rate).sleep();
  }
  double worst = 0.0;
  int checked = 0;
  for (const auto& msg : markers.since(first)) {
    const auto* marker = findMarker(msg, "grippers", 1);
    if (marker == nullptr) continue;
    const double t = (marker->header.stamp - t0).toSec();
    if (t < 0.5 || t > 1.4) continue;  // the motion under way, not its start or end
    worst = std::max(worst, std::abs(start.x + speed * t - marker->pose.position.x));
    ++checked;
  }
  std::printf("[ measured ] gripper behind its 100 Hz frame by at most %.4f m (%d markers)\n",
              worst, checked);
  EXPECT_GE(checked, 10);
  // One 10 ms sample period of motion is 2 mm; allow a step or two more and the machine's jitter.
  // Built with AddressSanitizer (scripts/run_sanitizers) the node, the broadcaster and tf run
  // several times slower, and samples arrive later: 15.3 mm there on a fresh clone's CI run
  // (2026-11-26), 6-9 mm in the normal build, which keeps the bound this test is for.
#if defined(__SANITIZE_ADDRESS__)
  constexpr double kLagBound = 0.03;
#else
  constexpr double kLagBound = 0.015;
#endif
  EXPECT_LT(worst, kLagBound) << "the gripper lags its frame by up to " << worst << " m";
}

TEST(Gripper, GraspByNameGraspsAndReleases) {
  StateRecorder states(node() + "/state");
  Recorder<visualization_msgs::MarkerArray> markers(node() + "/markers");
  PosePublisher gripper(node() + "/left/pose");
  ros::NodeHandle nh;
  ros::Publisher grasp_by_name =
      nh.advertise<diagnostic_msgs::KeyValue>(node() + "/grasp_by_name", 10);
  ASSERT_TRUE(gripper.waitForSubscriber());
  ClothState state;
  ASSERT_TRUE(pbd_cloth_test::resetAndReceiveInitialState(node(), states, state));
  const geometry_msgs::Point corner = state.positions[kCorner];
  // The tests before this one broadcast `hand` and stopped: ~body_tf_timeout (0.5 s) after their
  // last transform the node counts that outage once. Let it be counted before taking the count.
  ros::WallDuration(1.0).sleep();
  ASSERT_TRUE(states.waitForNext(state, 5.0));
  const unsigned rejected_before = state.stats.rejected_inputs;
  gripper.publish(pbd_cloth_test::poseStamped("world", corner));
  ASSERT_TRUE(waitForGripperAt(markers, 0, corner));
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(10.0);
  while (grasp_by_name.getNumSubscribers() == 0 && ros::WallTime::now() < deadline) {
    ros::WallDuration(0.01).sleep();
  }

  diagnostic_msgs::KeyValue command;
  command.key = "left";
  command.value = "true";
  grasp_by_name.publish(command);
  EXPECT_TRUE(states.waitForNext(state, 5.0, [](const ClothState& s) {
    return std::count(s.kinematic.begin(), s.kinematic.end(), kCorner) > 0;
  })) << "~grasp_by_name {left, true} did not grasp the corner";
  command.value = "release";
  grasp_by_name.publish(command);
  EXPECT_TRUE(states.waitForNext(state, 5.0, [](const ClothState& s) {
    return grasped(s).empty();
  })) << "~grasp_by_name {left, release} did not release it";
  EXPECT_EQ(state.stats.rejected_inputs, rejected_before);
}

}  // namespace

int main(int argc, char** argv) { return pbd_cloth_test::runTests(argc, argv, "gripper_test"); }
