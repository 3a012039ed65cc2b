// The node's record of refused inputs (a NaN pose, an unknown frame, a grasp on an unknown gripper,
// a reconfigure value the scene validation refuses, ...): counted for ~state.stats.rejected_inputs
// and the diagnostics, and warned about at most once per `warn_period` per topic and reason.
//
// Why not ROS_WARN_THROTTLE: it throttles per call site, so a stream of bad poses on one topic
// would hide the first bad pose on another. Here each (topic, reason) pair has its own throttle.
#pragma once

#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <utility>

namespace pbd_cloth {

enum class RejectReason {
  kNonFinite,       // NaN or Inf in a position or orientation
  kZeroQuaternion,  // an orientation of (near) zero length has no rotation to normalise to
  kOutOfOrder,      // stamped before the last accepted message on the same topic
  kUnknownFrame,    // a frame tf has never heard of
  kTfFailure,       // the frame exists but no transform arrived within the timeout
  kUnknownGripper,  // ~grasp_by_name names a gripper the scene does not have
  kBadValue,        // a value that cannot be parsed or that the scene validation refuses
  kClockJump,       // ROS time (/clock) went back, e.g. a looping rosbag: the node reset itself
  kFarFromOrigin,   // a pose beyond kMaxPoseCoordinate (simulation.h) of the scene origin
};

const char* toString(RejectReason reason);

class InputRejections {
 public:
  explicit InputRejections(double warn_period = 5.0) : warn_period_(warn_period) {}

  // Counts one refused input and warns (throttled) naming the topic and why.
  void reject(const std::string& topic, RejectReason reason, const std::string& detail);

  std::uint32_t total() const;
  std::map<RejectReason, std::uint32_t> countsByReason() const;
  // "<topic>: <reason>: <detail>" of the latest rejection, empty when there was none.
  std::string last() const;

 private:
  double warn_period_;
  mutable std::mutex mutex_;  // rejections come from the input thread and the main thread
  std::uint32_t total_ = 0;
  std::map<RejectReason, std::uint32_t> counts_;
  std::string last_;
  // Per (topic, reason): wall time of the last warning and rejections since then.
  struct Throttle {
    double last_warning = -1e300;
    std::uint32_t suppressed = 0;
  };
  std::map<std::pair<std::string, RejectReason>, Throttle> throttles_;
};

}  // namespace pbd_cloth
