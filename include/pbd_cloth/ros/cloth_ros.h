// The ROS side of the simulator: reads the scene from the private namespace, steps a Simulation on
// a wall timer, publishes ~state and ~markers and serves ~reset. cloth_node and ClothNodelet both
// build this one class, so the two entry points cannot drift apart.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>

#include <ros/ros.h>
#include <std_srvs/Trigger.h>

#include "pbd_cloth/ros/real_time_factor.h"
#include "pbd_cloth/simulation.h"

namespace pbd_cloth {

class ClothRos {
 public:
  // Reads and validates the scene, builds the simulation and starts the timers. On an invalid
  // scene it logs ROS_FATAL naming the key and its allowed range and rethrows the ConfigError, so
  // the caller can exit non-zero instead of simulating something the user did not ask for.
  ClothRos(ros::NodeHandle nh, ros::NodeHandle nh_private);

  ClothRos(const ClothRos&) = delete;
  ClothRos& operator=(const ClothRos&) = delete;

 private:
  void stepCallback(const ros::WallTimerEvent& event);
  void publishCallback(const ros::WallTimerEvent& event);
  bool resetCallback(std_srvs::Trigger::Request& request, std_srvs::Trigger::Response& response);

  // Both expect mutex_ held.
  void publishState();
  void publishMarkers();

  ros::NodeHandle nh_;
  ros::NodeHandle nh_private_;

  // Guards everything below. The node spins one thread, but a nodelet manager or later inputs
  // (gripper poses, tf, dynamic_reconfigure) may call in from other threads.
  std::mutex mutex_;
  std::unique_ptr<Simulation> sim_;
  RealTimeFactor real_time_factor_;
  std::uint32_t rejected_inputs_ = 0;  // inputs refused since start (bad poses, unknown frames)

  ros::Publisher state_pub_;
  ros::Publisher markers_pub_;
  ros::ServiceServer reset_service_;
  // Declared last so they stop first on destruction, before the simulation they drive.
  ros::WallTimer step_timer_;
  ros::WallTimer publish_timer_;
};

}  // namespace pbd_cloth
