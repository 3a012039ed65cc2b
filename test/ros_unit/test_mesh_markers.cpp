// The cloth's two sides in rviz (RosConversions::toMeshMarker, toBackMarker): the back is the
// front's triangles wound the other way, half a thickness behind it, so neither fights the other
// for depth (a flat cloth showed specks of its back through its front when they coincided).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cstdio>
#include <fstream>
#include <string>

#include "pbd_cloth/ros/ros_conversions.h"
#include "pbd_cloth/scene/scene_assets.h"
#include "pbd_cloth/sim/simulation.h"

namespace pbd_cloth {
namespace {

Vec3 at(const geometry_msgs::Point& p) { return Vec3(p.x, p.y, p.z); }

// Unit normal of triangle k of a TRIANGLE_LIST, by its winding.
Vec3 triangleNormal(const visualization_msgs::Marker& marker, std::size_t k) {
  const Vec3 a = at(marker.points[3 * k]);
  return (at(marker.points[3 * k + 1]) - a).cross(at(marker.points[3 * k + 2]) - a).normalized();
}

SceneConfig flatCloth(const Vec3& rpy) {
  SceneConfig scene;
  scene.cloth.rows = 5;
  scene.cloth.cols = 4;
  scene.cloth.spacing = 0.1;
  scene.cloth.thickness = 0.008;
  scene.cloth.rpy = rpy;
  scene.cloth.self_collision = false;
  return scene;
}

TEST(MeshMarkers, TheBackIsTheFrontTurnedOverHalfAThicknessBehind) {
  for (const Vec3& rpy : {Vec3(0.0, 0.0, 0.0), Vec3(1.2, -0.4, 2.0)}) {
    const Simulation sim(flatCloth(rpy));
    std_msgs::Header header;
    visualization_msgs::Marker front;
    visualization_msgs::Marker back;
    ASSERT_TRUE(RosConversions::toMeshMarker(sim, header, front));
    RosConversions::toBackMarker(sim, front, back);
    EXPECT_EQ(back.ns, "cloth_back");
    ASSERT_EQ(back.points.size(), front.points.size());
    ASSERT_EQ(front.points.size(), 3u * 2u * 4u * 3u);  // two triangles a cell
    const double depth = 0.5 * sim.scene().cloth.thickness;
    for (std::size_t k = 0; k < front.points.size() / 3; ++k) {
      const Vec3 n = triangleNormal(front, k);
      // Turned over: it faces the other way.
      EXPECT_NEAR(triangleNormal(back, k).dot(n), -1.0, 1e-9) << "triangle " << k;
      // Corner order 0, 2, 1, each moved by `depth` against the front's normal.
      const int order[3] = {0, 2, 1};
      for (int c = 0; c < 3; ++c) {
        const Vec3 moved = at(back.points[3 * k + c]) - at(front.points[3 * k + order[c]]);
        EXPECT_NEAR((moved + depth * n).norm(), 0.0, 1e-12)
            << "triangle " << k << " corner " << c << ": moved " << moved.transpose();
      }
    }
  }
}

// A plane obstacle is drawn as a square centred below where the cloth starts: for a mesh cloth
// too, whose place the grid's rows, cols and spacing do not describe.
TEST(MeshMarkers, APlanesSquareIsCentredBelowTheClothAsBuilt) {
  const std::string obj = testing::TempDir() + "pbd_cloth_plane_marker.obj";
  {
    // A 0.6 x 0.4 m rectangle of two triangles, corner (0, 0) at the file's origin.
    std::ofstream out(obj);
    out << "v 0 0 0\nv 0.6 0 0\nv 0.6 0.4 0\nv 0 0.4 0\nf 1 2 3\nf 1 3 4\n";
  }
  for (bool mesh : {false, true}) {
    SceneConfig scene = flatCloth(Vec3(0.0, 0.0, 0.3));
    scene.cloth.origin = Vec3(2.0, -1.0, 0.5);
    if (mesh) {
      scene.cloth.mesh = obj;
      loadClothMesh(scene);
    }
    ObstacleConfig floor;
    floor.name = "floor";
    floor.shape = ShapeType::kPlane;
    floor.normal = Vec3::UnitZ();
    floor.offset = 0.1;
    scene.obstacles.push_back(floor);
    const Simulation sim(scene);
    Eigen::AlignedBox3d box;
    for (int i = 0; i < sim.particles().cloth_count; ++i) box.extend(sim.particles().position[i]);
    visualization_msgs::MarkerArray markers;
    RosConversions::toObstacleMarkers(sim, std_msgs::Header(), markers);
    ASSERT_EQ(markers.markers.size(), 1u);
    const geometry_msgs::Point& centre = markers.markers[0].pose.position;
    EXPECT_NEAR(centre.x, box.center().x(), 1e-12) << (mesh ? "mesh" : "grid");
    EXPECT_NEAR(centre.y, box.center().y(), 1e-12) << (mesh ? "mesh" : "grid");
    EXPECT_LT(centre.z, floor.offset) << "the square's top face lies on the plane";
  }
  std::remove(obj.c_str());
}

// A rope is drawn as a LINE_STRIP through its own particles, as thick as it is; granular
// particles after it keep their own marker, without the rope's particles.
TEST(MeshMarkers, RopesAreLineStripsThroughTheirParticles) {
  SceneConfig scene = flatCloth(Vec3::Zero());
  RopeConfig rope;
  rope.name = "cable";
  rope.start = Vec3(0.0, 1.0, 1.0);
  rope.end = Vec3(1.0, 1.0, 1.0);
  rope.segments = 10;
  rope.radius = 0.004;
  scene.ropes = {rope};
  scene.granular.count = 3;
  scene.granular.radius = 0.01;
  scene.granular.region_min = Vec3(0.0, -1.0, 0.5);
  scene.granular.region_max = Vec3(0.2, -0.8, 0.7);
  const Simulation sim(scene);
  visualization_msgs::MarkerArray markers;
  RosConversions::toParticleMarkers(sim, std_msgs::Header(), markers);
  int lines = 0, granular_points = -1;
  for (const auto& marker : markers.markers) {
    if (marker.ns == "ropes") {
      ++lines;
      EXPECT_EQ(marker.type, visualization_msgs::Marker::LINE_STRIP);
      ASSERT_EQ(marker.points.size(), 11u);
      EXPECT_DOUBLE_EQ(marker.scale.x, 0.008);
      EXPECT_DOUBLE_EQ(marker.points[10].x, 1.0);
      EXPECT_DOUBLE_EQ(marker.points[10].y, 1.0);
    } else if (marker.ns == "particles" && marker.id == 1) {
      granular_points = static_cast<int>(marker.points.size());
    }
  }
  EXPECT_EQ(lines, 1);
  EXPECT_EQ(granular_points, 3);
}

}  // namespace
}  // namespace pbd_cloth
