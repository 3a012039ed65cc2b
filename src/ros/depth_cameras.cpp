// Simulated depth cameras on ROS (depth_cameras.h): capture on the step thread, ray casting and
// publishing on a render thread of their own.
#include "pbd_cloth/ros/depth_cameras.h"

#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/image_encodings.h>
#include <sensor_msgs/point_cloud2_iterator.h>
#include <tf2_eigen/tf2_eigen.h>

#include <cmath>
#include <cstring>

namespace pbd_cloth {

DepthCameras::DepthCameras(ros::NodeHandle nh_private, const SceneConfig& scene,
                           tf2_ros::Buffer& tf_buffer)
    : frame_id_(scene.frame_id), tf_buffer_(tf_buffer) {
  std::vector<geometry_msgs::TransformStamped> placed;
  for (std::size_t k = 0; k < scene.cameras.size(); ++k) {
    const CameraConfig& config = scene.cameras[k];
    auto camera = std::make_unique<Camera>();
    camera->config = config;
    camera->pinhole = PinholeCamera::fromConfig(config);
    camera->index = k;
    camera->ticks = PublishTicks(config.rate);
    camera->depth.resize(camera->pinhole.pixelCount());
    const std::string base = config.name + "/depth/";
    camera->image_pub = nh_private.advertise<sensor_msgs::Image>(base + "image_raw", 1);
    camera->info_pub = nh_private.advertise<sensor_msgs::CameraInfo>(base + "camera_info", 1);
    camera->points_pub = nh_private.advertise<sensor_msgs::PointCloud2>(base + "points", 1);
    if (config.has_pose) {
      geometry_msgs::TransformStamped transform = tf2::eigenToTransform(
          Eigen::Translation3d(config.pose.position) * config.pose.orientation);
      transform.header.stamp = ros::Time::now();
      transform.header.frame_id = frame_id_;
      transform.child_frame_id = config.frame;
      placed.push_back(transform);
    }
    ROS_INFO("Depth camera '%s': %dx%d at %.1f Hz in frame '%s' (%s), on %s*", config.name.c_str(),
             config.width, config.height, config.rate, config.frame.c_str(),
             config.has_pose ? "placed by its scene pose" : "followed in tf",
             nh_private.resolveName(base).c_str());
    cameras_.push_back(std::move(camera));
  }
  if (!placed.empty()) {
    static_broadcaster_ = std::make_unique<tf2_ros::StaticTransformBroadcaster>();
    static_broadcaster_->sendTransform(placed);
  }
  if (!cameras_.empty()) render_thread_ = std::thread(&DepthCameras::renderLoop, this);
}

DepthCameras::~DepthCameras() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  work_.notify_all();
  if (render_thread_.joinable()) render_thread_.join();
}

bool DepthCameras::listened(const Camera& camera) const {
  return camera.image_pub.getNumSubscribers() > 0 || camera.info_pub.getNumSubscribers() > 0 ||
         camera.points_pub.getNumSubscribers() > 0;
}

void DepthCameras::afterStep(const Simulation& simulation, const ros::Time& stamp) {
  bool captured = false;
  for (const std::unique_ptr<Camera>& camera : cameras_) {
    // The tick counts whether or not anyone listens, so a subscriber arriving later gets images
    // at the same simulated times as one that was there from the start.
    if (!camera->ticks.due(simulation.time()) || !listened(*camera)) continue;
    std::lock_guard<std::mutex> lock(mutex_);
    if (camera->has_pending) ++dropped_;  // the render thread did not take the last one
    camera->pending.capture(simulation);
    camera->pending_stamp = stamp;
    camera->has_pending = true;
    captured = true;
  }
  if (captured) work_.notify_one();
}

void DepthCameras::restart(double sim_time) {
  std::lock_guard<std::mutex> lock(mutex_);
  for (const std::unique_ptr<Camera>& camera : cameras_) {
    camera->ticks.restart(sim_time);
    camera->has_pending = false;  // a state of before the jump
  }
}

void DepthCameras::renderLoop() {
  while (true) {
    Camera* next = nullptr;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      work_.wait(lock, [this, &next] {
        if (stopping_) return true;
        for (const std::unique_ptr<Camera>& camera : cameras_) {
          if (camera->has_pending) {
            next = camera.get();
            return true;
          }
        }
        return false;
      });
      if (stopping_) return;
      // Swapping the buffers keeps both sized: neither side allocates after the first image.
      std::swap(next->pending, next->rendering);
      next->rendering_stamp = next->pending_stamp;
      next->has_pending = false;
    }
    Frame pose;
    if (!cameraPose(*next, next->rendering_stamp, pose)) continue;
    publish(*next, pose);
  }
}

bool DepthCameras::cameraPose(const Camera& camera, const ros::Time& stamp, Frame& pose) {
  if (camera.config.has_pose) {
    pose = frameFromPose(camera.config.pose);
    return true;
  }
  geometry_msgs::TransformStamped transform;
  try {
    if (tf_buffer_.canTransform(frame_id_, camera.config.frame, stamp)) {
      transform = tf_buffer_.lookupTransform(frame_id_, camera.config.frame, stamp);
    } else {
      transform = tf_buffer_.lookupTransform(frame_id_, camera.config.frame, ros::Time(0));
    }
  } catch (const tf2::TransformException& e) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      ++without_tf_;
    }
    ROS_WARN_THROTTLE(5.0,
                      "Depth camera '%s': no transform from '%s' to its frame '%s' (%s); its "
                      "images are skipped until tf has it (or give cameras[].pose).",
                      camera.config.name.c_str(), frame_id_.c_str(), camera.config.frame.c_str(),
                      e.what());
    return false;
  }
  const Eigen::Isometry3d placed = tf2::transformToEigen(transform);
  pose.rotation = placed.rotation();
  pose.translation = placed.translation();
  return true;
}

void DepthCameras::publish(Camera& camera, const Frame& pose) {
  const PinholeCamera& pinhole = camera.pinhole;
  const int width = pinhole.width, height = pinhole.height;
  camera.renderer.render(camera.rendering, pinhole, pose, camera.depth.data());
  // The same noise for the same image whoever renders it (cloth_bench --depth too).
  addCameraNoise(camera.depth.data(), camera.depth.size(), camera.config, camera.index,
                 camera.rendering.time);

  std_msgs::Header header;
  header.stamp = camera.rendering_stamp;
  header.frame_id = camera.config.frame;

  sensor_msgs::ImagePtr image = boost::make_shared<sensor_msgs::Image>();
  image->header = header;
  image->height = height;
  image->width = width;
  image->encoding = sensor_msgs::image_encodings::TYPE_32FC1;
  image->is_bigendian = 0;  // host order, little-endian on every machine ROS 1 runs on here
  image->step = width * sizeof(float);
  image->data.resize(camera.depth.size() * sizeof(float));
  std::memcpy(image->data.data(), camera.depth.data(), image->data.size());

  sensor_msgs::CameraInfoPtr info = boost::make_shared<sensor_msgs::CameraInfo>();
  info->header = header;
  info->height = height;
  info->width = width;
  info->distortion_model = "plumb_bob";
  info->D.assign(5, 0.0);
  info->K = {pinhole.fx, 0.0, pinhole.cx, 0.0, pinhole.fy, pinhole.cy, 0.0, 0.0, 1.0};
  info->R = {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0};
  info->P = {pinhole.fx, 0.0, pinhole.cx, 0.0, 0.0, pinhole.fy,
             pinhole.cy, 0.0, 0.0,        0.0, 1.0, 0.0};

  sensor_msgs::PointCloud2Ptr cloud = boost::make_shared<sensor_msgs::PointCloud2>();
  cloud->header = header;
  sensor_msgs::PointCloud2Modifier modifier(*cloud);
  modifier.setPointCloud2FieldsByString(1, "xyz");
  modifier.resize(camera.depth.size());
  cloud->height = height;  // organized: point (u, v) is pixel (u, v)
  cloud->width = width;
  cloud->row_step = cloud->point_step * width;
  cloud->is_dense = false;  // NaN where nothing is seen
  sensor_msgs::PointCloud2Iterator<float> x(*cloud, "x"), y(*cloud, "y"), z(*cloud, "z");
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u, ++x, ++y, ++z) {
      const float depth = camera.depth[static_cast<std::size_t>(v) * width + u];
      const Vec3 p = unprojectDepth(pinhole, u, v, depth);  // NaN depth: NaN x, y, z
      *x = static_cast<float>(p.x());
      *y = static_cast<float>(p.y());
      *z = depth;
    }
  }

  camera.image_pub.publish(image);
  camera.info_pub.publish(info);
  camera.points_pub.publish(cloud);
  std::lock_guard<std::mutex> lock(mutex_);
  ++published_;
}

std::uint64_t DepthCameras::framesPublished() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return published_;
}

std::uint64_t DepthCameras::framesDropped() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return dropped_;
}

std::uint64_t DepthCameras::framesWithoutTf() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return without_tf_;
}

}  // namespace pbd_cloth
