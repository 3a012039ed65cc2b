// cloth_node: the simulator as a stand-alone node. All the work is in ClothRos.
#include <malloc.h>

#include <cstdio>

#include <ros/ros.h>

#include "pbd_cloth/ros/cloth_ros.h"

int main(int argc, char** argv) {
  // Line-buffered: under roslaunch stdout is a pipe, and ROS_INFO lines would otherwise show up
  // only when the node exits.
  std::setvbuf(stdout, nullptr, _IOLBF, BUFSIZ);
#ifdef __GLIBC__
  // A fixed mmap threshold. glibc raises it each time a large block is freed; after that the
  // depth images, clouds and their serialized copies (77 kB to MBs, made and freed at the camera
  // rate by several threads) are carved from the threads' heaps among small blocks, where they
  // fragment and stay resident after they are freed (doc/reliability.md "Soak": a long run must not
  // grow). Fixed, each such block is mapped and unmapped whole (a few system calls per image). A
  // nodelet manager gets the same with MALLOC_MMAP_THRESHOLD_=65536 in its environment.
  mallopt(M_MMAP_THRESHOLD, 64 * 1024);
#endif
  ros::init(argc, argv, "cloth_node");
  try {
    pbd_cloth::ClothRos cloth(ros::NodeHandle(), ros::NodeHandle("~"));
    ros::spin();
  } catch (const pbd_cloth::ConfigError&) {
    return 1;  // ClothRos has already logged which key is wrong
  }
  return 0;
}
