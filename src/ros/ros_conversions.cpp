#include "pbd_cloth/ros/ros_conversions.h"

#include <cstdint>
#include <vector>

#include "pbd_cloth/geometry/shapes.h"

namespace pbd_cloth {
namespace {

// Alpha < 1 turns off depth writes in rviz and a mesh looks inside out: 1 unless see-through is
// the point (the gripper spheres around their grasped particles).
std_msgs::ColorRGBA color(float r, float g, float b, float a = 1.0f) {
  std_msgs::ColorRGBA c;
  c.r = r;
  c.g = g;
  c.b = b;
  c.a = a;
  return c;
}

// Edge length of the square drawn for an (infinite) plane obstacle (m).
constexpr double kPlaneMarkerSize = 4.0;
// Thickness of that square (m): thin, but thick enough not to flicker against the cloth on it.
constexpr double kPlaneMarkerThickness = 0.002;

// How far behind the front the back side is drawn, in cloth thicknesses (the particle radius):
// the back's triangles on the front's would fight for the same depth, and a flat cloth showed
// dark specks of its back through its front (doc/hanging.png, 2026-11-27).
constexpr double kBackSideDepth = 0.5;

// Centre of the box around the cloth as built (before it moves), where a plane's square is
// centred: a grid's or a mesh's alike (rows, cols and spacing say nothing about a mesh cloth).
Vec3 initialClothCentre(const Simulation& sim) {
  const Particles& initial = sim.initialParticles();
  Eigen::AlignedBox3d box;
  for (int i = 0; i < initial.cloth_count; ++i) box.extend(initial.position[i]);
  return box.center();
}

// `local` (in the obstacle's frame) placed by the obstacle's pose.
geometry_msgs::Pose placed(const Pose& obstacle_pose, const Vec3& local_position,
                           const Eigen::Quaterniond& local_orientation) {
  Pose local;
  local.position = local_position;
  local.orientation = local_orientation;
  return RosConversions::toPoseMessage(obstacle_pose.compose(local));
}

// Fields every marker of this node shares.
void initMarker(const std_msgs::Header& header, const std::string& ns, int id, int type,
                visualization_msgs::Marker& marker) {
  marker.header = header;
  marker.ns = ns;
  marker.id = id;
  marker.type = type;
  marker.action = visualization_msgs::Marker::ADD;
  marker.pose.orientation.w = 1.0;  // rviz warns about (and ignores) an unnormalised quaternion
  marker.scale.x = marker.scale.y = marker.scale.z = 1.0;
}

}  // namespace

geometry_msgs::Point RosConversions::toPoint(const Vec3& v) {
  geometry_msgs::Point p;
  p.x = v.x();
  p.y = v.y();
  p.z = v.z();
  return p;
}

geometry_msgs::Vector3 RosConversions::toVector3(const Vec3& v) {
  geometry_msgs::Vector3 m;
  m.x = v.x();
  m.y = v.y();
  m.z = v.z();
  return m;
}

geometry_msgs::Pose RosConversions::toPoseMessage(const Pose& pose) {
  geometry_msgs::Pose msg;
  msg.position = toPoint(pose.position);
  msg.orientation.x = pose.orientation.x();
  msg.orientation.y = pose.orientation.y();
  msg.orientation.z = pose.orientation.z();
  msg.orientation.w = pose.orientation.w();
  return msg;
}

Pose RosConversions::fromPoseMessage(const geometry_msgs::Pose& msg) {
  Pose pose;
  pose.position = Vec3(msg.position.x, msg.position.y, msg.position.z);
  pose.orientation = Eigen::Quaterniond(msg.orientation.w, msg.orientation.x, msg.orientation.y,
                                        msg.orientation.z);
  pose.orientation.normalize();
  return pose;
}

void RosConversions::toStatsMessage(const Simulation& sim, SolverStats& msg) {
  const StepStats& stats = sim.stats();
  // sim.time() rather than stats.sim_time: it is 0 right after a reset, before the next step.
  msg.sim_time = sim.time();
  msg.step_wall_time = stats.step_wall_time;
  // Before the first step the stats are empty; the configured count is what will run.
  msg.substeps = stats.substeps > 0 ? stats.substeps : sim.solver().config().substeps;
  msg.iterations = stats.iterations;
  msg.max_strain = stats.max_strain;
  msg.mean_strain = stats.mean_strain;
  msg.max_penetration = stats.max_penetration;
  msg.degenerate_constraints = static_cast<std::uint32_t>(stats.degenerate_constraints);
  msg.truncated_self_collision_searches =
      static_cast<std::uint32_t>(sim.collisions().stats().truncated_searches);
  msg.restored_steps = static_cast<std::uint32_t>(sim.faultGuard().restoredSteps());
  const Simulation::AccuracyReport& accuracy = sim.accuracy();
  msg.target_max_strain = sim.scene().solver.target_max_strain;
  msg.target_penetration = sim.scene().solver.target_penetration;
  double structural_mean = 0.0;
  computeStructuralStrain(sim.particles(), sim.topology(), msg.structural_max_strain,
                          structural_mean);
  msg.target_met = accuracy.target_met;
  msg.target_budget_exhausted = accuracy.budget_exhausted;
  msg.substeps_run =
      static_cast<std::uint32_t>(accuracy.substeps_run > 0 ? accuracy.substeps_run : msg.substeps);
  msg.redone = static_cast<std::uint32_t>(accuracy.redos);
  msg.real_time_factor = 0.0;
  msg.rejected_inputs = 0;
}

void RosConversions::toStateMessage(const Simulation& sim, ClothState& msg) {
  const Particles& particles = sim.particles();
  const int n = particles.size();
  msg.positions.resize(n);
  msg.velocities.resize(n);
  for (int i = 0; i < n; ++i) {
    msg.positions[i] = toPoint(particles.position[i]);
    msg.velocities[i] = toVector3(particles.velocity[i]);
  }
  const std::vector<unsigned>& triangles = sim.topology().triangles;
  msg.triangles.assign(triangles.begin(), triangles.end());
  sim.kinematicIndices(msg.kinematic);
  toStatsMessage(sim, msg.stats);
}

bool RosConversions::toMeshMarker(const Simulation& sim, const std_msgs::Header& header,
                                  visualization_msgs::Marker& marker) {
  const std::vector<unsigned>& triangles = sim.topology().triangles;
  if (triangles.empty()) {
    return false;
  }
  initMarker(header, "cloth", 0, visualization_msgs::Marker::TRIANGLE_LIST, marker);
  marker.color = color(0.85f, 0.35f, 0.2f);
  marker.colors.clear();
  const Vec3Array& position = sim.particles().position;
  marker.points.resize(triangles.size());
  for (std::size_t k = 0; k < triangles.size(); ++k) {
    marker.points[k] = toPoint(position[triangles[k]]);
  }
  return true;
}

void RosConversions::toBackMarker(const Simulation& sim, const visualization_msgs::Marker& mesh,
                                  visualization_msgs::Marker& back) {
  back = mesh;
  back.ns = "cloth_back";
  back.color = color(0.6f, 0.25f, 0.15f);
  // Each particle's normal: the sum of its triangles' cross products (area-weighted), so the
  // back follows the cloth's surface through folds and corners alike.
  const std::vector<unsigned>& triangles = sim.topology().triangles;
  const Vec3Array& position = sim.particles().position;
  std::vector<Vec3> behind(position.size(), Vec3::Zero());
  for (std::size_t k = 0; k + 2 < triangles.size(); k += 3) {
    const Vec3& a = position[triangles[k]];
    const Vec3 n = (position[triangles[k + 1]] - a).cross(position[triangles[k + 2]] - a);
    for (int corner = 0; corner < 3; ++corner) behind[triangles[k + corner]] += n;
  }
  // Then each particle's place on the back. One whose triangles cancel (a degenerate or
  // folded-flat spot) keeps its position.
  const double depth = kBackSideDepth * sim.scene().cloth.thickness;
  for (std::size_t i = 0; i < behind.size(); ++i) {
    const double length = behind[i].norm();
    behind[i] = length > 0.0 ? Vec3(position[i] - (depth / length) * behind[i]) : position[i];
  }
  // The front's triangles wound the other way: corners 0, 2, 1.
  for (std::size_t k = 0; k + 2 < triangles.size(); k += 3) {
    back.points[k] = toPoint(behind[triangles[k]]);
    back.points[k + 1] = toPoint(behind[triangles[k + 2]]);
    back.points[k + 2] = toPoint(behind[triangles[k + 1]]);
  }
}

void RosConversions::toParticleMarkers(const Simulation& sim, const std_msgs::Header& header,
                                       visualization_msgs::MarkerArray& markers) {
  const Particles& particles = sim.particles();
  const SceneConfig& scene = sim.scene();

  visualization_msgs::Marker cloth;
  initMarker(header, "particles", 0, visualization_msgs::Marker::SPHERE_LIST, cloth);
  cloth.scale.x = cloth.scale.y = cloth.scale.z = 2.0 * scene.cloth.thickness;
  cloth.color = color(0.9f, 0.9f, 0.9f);
  const std_msgs::ColorRGBA free_color = color(0.9f, 0.9f, 0.9f);
  const std_msgs::ColorRGBA kinematic_color = color(0.1f, 0.4f, 1.0f);
  cloth.points.resize(particles.cloth_count);
  cloth.colors.resize(particles.cloth_count);
  for (int i = 0; i < particles.cloth_count; ++i) {
    cloth.points[i] = toPoint(particles.position[i]);
    cloth.colors[i] = particles.isKinematic(i) ? kinematic_color : free_color;
  }
  markers.markers.push_back(cloth);

  // Each rope as a LINE_STRIP of its diameter through its particles (namespace "ropes", id its
  // index in scene.ropes).
  int after_ropes = particles.cloth_count;
  for (std::size_t r = 0; r < sim.ropes().size(); ++r) {
    const Rod& rope = sim.ropes()[r];
    visualization_msgs::Marker line;
    initMarker(header, "ropes", static_cast<int>(r), visualization_msgs::Marker::LINE_STRIP, line);
    line.scale.x = 2.0 * rope.radius;
    line.color = color(0.85f, 0.45f, 0.15f);
    line.points.resize(rope.size());
    for (int k = 0; k < rope.size(); ++k) {
      line.points[k] = toPoint(particles.position[rope.first_particle + k]);
    }
    markers.markers.push_back(line);
    after_ropes = rope.first_particle + rope.size();
  }

  const int granular_count = particles.size() - after_ropes;
  if (granular_count <= 0) {
    return;
  }
  visualization_msgs::Marker granular;
  initMarker(header, "particles", 1, visualization_msgs::Marker::SPHERE_LIST, granular);
  granular.scale.x = granular.scale.y = granular.scale.z = 2.0 * scene.granular.radius;
  granular.color = color(0.8f, 0.7f, 0.4f);
  granular.points.reserve(granular_count);
  for (int i = after_ropes; i < particles.size(); ++i) {
    granular.points.push_back(toPoint(particles.position[i]));
  }
  markers.markers.push_back(granular);
}

void RosConversions::toObstacleMarkers(const Simulation& sim, const std_msgs::Header& header,
                                       visualization_msgs::MarkerArray& markers) {
  using visualization_msgs::Marker;
  const std_msgs::ColorRGBA solid = color(0.45f, 0.5f, 0.6f);
  const std_msgs::ColorRGBA ground = color(0.35f, 0.35f, 0.4f);
  const Eigen::Quaterniond identity = Eigen::Quaterniond::Identity();
  for (int k = 0; k < sim.obstacleCount(); ++k) {
    const Collider& obstacle = sim.obstacle(k);
    // The core's own local shape: the plane normal comes normalised together with its offset.
    const Shape& shape = obstacle.shape;
    const auto add = [&](int part, int type, const Vec3& local_position,
                         const Eigen::Quaterniond& local_orientation, const Vec3& scale) {
      Marker marker;
      initMarker(header, "obstacles", 3 * k + part, type, marker);
      marker.pose = placed(obstacle.pose, local_position, local_orientation);
      marker.scale.x = scale.x();
      marker.scale.y = scale.y();
      marker.scale.z = scale.z();
      marker.color = shape.type == ShapeType::kPlane ? ground : solid;
      markers.markers.push_back(marker);
    };
    switch (shape.type) {
      case ShapeType::kSphere:
        add(0, Marker::SPHERE, Vec3::Zero(), identity, Vec3::Constant(2.0 * shape.radius));
        break;
      case ShapeType::kBox:
        add(0, Marker::CUBE, Vec3::Zero(), identity, 2.0 * shape.half_extents);
        break;
      case ShapeType::kCapsule: {
        // rviz's CYLINDER runs along its local z, like the capsule's segment.
        const double diameter = 2.0 * shape.radius;
        add(0, Marker::CYLINDER, Vec3::Zero(), identity,
            Vec3(diameter, diameter, 2.0 * shape.half_length));
        add(1, Marker::SPHERE, Vec3(0.0, 0.0, shape.half_length), identity,
            Vec3::Constant(diameter));
        add(2, Marker::SPHERE, Vec3(0.0, 0.0, -shape.half_length), identity,
            Vec3::Constant(diameter));
        break;
      }
      case ShapeType::kCylinder: {
        const double diameter = 2.0 * shape.radius;
        add(0, Marker::CYLINDER, Vec3::Zero(), identity,
            Vec3(diameter, diameter, 2.0 * shape.half_length));
        break;
      }
      case ShapeType::kMesh: {
        // The collision mesh itself, as the solver sees it (after welding and scaling).
        add(0, Marker::TRIANGLE_LIST, Vec3::Zero(), identity, Vec3::Ones());
        Marker& marker = markers.markers.back();
        const auto& vertices = shape.mesh->vertices();
        marker.points.reserve(3 * shape.mesh->triangleCount());
        for (const auto& triangle : shape.mesh->triangles()) {
          for (int v : triangle) marker.points.push_back(toPoint(vertices[v]));
        }
        break;
      }
      case ShapeType::kPlane: {
        // A square below the cloth's starting place, its top face on the plane.
        const Vec3 centre = obstacle.pose.orientation.conjugate() *
                            (initialClothCentre(sim) - obstacle.pose.position);
        const Vec3 on_plane = centre - (shape.normal.dot(centre) - shape.offset) * shape.normal;
        add(0, Marker::CUBE, on_plane - 0.5 * kPlaneMarkerThickness * shape.normal,
            Eigen::Quaterniond::FromTwoVectors(Vec3::UnitZ(), shape.normal),
            Vec3(kPlaneMarkerSize, kPlaneMarkerSize, kPlaneMarkerThickness));
        break;
      }
    }
  }
}

void RosConversions::toGripperMarkers(const Simulation& sim, const std_msgs::Header& header,
                                      visualization_msgs::MarkerArray& markers) {
  for (int g = 0; g < sim.grippers().count(); ++g) {
    visualization_msgs::Marker marker;
    initMarker(header, "grippers", g, visualization_msgs::Marker::SPHERE, marker);
    marker.pose = toPoseMessage(sim.grippers().pose(g));
    marker.scale.x = marker.scale.y = marker.scale.z = 2.0 * sim.scene().grippers[g].radius;
    marker.color = sim.grippers().grasping(g) ? color(0.2f, 0.8f, 0.2f, 0.5f)
                                              : color(0.95f, 0.85f, 0.2f, 0.5f);
    markers.markers.push_back(marker);
  }
}

void RosConversions::toMarkerArray(const Simulation& sim, const std_msgs::Header& header,
                                   visualization_msgs::MarkerArray& markers) {
  markers.markers.clear();
  visualization_msgs::Marker mesh;
  if (toMeshMarker(sim, header, mesh)) {
    visualization_msgs::Marker back;
    toBackMarker(sim, mesh, back);
    markers.markers.push_back(mesh);
    markers.markers.push_back(back);
  }
  toParticleMarkers(sim, header, markers);
  toObstacleMarkers(sim, header, markers);
  toGripperMarkers(sim, header, markers);
}

}  // namespace pbd_cloth
