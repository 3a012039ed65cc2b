// cloth_node: the simulator as a stand-alone node. All the work is in ClothRos.
#include <cstdio>

#include <ros/ros.h>

#include "pbd_cloth/ros/cloth_ros.h"

int main(int argc, char** argv) {
  // Line-buffered: under roslaunch stdout is a pipe, and ROS_INFO lines would otherwise show up
  // only when the node exits.
  std::setvbuf(stdout, nullptr, _IOLBF, BUFSIZ);
  ros::init(argc, argv, "cloth_node");
  try {
    pbd_cloth::ClothRos cloth(ros::NodeHandle(), ros::NodeHandle("~"));
    ros::spin();
  } catch (const pbd_cloth::ConfigError&) {
    return 1;  // ClothRos has already logged which key is wrong
  }
  return 0;
}
