// cloth_node's ROS interface, checked against the scene it was started with (cloth_node.test loads
// test/ros/small_scene.yaml; the expectations are read back from the parameter server, so the scene
// can change without touching this file). nodelet.test runs the same checks on the nodelet: the
// node under test is the client's private parameter ~node (default /cloth_node).
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <ros/ros.h>
#include <visualization_msgs/MarkerArray.h>

#include "pbd_cloth/ClothState.h"
#include "ros_test_helpers.h"

namespace {

using pbd_cloth_test::distance;
using pbd_cloth_test::node;
using pbd_cloth_test::Recorder;
using pbd_cloth_test::StateRecorder;

// The parts of the scene the checks need.
struct Scene {
  int rows = 0;
  int cols = 0;
  double spacing = 0.0;
  double thickness = 0.0;
  std::vector<double> origin;
  std::vector<double> rpy;
  std::vector<int> pinned;
  int substeps = 0;
  std::string frame_id;
};

Scene readScene() {
  ros::NodeHandle nh(node());
  Scene scene;
  EXPECT_TRUE(nh.getParam("cloth/rows", scene.rows));
  EXPECT_TRUE(nh.getParam("cloth/cols", scene.cols));
  EXPECT_TRUE(nh.getParam("cloth/spacing", scene.spacing));
  EXPECT_TRUE(nh.getParam("cloth/thickness", scene.thickness));
  EXPECT_TRUE(nh.getParam("cloth/origin", scene.origin));
  EXPECT_TRUE(nh.getParam("cloth/rpy", scene.rpy));
  EXPECT_TRUE(nh.getParam("cloth/pinned", scene.pinned));
  EXPECT_TRUE(nh.getParam("solver/substeps", scene.substeps));
  EXPECT_TRUE(nh.getParam("frame_id", scene.frame_id));
  return scene;
}

// Particle (r, c) at rest: origin + R(rpy) * (c * spacing, -r * spacing, 0), R = Rz(y) Ry(p) Rx(r).
geometry_msgs::Point initialPosition(const Scene& s, int index) {
  const double u = (index % s.cols) * s.spacing;
  const double v = -(index / s.cols) * s.spacing;
  const double cr = std::cos(s.rpy[0]), sr = std::sin(s.rpy[0]);
  const double cp = std::cos(s.rpy[1]), sp = std::sin(s.rpy[1]);
  const double cy = std::cos(s.rpy[2]), sy = std::sin(s.rpy[2]);
  geometry_msgs::Point p;
  p.x = s.origin[0] + cy * cp * u + (cy * sp * sr - sy * cr) * v;
  p.y = s.origin[1] + sy * cp * u + (sy * sp * sr + cy * cr) * v;
  p.z = s.origin[2] - sp * u + cp * sr * v;
  return p;
}

bool resetAndReceiveInitialState(StateRecorder& recorder, pbd_cloth::ClothState& initial) {
  return pbd_cloth_test::resetAndReceiveInitialState(node(), recorder, initial);
}

TEST(ClothNode, PublishesTheWholeGrid) {
  const Scene scene = readScene();
  StateRecorder recorder(node() + "/state");
  pbd_cloth::ClothState state;
  ASSERT_TRUE(recorder.waitForNext(state, 10.0)) << "no message on " << node() << "/state";

  const std::size_t n = scene.rows * scene.cols;
  EXPECT_EQ(state.header.frame_id, scene.frame_id);
  EXPECT_GT(state.header.stamp.toSec(), 0.0);
  ASSERT_EQ(state.positions.size(), n);
  ASSERT_EQ(state.velocities.size(), n);
  for (const auto& p : state.positions) {
    ASSERT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z));
  }
  ASSERT_EQ(state.triangles.size(), 3u * 2u * (scene.rows - 1) * (scene.cols - 1));
  for (unsigned index : state.triangles) {
    ASSERT_LT(index, n);
  }
}

TEST(ClothNode, ListsPinnedParticlesAsKinematic) {
  Scene scene = readScene();
  StateRecorder recorder(node() + "/state");
  pbd_cloth::ClothState state;
  ASSERT_TRUE(recorder.waitForNext(state, 10.0));
  std::vector<int> kinematic(state.kinematic.begin(), state.kinematic.end());
  std::sort(kinematic.begin(), kinematic.end());
  std::sort(scene.pinned.begin(), scene.pinned.end());
  EXPECT_EQ(kinematic, scene.pinned);
}

TEST(ClothNode, ReportsTheSceneSubstepsAndRealTime) {
  const Scene scene = readScene();
  StateRecorder recorder(node() + "/state");
  pbd_cloth::ClothState state;
  // After more than a second of stepping, so the real-time factor spans its whole window.
  ASSERT_TRUE(recorder.waitForNext(
      state, 10.0, [](const pbd_cloth::ClothState& msg) { return msg.stats.sim_time > 1.5; }));
  EXPECT_EQ(state.stats.substeps, static_cast<unsigned>(scene.substeps));
  EXPECT_GT(state.stats.iterations, 0u);
  // A 10x10 cloth steps far faster than real time, and the node never runs ahead of the clock.
  EXPECT_GT(state.stats.real_time_factor, 0.5);
  EXPECT_LT(state.stats.real_time_factor, 1.5);
  EXPECT_EQ(state.stats.rejected_inputs, 0u);
}

TEST(ClothNode, ResetRestoresTheInitialState) {
  const Scene scene = readScene();
  StateRecorder recorder(node() + "/state");
  pbd_cloth::ClothState first;
  ASSERT_TRUE(recorder.waitForNext(first, 10.0));

  pbd_cloth::ClothState initial;
  ASSERT_TRUE(resetAndReceiveInitialState(recorder, initial)) << "no state with sim_time 0";
  ASSERT_EQ(initial.positions.size(), first.positions.size());
  EXPECT_NEAR(initial.stats.sim_time, 0.0, 1e-9);
  for (std::size_t i = 0; i < initial.positions.size(); ++i) {
    EXPECT_LT(distance(initial.positions[i], initialPosition(scene, i)), 1e-6) << "particle " << i;
  }
  for (int i : scene.pinned) {
    EXPECT_LT(distance(initial.positions[i], first.positions[i]), 1e-9) << "pinned " << i;
  }

  // The next states start again from t = 0.
  pbd_cloth::ClothState next;
  ASSERT_TRUE(recorder.waitForNext(
      next, 5.0, [](const pbd_cloth::ClothState& msg) { return msg.stats.sim_time > 0.0; }));
  EXPECT_LT(next.stats.sim_time, 0.5);

  // A second reset lands on exactly the same state.
  pbd_cloth::ClothState again;
  ASSERT_TRUE(resetAndReceiveInitialState(recorder, again));
  for (std::size_t i = 0; i < initial.positions.size(); ++i) {
    EXPECT_LT(distance(again.positions[i], initial.positions[i]), 1e-12) << "particle " << i;
  }
}

TEST(ClothNode, PinnedParticlesStayWhileTheClothFalls) {
  const Scene scene = readScene();
  StateRecorder recorder(node() + "/state");
  pbd_cloth::ClothState initial;
  ASSERT_TRUE(resetAndReceiveInitialState(recorder, initial));

  const std::size_t first = recorder.count();
  pbd_cloth::ClothState later;
  ASSERT_TRUE(recorder.waitForNext(
      later, 10.0, [](const pbd_cloth::ClothState& msg) { return msg.stats.sim_time >= 2.0; }));
  ASSERT_EQ(later.positions.size(), initial.positions.size());
  for (int i : scene.pinned) {
    EXPECT_LT(distance(later.positions[i], initial.positions[i]), 1e-9) << "pinned " << i;
  }
  // The free corner opposite the first pin swings down well below where it started. Without
  // damping it may swing back up, so the lowest point over the whole interval is checked.
  const int corner = scene.rows * scene.cols - 1;
  ASSERT_EQ(std::count(scene.pinned.begin(), scene.pinned.end(), corner), 0);
  double lowest = initial.positions[corner].z;
  for (const pbd_cloth::ClothState& msg : recorder.since(first)) {
    lowest = std::min(lowest, msg.positions[corner].z);
  }
  EXPECT_LT(lowest, initial.positions[corner].z - 0.1);
  for (const auto& p : later.positions) {
    ASSERT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z));
  }
}

TEST(ClothNode, PublishesALitMeshAndParticles) {
  const Scene scene = readScene();
  Recorder<visualization_msgs::MarkerArray> recorder(node() + "/markers");
  visualization_msgs::MarkerArray markers;
  ASSERT_TRUE(recorder.waitForNext(markers, 10.0)) << "no message on " << node() << "/markers";

  const visualization_msgs::Marker* mesh = nullptr;
  const visualization_msgs::Marker* particles = nullptr;
  for (const auto& marker : markers.markers) {
    if (marker.ns == "cloth") mesh = &marker;
    if (marker.ns == "particles" && marker.id == 0) particles = &marker;
  }
  ASSERT_NE(mesh, nullptr);
  EXPECT_EQ(mesh->type, visualization_msgs::Marker::TRIANGLE_LIST);
  EXPECT_EQ(mesh->header.frame_id, scene.frame_id);
  EXPECT_EQ(mesh->points.size(), 3u * 2u * (scene.rows - 1) * (scene.cols - 1));
  EXPECT_TRUE(mesh->colors.empty()) << "per-vertex colours switch rviz lighting off";
  EXPECT_EQ(mesh->color.a, 1.0f);
  EXPECT_EQ(mesh->pose.orientation.w, 1.0);

  ASSERT_NE(particles, nullptr);
  EXPECT_EQ(particles->type, visualization_msgs::Marker::SPHERE_LIST);
  EXPECT_EQ(particles->points.size(), static_cast<std::size_t>(scene.rows * scene.cols));
  EXPECT_NEAR(particles->scale.x, 2.0 * scene.thickness, 1e-12);
  EXPECT_EQ(particles->pose.orientation.w, 1.0);
}

// Normal (not normalised) of the triangle a, b, c.
geometry_msgs::Point triangleNormal(const geometry_msgs::Point& a, const geometry_msgs::Point& b,
                                    const geometry_msgs::Point& c) {
  const double ux = b.x - a.x, uy = b.y - a.y, uz = b.z - a.z;
  const double vx = c.x - a.x, vy = c.y - a.y, vz = c.z - a.z;
  return pbd_cloth_test::point(uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx);
}

double dot(const geometry_msgs::Point& a, const geometry_msgs::Point& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}

TEST(ClothNode, MeshHasThreePointsPerTriangleOfTheStateWoundOneWay) {
  StateRecorder states(node() + "/state");
  Recorder<visualization_msgs::MarkerArray> marker_arrays(node() + "/markers");
  pbd_cloth::ClothState initial;
  ASSERT_TRUE(resetAndReceiveInitialState(states, initial));
  visualization_msgs::MarkerArray markers;
  ASSERT_TRUE(marker_arrays.waitForNext(markers, 10.0));
  const visualization_msgs::Marker* mesh = nullptr;
  for (const auto& marker : markers.markers) {
    if (marker.ns == "cloth") mesh = &marker;
  }
  ASSERT_NE(mesh, nullptr);
  ASSERT_GT(initial.triangles.size(), 0u);
  EXPECT_EQ(mesh->points.size(), initial.triangles.size()) << "3 points per triangle of ~state";

  // The flat initial grid: every triangle of ~state faces the same side.
  const auto& t = initial.triangles;
  const auto& x = initial.positions;
  const geometry_msgs::Point first = triangleNormal(x[t[0]], x[t[1]], x[t[2]]);
  for (std::size_t k = 0; k < t.size(); k += 3) {
    EXPECT_GT(dot(triangleNormal(x[t[k]], x[t[k + 1]], x[t[k + 2]]), first), 0.0)
        << "triangle " << k / 3 << " is wound the other way";
  }
  // The mesh marker of a moving cloth: the two triangles of each grid cell (consecutive in the
  // list) face the same side, so rviz lights both alike.
  const auto& p = mesh->points;
  for (std::size_t k = 0; k + 5 < p.size(); k += 6) {
    EXPECT_GT(
        dot(triangleNormal(p[k], p[k + 1], p[k + 2]), triangleNormal(p[k + 3], p[k + 4], p[k + 5])),
        0.0)
        << "cell " << k / 6;
  }
}

}  // namespace

int main(int argc, char** argv) { return pbd_cloth_test::runTests(argc, argv, "cloth_node_test"); }
