#include "pbd_cloth/ros/cloth_ros.h"

#include <visualization_msgs/MarkerArray.h>
#include <boost/make_shared.hpp>

#include "pbd_cloth/ClothState.h"
#include "pbd_cloth/metrics.h"
#include "pbd_cloth/ros/ros_conversions.h"
#include "pbd_cloth/ros/ros_params.h"

namespace pbd_cloth {

ClothRos::ClothRos(ros::NodeHandle nh, ros::NodeHandle nh_private)
    : nh_(nh), nh_private_(nh_private) {
  try {
    sim_ = std::make_unique<Simulation>(readSceneParameters(nh_private_));
  } catch (const ConfigError& error) {
    ROS_FATAL("Invalid scene parameter in %s: %s", nh_private_.getNamespace().c_str(),
              error.what());
    throw;
  }
  const SceneConfig& scene = sim_->scene();
  ROS_INFO(
      "Cloth %dx%d (%d particles, %d triangles), %s with %d substeps, stepping at %.0f Hz, "
      "publishing at %.0f Hz in frame '%s'.",
      scene.cloth.rows, scene.cloth.cols, sim_->particles().size(),
      sim_->topology().triangleCount(), toString(scene.solver.method), scene.solver.substeps,
      scene.step_rate, scene.publish_rate, scene.frame_id.c_str());

  state_pub_ = nh_private_.advertise<ClothState>("state", 1);
  markers_pub_ = nh_private_.advertise<visualization_msgs::MarkerArray>("markers", 1);
  reset_service_ = nh_private_.advertiseService("reset", &ClothRos::resetCallback, this);

  // roscpp never queues missed timer ticks: when a step overruns its period the next one simply
  // starts later, so the simulation slows down instead of trying to catch up.
  step_timer_ =
      nh_.createWallTimer(ros::WallDuration(1.0 / scene.step_rate), &ClothRos::stepCallback, this);
  publish_timer_ = nh_.createWallTimer(ros::WallDuration(1.0 / scene.publish_rate),
                                       &ClothRos::publishCallback, this);
}

void ClothRos::stepCallback(const ros::WallTimerEvent& /*event*/) {
  std::lock_guard<std::mutex> lock(mutex_);
  sim_->step();
  real_time_factor_.add(ros::WallTime::now().toSec(), sim_->time());

  const double period = 1.0 / sim_->scene().step_rate;
  if (sim_->stats().step_wall_time > period) {
    ROS_WARN_THROTTLE(10.0,
                      "A step takes %.1f ms, longer than its period of %.1f ms: the simulation "
                      "runs slower than real time (factor %.2f). Lower step_rate, "
                      "solver.substeps or the cloth size.",
                      1e3 * sim_->stats().step_wall_time, 1e3 * period, real_time_factor_.value());
  }
}

void ClothRos::publishCallback(const ros::WallTimerEvent& /*event*/) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!allFinite(sim_->particles())) {
    ROS_ERROR_THROTTLE(5.0, "The simulation diverged (non-finite positions); call %s to restart.",
                       reset_service_.getService().c_str());
  }
  publishState();
  publishMarkers();
}

bool ClothRos::resetCallback(std_srvs::Trigger::Request& /*request*/,
                             std_srvs::Trigger::Response& response) {
  std::lock_guard<std::mutex> lock(mutex_);
  sim_->reset();
  real_time_factor_.clear();  // simulated time jumps back: old samples would give a negative rate
  // Publish the initial state at once, so a client sees it before the next step moves it.
  publishState();
  response.success = true;
  response.message = "back to the initial state";
  return true;
}

void ClothRos::publishState() {
  if (state_pub_.getNumSubscribers() == 0) {
    return;
  }
  // A fresh message each time: a nodelet subscriber may still hold the previous one.
  const ClothStatePtr msg = boost::make_shared<ClothState>();
  msg->header.frame_id = sim_->scene().frame_id;
  msg->header.stamp = ros::Time::now();
  RosConversions::toStateMessage(*sim_, *msg);
  msg->stats.real_time_factor = real_time_factor_.value();
  msg->stats.rejected_inputs = rejected_inputs_;
  state_pub_.publish(msg);
}

void ClothRos::publishMarkers() {
  // The mesh is the largest message of the node: build it only for someone who looks.
  if (markers_pub_.getNumSubscribers() == 0) {
    return;
  }
  std_msgs::Header header;
  header.frame_id = sim_->scene().frame_id;
  header.stamp = ros::Time::now();
  const auto msg = boost::make_shared<visualization_msgs::MarkerArray>();
  RosConversions::toMarkerArray(*sim_, header, *msg);
  markers_pub_.publish(msg);
}

}  // namespace pbd_cloth
