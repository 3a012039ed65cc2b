#include "pbd_cloth/ros/pose_transformer.h"

#include "pbd_cloth/sim/simulation.h"

#include <cmath>
#include <sstream>

#include <tf2/exceptions.h>
#include <tf2_eigen/tf2_eigen.h>

#include "pbd_cloth/ros/ros_conversions.h"

namespace pbd_cloth {
namespace {

// Below this length a quaternion is taken for the all-zero default of an unset message field; any
// longer one has a direction and is normalised.
constexpr double kMinQuaternionNorm = 1e-6;

// tf2 refuses ROS 1's leading '/', a habit in hand-written messages; it names the same frame.
std::string tf2FrameName(const std::string& frame) {
  return !frame.empty() && frame.front() == '/' ? frame.substr(1) : frame;
}

Pose poseFromTransform(const geometry_msgs::TransformStamped& transform) {
  const Eigen::Isometry3d isometry = tf2::transformToEigen(transform);
  Pose pose;
  pose.position = isometry.translation();
  pose.orientation = Eigen::Quaterniond(isometry.rotation()).normalized();
  return pose;
}

// The pose in the scene frame, as the simulation will take it (simulation.h poseProblem): a
// transform may turn a finite message into Inf, or carry it 10 km away.
bool checkScenePose(const Pose& pose, const std::string& frame, PoseTransformer::Failure& failure) {
  if (!pose.position.allFinite() || !pose.orientation.coeffs().allFinite()) {
    failure = {RejectReason::kNonFinite, "the transform from '" + frame + "' is not finite"};
    return false;
  }
  const std::string problem = poseProblem(pose);
  if (!problem.empty()) {
    std::ostringstream detail;
    detail << "in the scene frame the pose (from '" << frame << "') is at (" << pose.position.x()
           << ", " << pose.position.y() << ", " << pose.position.z() << "): " << problem;
    failure = {RejectReason::kFarFromOrigin, detail.str()};
    return false;
  }
  return true;
}

}  // namespace

bool PoseTransformer::checkPose(const geometry_msgs::Pose& msg, Failure& failure) {
  const auto& p = msg.position;
  const auto& q = msg.orientation;
  if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z) || !std::isfinite(q.x) ||
      !std::isfinite(q.y) || !std::isfinite(q.z) || !std::isfinite(q.w)) {
    std::ostringstream detail;
    detail << "position (" << p.x << ", " << p.y << ", " << p.z << "), orientation (" << q.x << ", "
           << q.y << ", " << q.z << ", " << q.w << ")";
    failure = {RejectReason::kNonFinite, detail.str()};
    return false;
  }
  if (std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w) < kMinQuaternionNorm) {
    failure = {RejectReason::kZeroQuaternion,
               "orientation (x y z w) is all zeros; identity is (0, 0, 0, 1)"};
    return false;
  }
  return true;
}

bool PoseTransformer::toSceneFrame(const geometry_msgs::PoseStamped& msg, Pose& pose,
                                   Failure& failure) const {
  if (!checkPose(msg.pose, failure)) {
    return false;
  }
  const Pose local = RosConversions::fromPoseMessage(msg.pose);
  const std::string frame = tf2FrameName(msg.header.frame_id);
  if (frame.empty() || frame == config_.frame_id) {
    pose = local;
    return checkScenePose(pose, config_.frame_id, failure);
  }

  // Waited for in wall time, not with canTransform's own timeout: that one counts and sleeps in
  // ROS time, so under /use_sim_time with /clock paused (a paused bag) it would never return and
  // the input thread would hang. The wait is for tf messages to arrive, a wall-time matter.
  std::string error;
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(config_.timeout);
  bool available = buffer_.canTransform(config_.frame_id, frame, msg.header.stamp, &error);
  while (!available && ros::WallTime::now() < deadline) {
    ros::WallDuration(0.005).sleep();
    error.clear();
    available = buffer_.canTransform(config_.frame_id, frame, msg.header.stamp, &error);
  }
  if (!available) {
    std::ostringstream detail;
    if (!buffer_._frameExists(frame)) {
      detail << "tf has no frame '" << frame << "' (waited " << config_.timeout << " s)";
      failure = {RejectReason::kUnknownFrame, detail.str()};
    } else {
      detail << "no transform '" << frame << "' -> '" << config_.frame_id << "' at stamp "
             << msg.header.stamp << " within " << config_.timeout << " s: " << error;
      failure = {RejectReason::kTfFailure, detail.str()};
    }
    return false;
  }
  try {
    pose = poseFromTransform(buffer_.lookupTransform(config_.frame_id, frame, msg.header.stamp))
               .compose(local);
  } catch (const tf2::TransformException& exception) {
    // canTransform said yes, but the cache may have moved on since (a stamp at its old edge).
    failure = {RejectReason::kTfFailure, exception.what()};
    return false;
  }
  return checkScenePose(pose, frame, failure);
}

bool PoseTransformer::lookupFrame(const std::string& frame, Pose& pose, ros::Time& stamp,
                                  Failure& failure) const {
  const std::string name = tf2FrameName(frame);
  try {
    const geometry_msgs::TransformStamped transform =
        buffer_.lookupTransform(config_.frame_id, name, ros::Time(0));
    pose = poseFromTransform(transform);
    stamp = transform.header.stamp;
  } catch (const tf2::TransformException& exception) {
    failure = {buffer_._frameExists(name) ? RejectReason::kTfFailure : RejectReason::kUnknownFrame,
               exception.what()};
    return false;
  }
  return checkScenePose(pose, name, failure);
}

}  // namespace pbd_cloth
