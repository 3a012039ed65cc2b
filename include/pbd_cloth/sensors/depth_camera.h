// Simulated depth cameras: what a pinhole depth camera sees of the cloth, the obstacles (planes
// included) and the robot links in one state. CPU ray casting, exact per pixel:
// - the cloth (and every mesh collider) as triangles: each pixel's ray is tested against each
//   triangle whose projected bounding box covers it, and the depth comes from the triangle's plane,
//   so a flat cloth has exactly the depth of its plane (no interpolation error);
// - spheres, boxes, capsules, cylinders and planes analytically (ray-quadric, ray-slab);
// - particles that belong to no triangle (a rope, granular matter) as spheres of their contact
//   radius.
// The nearest hit wins (a z-buffer); afterwards depths outside [range.min, range.max], and pixels
// that saw nothing, become NaN, so a surface closer than range.min still hides what is behind it,
// as on a real sensor. Colliders are drawn without their padding (padding is a contact margin, not
// geometry a camera would see).
//
// Depth is along the optical axis (z of the optical frame, REP 103: z forward, x right, y down),
// pixel centres at integer coordinates (OpenCV, ROS CameraInfo): pixel (u, v) looks along
// ((u - cx) / fx, (v - cy) / fy, 1). The same convention unprojects depth to points, as
// depth_image_proc does.
//
// Threads: a DepthSnapshot copies what the camera needs from a Simulation (positions, collider
// poses) so that rendering can run on another thread while the simulation steps on. Neither the
// capture nor the render allocates once the buffers have their sizes.
#pragma once

#include <cstdint>
#include <vector>

#include "pbd_cloth/config/scene_config.h"
#include "pbd_cloth/geometry/shapes.h"
#include "pbd_cloth/model/particles.h"

namespace pbd_cloth {

class Simulation;

struct PinholeCamera {
  int width = 320;
  int height = 240;
  double fx = 277.0, fy = 277.0;
  double cx = 159.5, cy = 119.5;
  double range_min = 0.1, range_max = 5.0;

  static PinholeCamera fromConfig(const CameraConfig& config);
  // The ray through pixel (u, v), scaled so that its z is 1: a hit at ray parameter t has depth t.
  Vec3 ray(double u, double v) const { return Vec3((u - cx) / fx, (v - cy) / fy, 1.0); }
  std::size_t pixelCount() const {
    return static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  }
};

// What a camera can see, copied out of a simulation at one instant.
struct DepthSnapshot {
  double time = 0.0;
  Vec3Array positions;              // every particle
  std::vector<double> radius;       // contact radius, for particles drawn as spheres
  std::vector<unsigned> triangles;  // the cloth's triangles (3 indices each); fixed for a run
  std::vector<int> loose;           // particles in no triangle: drawn as spheres
  std::vector<Shape> shapes;        // every collider (obstacles, then robot link elements)
  std::vector<Frame> frames;        // its pose now
  std::vector<char> visible;        // 0: a disabled collider (a robot link without tf)

  // Copies the state of `simulation`. The first capture sizes the buffers; later captures of the
  // same simulation copy into them without allocating.
  void capture(const Simulation& simulation);
};

class DepthRenderer {
 public:
  // Fills `depth` (camera.pixelCount() floats, row-major, row v at depth[v * width]) with what
  // the camera at `camera_pose` (the optical frame in the scene frame) sees of `scene`: metres
  // along the optical axis, NaN where nothing is seen within range. Allocates only the first time
  // a mesh of a given size is drawn (scratch space for its transformed vertices).
  void render(const DepthSnapshot& scene, const PinholeCamera& camera, const Frame& camera_pose,
              float* depth);

 private:
  void drawTriangle(const Vec3& a, const Vec3& b, const Vec3& c, const PinholeCamera& camera,
                    float* depth) const;
  void drawShape(const Shape& shape, const Frame& shape_in_camera, const PinholeCamera& camera,
                 float* depth);
  void drawSphere(const Vec3& centre, double radius, const PinholeCamera& camera,
                  float* depth) const;

  Vec3Array camera_points_;  // scratch: particles or mesh vertices in the camera frame
};

// Adds Gaussian noise of standard deviation `sigma` (m) to every finite pixel. The random stream
// depends only on (seed, frame), so an image is reproducible whatever thread renders it and
// however many images came before. Pixels pushed outside [range_min, range_max] become NaN.
void addDepthNoise(float* depth, std::size_t count, double sigma, std::uint64_t seed,
                   std::uint64_t frame, double range_min, double range_max);

// The noise of camera `camera_index` of the scene (config.noise, config.seed) on its image of the
// state at `sim_time`: addDepthNoise with the stream of (seed, camera index) and the image's index
// round(sim_time * rate). The node and cloth_bench --depth both call this, so the same scene gives
// the same noisy image in either; cameras given the same seed still get independent noise.
void addCameraNoise(float* depth, std::size_t count, const CameraConfig& config,
                    std::size_t camera_index, double sim_time);

// The point seen at pixel (u, v) with depth z, in the optical frame.
inline Vec3 unprojectDepth(const PinholeCamera& camera, int u, int v, double z) {
  return Vec3((u - camera.cx) * z / camera.fx, (v - camera.cy) * z / camera.fy, z);
}

}  // namespace pbd_cloth
