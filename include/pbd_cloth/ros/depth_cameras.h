// The scene's simulated depth cameras (`cameras:`) on ROS. For each camera, in the node's private
// namespace:
//   ~<camera>/depth/image_raw    sensor_msgs/Image 32FC1, metres along the optical axis, NaN where
//                                nothing is seen within range
//   ~<camera>/depth/camera_info  sensor_msgs/CameraInfo: K and P from fx, fy, cx, cy; no distortion
//   ~<camera>/depth/points       sensor_msgs/PointCloud2, organized width x height, float32 x y z
//                                in the optical frame (NaN where the image is NaN)
// All three carry the same header: the optical frame and the stamp of the state rendered, so
// message_filters' exact-time synchronizers pair them.
//
// Timing: an image is due at each multiple of 1/rate of simulated time (the first state at or past
// it, as ~state's publish ticks). Nothing is captured or rendered while nobody subscribes to any of
// a camera's three topics (like a camera driver's lazy publishing): a camera in the scene costs
// nothing until it is looked at.
//
// Threads: the step thread only copies the state (DepthSnapshot::capture: positions and collider
// poses, no allocation) into the camera's pending slot; one render thread ray-casts and publishes.
// When the render thread is still busy with an earlier image, the newer state replaces the pending
// one and the older is dropped (counted: framesDropped), so the camera never holds up the steps.
//
// Where the camera is: with `pose` the optical frame stands there in the scene frame and the node
// broadcasts it as a static transform frame_id -> frame; without, `frame` is looked up in tf at
// the state's stamp, or, when tf has nothing that recent yet, its newest transform. A frame tf
// cannot resolve skips the image with a throttled warning naming the camera and frame (counted:
// framesWithoutTf).
#pragma once

#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <ros/ros.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include "pbd_cloth/ros/publish_ticks.h"
#include "pbd_cloth/sensors/depth_camera.h"
#include "pbd_cloth/sim/simulation.h"

namespace pbd_cloth {

class DepthCameras {
 public:
  DepthCameras(ros::NodeHandle nh_private, const SceneConfig& scene, tf2_ros::Buffer& tf_buffer);
  ~DepthCameras();
  DepthCameras(const DepthCameras&) = delete;
  DepthCameras& operator=(const DepthCameras&) = delete;

  bool empty() const { return cameras_.empty(); }
  // After each step (the caller holds the simulation still): captures the state for every camera
  // whose image is due and that someone listens to. `stamp` is the state's ROS time.
  void afterStep(const Simulation& simulation, const ros::Time& stamp);
  // Simulated time jumped to `sim_time` (reset, set_state): the next image is due at the first
  // tick after it.
  void restart(double sim_time);

  std::uint64_t framesPublished() const;
  std::uint64_t framesDropped() const;
  std::uint64_t framesWithoutTf() const;

 private:
  struct Camera {
    CameraConfig config;
    PinholeCamera pinhole;
    std::size_t index = 0;  // in the scene's cameras (addCameraNoise)
    PublishTicks ticks;
    ros::Publisher image_pub, info_pub, points_pub;
    // Written by the step thread, taken by the render thread (under mutex_).
    DepthSnapshot pending;
    ros::Time pending_stamp;
    bool has_pending = false;
    // The render thread's own.
    DepthSnapshot rendering;
    ros::Time rendering_stamp;
    DepthRenderer renderer;
    std::vector<float> depth;
  };

  bool listened(const Camera& camera) const;
  void renderLoop();
  // The optical frame in the scene frame at `stamp`; false (with a warning) when tf lacks it.
  bool cameraPose(const Camera& camera, const ros::Time& stamp, Frame& pose);
  void publish(Camera& camera, const Frame& pose);

  std::string frame_id_;
  tf2_ros::Buffer& tf_buffer_;
  std::unique_ptr<tf2_ros::StaticTransformBroadcaster> static_broadcaster_;
  std::vector<std::unique_ptr<Camera>> cameras_;

  mutable std::mutex mutex_;
  std::condition_variable work_;
  bool stopping_ = false;
  std::uint64_t published_ = 0, dropped_ = 0, without_tf_ = 0;
  std::thread render_thread_;  // last: started once everything above exists
};

}  // namespace pbd_cloth
