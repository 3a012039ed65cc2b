// Checks an incoming pose and brings it into the scene frame with tf2. The node owns one
// tf2_ros::Buffer and TransformListener (robot_localization's pattern); this class only reads it.
#pragma once

#include <string>

#include <geometry_msgs/Pose.h>
#include <geometry_msgs/PoseStamped.h>
#include <ros/duration.h>
#include <ros/time.h>
#include <tf2_ros/buffer.h>

#include "pbd_cloth/config/scene_config.h"
#include "pbd_cloth/ros/input_rejections.h"

namespace pbd_cloth {

class PoseTransformer {
 public:
  struct Config {
    std::string frame_id = "world";  // the scene frame every pose is brought into
    double timeout = 0.1;            // wall s: how long a lookup waits for a transform to arrive
  };

  // Why a pose was refused, for InputRejections.
  struct Failure {
    RejectReason reason = RejectReason::kBadValue;
    std::string detail;
  };

  PoseTransformer(const tf2_ros::Buffer& buffer, const Config& config)
      : buffer_(buffer), config_(config) {}

  // The pose in the scene frame, or false with the reason. Refuses NaN/Inf and a (near) zero
  // quaternion; normalises any other. The header's frame may be empty (= the scene frame, as
  // `rostopic pub` leaves it) and may carry ROS 1's leading '/'. Stamp 0 means "the latest
  // transform". May wait up to `timeout` for tf: call it off the simulation thread.
  bool toSceneFrame(const geometry_msgs::PoseStamped& msg, Pose& pose, Failure& failure) const;

  // The latest pose of tf frame `frame` in the scene frame and its stamp, without waiting (polled
  // every step).
  bool lookupFrame(const std::string& frame, Pose& pose, ros::Time& stamp, Failure& failure) const;

  // Only the checks that need no tf.
  static bool checkPose(const geometry_msgs::Pose& msg, Failure& failure);

  const Config& config() const { return config_; }

 private:
  const tf2_ros::Buffer& buffer_;
  Config config_;
};

}  // namespace pbd_cloth
