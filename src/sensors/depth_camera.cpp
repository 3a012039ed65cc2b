// Depth images by ray casting (depth_camera.h). Every hit is computed in closed form along the
// pixel's ray d = ((u - cx) / fx, (v - cy) / fy, 1) from the optical centre, so the ray parameter
// is the depth itself.
#include "pbd_cloth/sensors/depth_camera.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "pbd_cloth/sim/simulation.h"

namespace pbd_cloth {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
// Points this close to the camera plane (or behind it) cannot be projected to pixels.
constexpr double kNearPlane = 1e-9;

// The pixels [u0, u1] x [v0, v1] worth testing; empty when u0 > u1.
struct PixelRect {
  int u0 = 0, u1 = -1, v0 = 0, v1 = -1;
  bool empty() const { return u0 > u1 || v0 > v1; }
};

PixelRect wholeImage(const PinholeCamera& camera) {
  return PixelRect{0, camera.width - 1, 0, camera.height - 1};
}

// The pixels onto which points (camera frame) of a convex set with these corners can project.
// Whole image when the set reaches behind the camera plane; empty when all of it is behind.
PixelRect projectedRect(const Vec3* corners, int count, const PinholeCamera& camera) {
  double u_lo = kInfinity, u_hi = -kInfinity, v_lo = kInfinity, v_hi = -kInfinity;
  bool all_behind = true;
  bool all_in_front = true;
  for (int k = 0; k < count; ++k) {
    const Vec3& p = corners[k];
    all_behind = all_behind && p.z() <= 0.0;
    all_in_front = all_in_front && p.z() > kNearPlane;
    if (p.z() <= kNearPlane) continue;
    const double u = camera.fx * p.x() / p.z() + camera.cx;
    const double v = camera.fy * p.y() / p.z() + camera.cy;
    u_lo = std::min(u_lo, u);
    u_hi = std::max(u_hi, u);
    v_lo = std::min(v_lo, v);
    v_hi = std::max(v_hi, v);
  }
  if (all_behind) return PixelRect{};
  if (!all_in_front) return wholeImage(camera);
  // Clamp in double before converting: a point just in front of the camera projects far away.
  const auto clampTo = [](double x, int hi) {
    return static_cast<int>(std::max(0.0, std::min(static_cast<double>(hi), x)));
  };
  PixelRect rect;
  rect.u0 = clampTo(std::floor(u_lo), camera.width - 1);
  rect.u1 = clampTo(std::ceil(u_hi), camera.width - 1);
  rect.v0 = clampTo(std::floor(v_lo), camera.height - 1);
  rect.v1 = clampTo(std::ceil(v_hi), camera.height - 1);
  if (u_hi < 0.0 || v_hi < 0.0 || u_lo > camera.width - 1 || v_lo > camera.height - 1) {
    return PixelRect{};
  }
  return rect;
}

// The 8 corners of the local box [lo, hi] placed by `frame`.
void boxCorners(const Vec3& lo, const Vec3& hi, const Frame& frame, Vec3 corners[8]) {
  for (int k = 0; k < 8; ++k) {
    const Vec3 local((k & 1) ? hi.x() : lo.x(), (k & 2) ? hi.y() : lo.y(),
                     (k & 4) ? hi.z() : lo.z());
    corners[k] = frame.toWorld(local);
  }
}

std::uint64_t splitMix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// The pixels onto which a shape (not a plane) placed by `shape_in_camera` can project: its bounds
// (shapes.h worldBounds), an axis-aligned box in the camera frame.
PixelRect boundsRect(const Shape& shape, const Frame& shape_in_camera,
                     const PinholeCamera& camera) {
  Vec3 lo = Vec3::Zero(), hi = Vec3::Zero(), corners[8];
  worldBounds(shape, shape_in_camera, lo, hi);
  boxCorners(lo, hi, Frame(), corners);
  return projectedRect(corners, 8, camera);
}

}  // namespace

PinholeCamera PinholeCamera::fromConfig(const CameraConfig& config) {
  PinholeCamera camera;
  camera.width = config.width;
  camera.height = config.height;
  camera.fx = config.fx;
  camera.fy = config.fy;
  camera.cx = config.cx;
  camera.cy = config.cy;
  camera.range_min = config.range_min;
  camera.range_max = config.range_max;
  return camera;
}

void DepthSnapshot::capture(const Simulation& simulation) {
  const Particles& particles = simulation.particles();
  time = simulation.time();
  positions.assign(particles.position.begin(), particles.position.end());
  radius.assign(particles.radius.begin(), particles.radius.end());
  const std::vector<unsigned>& cloth = simulation.topology().triangles;
  // The triangles, and so which particles are loose, are the same for the whole run.
  if (triangles != cloth || loose.size() + triangles.size() == 0) {
    triangles = cloth;
    std::vector<char> in_triangle(positions.size(), 0);
    for (unsigned index : triangles) in_triangle[index] = 1;
    loose.clear();
    for (std::size_t i = 0; i < positions.size(); ++i) {
      if (!in_triangle[i]) loose.push_back(static_cast<int>(i));
    }
  }
  const Collisions& collisions = simulation.collisions();
  const std::vector<Collider>& colliders = collisions.obstacles();
  if (shapes.size() != colliders.size()) {
    shapes.clear();
    for (const Collider& collider : colliders) {
      shapes.push_back(collider.shape);
      shapes.back().padding = 0.0;
    }
    frames.resize(colliders.size());
    visible.resize(colliders.size());
  }
  for (std::size_t k = 0; k < colliders.size(); ++k) {
    frames[k] = frameFromPose(colliders[k].pose);
    visible[k] = collisions.obstacleEnabled(static_cast<int>(k)) ? 1 : 0;
  }
}

void DepthRenderer::render(const DepthSnapshot& scene, const PinholeCamera& camera,
                           const Frame& camera_pose, float* depth) {
  const std::size_t pixels = camera.pixelCount();
  std::fill(depth, depth + pixels, std::numeric_limits<float>::infinity());

  // The cloth: its triangles in the camera frame.
  camera_points_.resize(std::max(camera_points_.size(), scene.positions.size()));
  for (std::size_t i = 0; i < scene.positions.size(); ++i) {
    camera_points_[i] = camera_pose.toLocal(scene.positions[i]);
  }
  for (std::size_t t = 0; t + 2 < scene.triangles.size(); t += 3) {
    drawTriangle(camera_points_[scene.triangles[t]], camera_points_[scene.triangles[t + 1]],
                 camera_points_[scene.triangles[t + 2]], camera, depth);
  }
  for (int i : scene.loose) drawSphere(camera_points_[i], scene.radius[i], camera, depth);

  // Colliders: the shape's frame seen from the camera.
  for (std::size_t k = 0; k < scene.shapes.size(); ++k) {
    if (!scene.visible[k]) continue;
    Frame in_camera;
    in_camera.rotation = camera_pose.rotation.transpose() * scene.frames[k].rotation;
    in_camera.translation = camera_pose.toLocal(scene.frames[k].translation);
    drawShape(scene.shapes[k], in_camera, camera, depth);
  }

  // Nearest hit within range, else NaN.
  const float lo = static_cast<float>(camera.range_min);
  const float hi = static_cast<float>(camera.range_max);
  for (std::size_t p = 0; p < pixels; ++p) {
    if (!(depth[p] >= lo && depth[p] <= hi)) depth[p] = std::numeric_limits<float>::quiet_NaN();
  }
}

// A triangle (camera frame). The ray d hits it in front of the camera exactly when d lies in the
// cone the three vertices span from the optical centre: d = alpha a + beta b + gamma c with
// alpha, beta, gamma >= 0, i.e. d.(b x c), d.(c x a), d.(a x b) all share the sign of the triple
// product a.(b x c). The depth is then that of the triangle's plane, n.a / n.d with n its normal.
// Edges test with >= so that neighbouring triangles leave no crack between them.
void DepthRenderer::drawTriangle(const Vec3& a, const Vec3& b, const Vec3& c,
                                 const PinholeCamera& camera, float* depth) const {
  const double volume = a.dot(b.cross(c));
  // Zero: degenerate, or seen edge-on (the optical centre in its plane): it covers no area.
  if (volume == 0.0 || !std::isfinite(volume)) return;
  const double sign = volume > 0.0 ? 1.0 : -1.0;
  const Vec3 edge_a = sign * b.cross(c), edge_b = sign * c.cross(a), edge_c = sign * a.cross(b);
  const Vec3 normal = (b - a).cross(c - a);
  const double plane = normal.dot(a);
  const Vec3 corners[3] = {a, b, c};
  const PixelRect rect = projectedRect(corners, 3, camera);
  for (int v = rect.v0; v <= rect.v1; ++v) {
    const double y = (v - camera.cy) / camera.fy;
    float* row = depth + static_cast<std::size_t>(v) * camera.width;
    for (int u = rect.u0; u <= rect.u1; ++u) {
      const double x = (u - camera.cx) / camera.fx;
      if (edge_a.x() * x + edge_a.y() * y + edge_a.z() < 0.0 ||
          edge_b.x() * x + edge_b.y() * y + edge_b.z() < 0.0 ||
          edge_c.x() * x + edge_c.y() * y + edge_c.z() < 0.0) {
        continue;
      }
      const double t = plane / (normal.x() * x + normal.y() * y + normal.z());
      if (t > 0.0 && t < row[u]) row[u] = static_cast<float>(t);
    }
  }
}

void DepthRenderer::drawSphere(const Vec3& centre, double radius, const PinholeCamera& camera,
                               float* depth) const {
  Vec3 corners[8];
  Frame at;
  at.translation = centre;
  boxCorners(Vec3::Constant(-radius), Vec3::Constant(radius), at, corners);
  const PixelRect rect = projectedRect(corners, 8, camera);
  for (int v = rect.v0; v <= rect.v1; ++v) {
    float* row = depth + static_cast<std::size_t>(v) * camera.width;
    for (int u = rect.u0; u <= rect.u1; ++u) {
      const double t = raySphere(Vec3::Zero(), camera.ray(u, v), centre, radius);
      if (t < row[u]) row[u] = static_cast<float>(t);
    }
  }
}

void DepthRenderer::drawShape(const Shape& shape, const Frame& shape_in_camera,
                              const PinholeCamera& camera, float* depth) {
  if (shape.type == ShapeType::kMesh) {
    const std::vector<Vec3>& vertices = shape.mesh->vertices();
    if (camera_points_.size() < vertices.size()) camera_points_.resize(vertices.size());
    for (std::size_t i = 0; i < vertices.size(); ++i) {
      camera_points_[i] = shape_in_camera.toWorld(vertices[i]);
    }
    if (boundsRect(shape, shape_in_camera, camera).empty()) return;
    for (const TriangleMesh::Triangle& t : shape.mesh->triangles()) {
      drawTriangle(camera_points_[t[0]], camera_points_[t[1]], camera_points_[t[2]], camera, depth);
    }
    return;
  }
  const PixelRect rect = shape.type == ShapeType::kPlane
                             ? wholeImage(camera)
                             : boundsRect(shape, shape_in_camera, camera);
  // The ray in the shape's frame: origin and direction (linear in the pixel).
  const Vec3 origin = shape_in_camera.toLocal(Vec3::Zero());
  const Eigen::Matrix3d to_local = shape_in_camera.rotation.transpose();
  for (int v = rect.v0; v <= rect.v1; ++v) {
    float* row = depth + static_cast<std::size_t>(v) * camera.width;
    for (int u = rect.u0; u <= rect.u1; ++u) {
      const double t = rayHit(shape, origin, to_local * camera.ray(u, v));
      if (t < row[u]) row[u] = static_cast<float>(t);
    }
  }
}

void addDepthNoise(float* depth, std::size_t count, double sigma, std::uint64_t seed,
                   std::uint64_t frame, double range_min, double range_max) {
  if (!(sigma > 0.0)) return;
  std::mt19937_64 random(splitMix64(seed) ^ splitMix64(frame + 0x632BE59BD9B4E019ull));
  std::normal_distribution<double> gaussian(0.0, sigma);
  for (std::size_t p = 0; p < count; ++p) {
    if (!std::isfinite(depth[p])) continue;
    const double z = depth[p] + gaussian(random);
    depth[p] = z >= range_min && z <= range_max ? static_cast<float>(z)
                                                : std::numeric_limits<float>::quiet_NaN();
  }
}

void addCameraNoise(float* depth, std::size_t count, const CameraConfig& config,
                    std::size_t camera_index, double sim_time) {
  const std::uint64_t stream = (static_cast<std::uint64_t>(config.seed) << 16) | camera_index;
  const auto image = static_cast<std::uint64_t>(std::llround(sim_time * config.rate));
  addDepthNoise(depth, count, config.noise, stream, image, config.range_min, config.range_max);
}

}  // namespace pbd_cloth
