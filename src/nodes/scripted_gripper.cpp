// scripted_gripper: the robot of demo.launch. It folds the cloth of a running cloth_node corner to
// corner through the node's public interface only, as a user's robot would: ~<gripper>/pose
// messages at `rate` Hz, ~<gripper>/grasp to grasp and release, ~state to find the corners, ~reset
// to start over.
//
// The fold: the grasp corner is carried over the fold line (the perpendicular bisector, on the
// table, of the grasp corner and the target corner) on a half circle about that line, turning the
// gripper by the same angle about it, so the carried corner always stays at the distance the cloth
// allows and lands upside down, as a hand folds a towel. It is released `lift` above the cloth and
// drops onto the other half. Every motion is timed in simulated seconds (~state's sim_time), so the
// fold looks the same when the simulation runs slower than real time.
//
// Like a robot driver it also broadcasts its tool frame on tf (`tool_frame`, in the scene frame),
// which gives rviz the scene frame to display in.
//
// Parameters (private): simulator (cloth_node), gripper (hand), grasp_index (0), target_index (-1:
// the last cloth particle, the corner opposite particle 0), rate (30 Hz), approach_height (0.1 m),
// fold_duration (4 s), fold_reach (0.95: the carried corner lands this fraction of the way to the
// target corner), lift (0.1 m), settle (1 s), hold (3 s), repeat (true: reset and fold again),
// tool_frame (scripted_gripper).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <mutex>
#include <string>

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <ros/ros.h>
#include <std_srvs/SetBool.h>
#include <std_srvs/Trigger.h>
#include <tf2_ros/transform_broadcaster.h>
#include <Eigen/Geometry>

#include "pbd_cloth/ClothState.h"

namespace pbd_cloth {
namespace {

struct GripperPose {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
};

Eigen::Vector3d toEigen(const geometry_msgs::Point& p) { return {p.x, p.y, p.z}; }

// 0 -> 0, 1 -> 1 with zero speed at both ends: no jerk at the start and end of a motion.
double ease(double s) { return 0.5 * (1.0 - std::cos(M_PI * std::min(std::max(s, 0.0), 1.0))); }

}  // namespace

class ScriptedGripper {
 public:
  struct Config {
    std::string simulator = "cloth_node";
    std::string gripper = "hand";
    int grasp_index = 0;
    int target_index = -1;
    double rate = 30.0;
    double approach_height = 0.1;
    double fold_duration = 4.0;
    double fold_reach = 0.95;
    double lift = 0.1;
    double settle = 1.0;
    double hold = 3.0;
    bool repeat = true;
    std::string tool_frame = "scripted_gripper";
  };

  explicit ScriptedGripper(const Config& config) : config_(config) {
    ros::NodeHandle nh;
    const std::string sim = config_.simulator;
    state_sub_ = nh.subscribe(sim + "/state", 1, &ScriptedGripper::stateCallback, this);
    pose_pub_ = nh.advertise<geometry_msgs::PoseStamped>(sim + "/" + config_.gripper + "/pose", 10);
    grasp_service_ = nh.resolveName(sim + "/" + config_.gripper + "/grasp");
    reset_service_ = nh.resolveName(sim + "/reset");
  }

  // Folds until shutdown (or once, without `repeat`).
  void run() {
    if (!waitForSimulator()) return;
    do {
      if (!fold()) {
        ROS_WARN("scripted_gripper: this fold failed; starting over.");
      }
      if (config_.repeat && ros::ok()) {
        std_srvs::Trigger reset;
        if (!ros::service::call(reset_service_, reset)) {
          ROS_WARN("scripted_gripper: %s failed", reset_service_.c_str());
        }
        latest_pose_ = GripperPose();
      }
    } while (config_.repeat && ros::ok());
  }

 private:
  void stateCallback(const ClothStateConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    state_ = msg;
  }

  ClothStateConstPtr state() {
    std::lock_guard<std::mutex> lock(mutex_);
    return state_;
  }

  bool waitForSimulator() {
    ROS_INFO("scripted_gripper: waiting for %s and %s", state_sub_.getTopic().c_str(),
             grasp_service_.c_str());
    while (ros::ok() && (!state() || pose_pub_.getNumSubscribers() == 0)) {
      ros::WallDuration(0.1).sleep();
    }
    return ros::ok() && ros::service::waitForService(grasp_service_, -1) &&
           ros::service::waitForService(reset_service_, -1);
  }

  // Waits `seconds` of simulated time, publishing the last pose (a driver keeps streaming).
  void wait(double seconds) {
    move(seconds, [this](double) { return latest_pose_; });
  }

  // Publishes path(s) for s from 0 to 1 over `duration` simulated seconds at `rate` Hz.
  void move(double duration, const std::function<GripperPose(double)>& path) {
    ros::WallRate rate(config_.rate);
    const double start = state()->stats.sim_time;
    double elapsed = 0.0;
    while (ros::ok()) {
      const ClothStateConstPtr now = state();
      // A reset from elsewhere sends simulated time back: end the motion there.
      elapsed = now->stats.sim_time - start;
      const double s = duration > 0.0 ? std::min(std::max(elapsed / duration, 0.0), 1.0) : 1.0;
      publish(path(s), now->header.frame_id);
      if (s >= 1.0 || elapsed < 0.0) break;
      rate.sleep();
    }
  }

  void publish(const GripperPose& pose, const std::string& frame) {
    latest_pose_ = pose;
    geometry_msgs::PoseStamped msg;
    msg.header.stamp = ros::Time::now();
    msg.header.frame_id = frame;
    msg.pose.position.x = pose.position.x();
    msg.pose.position.y = pose.position.y();
    msg.pose.position.z = pose.position.z();
    msg.pose.orientation.x = pose.orientation.x();
    msg.pose.orientation.y = pose.orientation.y();
    msg.pose.orientation.z = pose.orientation.z();
    msg.pose.orientation.w = pose.orientation.w();
    pose_pub_.publish(msg);

    geometry_msgs::TransformStamped tool;
    tool.header = msg.header;
    tool.child_frame_id = config_.tool_frame;
    tool.transform.translation.x = msg.pose.position.x;
    tool.transform.translation.y = msg.pose.position.y;
    tool.transform.translation.z = msg.pose.position.z;
    tool.transform.rotation = msg.pose.orientation;
    tf_broadcaster_.sendTransform(tool);
  }

  bool callGrasp(bool grasp) {
    std_srvs::SetBool srv;
    srv.request.data = grasp;
    if (!ros::service::call(grasp_service_, srv)) {
      ROS_WARN("scripted_gripper: %s did not answer", grasp_service_.c_str());
      return false;
    }
    ROS_INFO("scripted_gripper: %s", srv.response.message.c_str());
    return srv.response.success;
  }

  bool fold() {
    wait(config_.settle);
    const ClothStateConstPtr start_state = state();
    const int count = static_cast<int>(start_state->positions.size());
    const int target = config_.target_index >= 0 ? config_.target_index : count - 1;
    if (config_.grasp_index < 0 || config_.grasp_index >= count || target >= count) {
      ROS_ERROR("scripted_gripper: grasp_index %d or target_index %d is not a particle (0..%d)",
                config_.grasp_index, target, count - 1);
      ros::shutdown();
      return false;
    }
    const Eigen::Vector3d corner = toEigen(start_state->positions[config_.grasp_index]);
    const Eigen::Vector3d goal = toEigen(start_state->positions[target]);

    // Down onto the corner from above, then grasp.
    GripperPose above;
    above.position = corner + Eigen::Vector3d(0.0, 0.0, config_.approach_height);
    publish(above, start_state->header.frame_id);
    wait(0.5);
    move(1.0, [&](double s) {
      GripperPose pose;
      pose.position = above.position + ease(s) * (corner - above.position);
      return pose;
    });
    wait(0.2);  // the node follows a pose over about one message period
    if (!callGrasp(true)) return false;

    // Over the fold line on a half circle about it (see the file comment).
    Eigen::Vector3d across = goal - corner;
    across.z() = 0.0;
    const double radius = 0.5 * across.norm();
    if (radius <= 0.0) return false;
    const Eigen::Vector3d direction = across / (2.0 * radius);
    const Eigen::Vector3d middle = corner + 0.5 * across;
    const Eigen::Vector3d axis = Eigen::Vector3d::UnitZ().cross(direction);
    move(config_.fold_duration, [&](double s) {
      const double eased = ease(s);
      const double angle = M_PI * eased;
      const double r = radius * (1.0 - (1.0 - config_.fold_reach) * eased);
      GripperPose pose;
      pose.position = middle - r * std::cos(angle) * direction +
                      Eigen::Vector3d(0.0, 0.0, config_.lift * eased + r * std::sin(angle));
      pose.orientation = Eigen::AngleAxisd(angle, axis);
      return pose;
    });
    wait(0.3);
    callGrasp(false);

    // Up and out of the way, then let the result be seen.
    const GripperPose released = latest_pose_;
    move(1.0, [&](double s) {
      GripperPose pose = released;
      pose.position.z() += 0.15 * ease(s);
      return pose;
    });
    wait(config_.hold);
    return true;
  }

  Config config_;
  ros::Subscriber state_sub_;
  ros::Publisher pose_pub_;
  tf2_ros::TransformBroadcaster tf_broadcaster_;
  std::string grasp_service_;
  std::string reset_service_;
  std::mutex mutex_;
  ClothStateConstPtr state_;
  GripperPose latest_pose_;  // the last pose published
};

}  // namespace pbd_cloth

int main(int argc, char** argv) {
  std::setvbuf(stdout, nullptr, _IOLBF, BUFSIZ);  // ROS_INFO lines show under roslaunch at once
  ros::init(argc, argv, "scripted_gripper");
  ros::NodeHandle nh_private("~");
  pbd_cloth::ScriptedGripper::Config config;
  nh_private.param("simulator", config.simulator, config.simulator);
  nh_private.param("gripper", config.gripper, config.gripper);
  nh_private.param("grasp_index", config.grasp_index, config.grasp_index);
  nh_private.param("target_index", config.target_index, config.target_index);
  nh_private.param("rate", config.rate, config.rate);
  nh_private.param("approach_height", config.approach_height, config.approach_height);
  nh_private.param("fold_duration", config.fold_duration, config.fold_duration);
  nh_private.param("fold_reach", config.fold_reach, config.fold_reach);
  nh_private.param("lift", config.lift, config.lift);
  nh_private.param("settle", config.settle, config.settle);
  nh_private.param("hold", config.hold, config.hold);
  nh_private.param("repeat", config.repeat, config.repeat);
  nh_private.param("tool_frame", config.tool_frame, config.tool_frame);
  // A bad setting stops start-up with the key and its allowed range.
  const auto check = [](bool ok, const char* key, const char* range, double value) {
    if (!ok) ROS_FATAL("scripted_gripper: ~%s must be %s, got %g", key, range, value);
    return ok;
  };
  if (!check(config.rate > 0.0, "rate", "> 0 (Hz)", config.rate) ||
      !check(config.fold_duration > 0.0, "fold_duration", "> 0 (s)", config.fold_duration) ||
      !check(config.fold_reach > 0.0 && config.fold_reach <= 1.0, "fold_reach", "in (0, 1]",
             config.fold_reach) ||
      !check(config.approach_height >= 0.0, "approach_height", ">= 0 (m)",
             config.approach_height) ||
      !check(config.lift >= 0.0, "lift", ">= 0 (m)", config.lift) ||
      !check(config.settle >= 0.0, "settle", ">= 0 (s)", config.settle) ||
      !check(config.hold >= 0.0, "hold", ">= 0 (s)", config.hold) ||
      !check(config.grasp_index >= 0, "grasp_index", ">= 0", config.grasp_index) ||
      !check(config.target_index >= -1, "target_index", ">= -1 (-1: the last particle)",
             config.target_index)) {
    return 1;
  }
  ros::AsyncSpinner spinner(1);  // fills the latest state while run() moves the gripper
  spinner.start();
  pbd_cloth::ScriptedGripper gripper(config);
  gripper.run();
  return 0;
}
