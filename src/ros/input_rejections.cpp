#include "pbd_cloth/ros/input_rejections.h"

#include <ros/console.h>
#include <ros/time.h>

namespace pbd_cloth {

const char* toString(RejectReason reason) {
  switch (reason) {
    case RejectReason::kNonFinite:
      return "non-finite value";
    case RejectReason::kZeroQuaternion:
      return "zero quaternion";
    case RejectReason::kOutOfOrder:
      return "older than the last message";
    case RejectReason::kUnknownFrame:
      return "unknown frame";
    case RejectReason::kTfFailure:
      return "tf lookup failed";
    case RejectReason::kUnknownGripper:
      return "unknown gripper";
    case RejectReason::kBadValue:
      return "invalid value";
    case RejectReason::kClockJump:
      return "clock went back";
    case RejectReason::kFarFromOrigin:
      return "far from the origin";
  }
  return "unknown reason";
}

namespace {

// What the node does about a rejected input, for the warning.
const char* consequence(RejectReason reason) {
  return reason == RejectReason::kClockJump
             ? "the simulation restarts from its initial state at the new time"
             : "the simulation goes on with the last good input";
}

}  // namespace

void InputRejections::reject(const std::string& topic, RejectReason reason,
                             const std::string& detail) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++total_;
  ++counts_[reason];
  last_ = topic + ": " + toString(reason) + ": " + detail;

  Throttle& throttle = throttles_[{topic, reason}];
  const double now = ros::WallTime::now().toSec();
  if (now - throttle.last_warning < warn_period_) {
    ++throttle.suppressed;
    return;
  }
  if (throttle.suppressed > 0) {
    ROS_WARN("Rejected input on %s (%s): %s (and %u more like it since the last warning); %s.",
             topic.c_str(), toString(reason), detail.c_str(), throttle.suppressed,
             consequence(reason));
  } else {
    ROS_WARN("Rejected input on %s (%s): %s; %s.", topic.c_str(), toString(reason), detail.c_str(),
             consequence(reason));
  }
  throttle.last_warning = now;
  throttle.suppressed = 0;
}

std::uint32_t InputRejections::total() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return total_;
}

std::map<RejectReason, std::uint32_t> InputRejections::countsByReason() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return counts_;
}

std::string InputRejections::last() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return last_;
}

}  // namespace pbd_cloth
