// Core types <-> ROS messages, as small static converters (after grid_map's GridMapRosConverter):
// the only place that knows both the core's layout and the message layouts.
#pragma once

#include <geometry_msgs/Point.h>
#include <geometry_msgs/Pose.h>
#include <geometry_msgs/Vector3.h>
#include <std_msgs/Header.h>
#include <visualization_msgs/Marker.h>
#include <visualization_msgs/MarkerArray.h>

#include "pbd_cloth/ClothState.h"
#include "pbd_cloth/SolverStats.h"
#include "pbd_cloth/config/scene_config.h"
#include "pbd_cloth/sim/simulation.h"

namespace pbd_cloth {

class RosConversions {
 public:
  static geometry_msgs::Point toPoint(const Vec3& v);
  static geometry_msgs::Vector3 toVector3(const Vec3& v);
  static geometry_msgs::Pose toPoseMessage(const Pose& pose);
  // Normalises the quaternion: a hand-written pose message is rarely exactly unit length.
  static Pose fromPoseMessage(const geometry_msgs::Pose& msg);

  // Everything the simulation knows about the last step; real_time_factor and rejected_inputs
  // belong to the node and are left at 0.
  static void toStatsMessage(const Simulation& sim, SolverStats& msg);

  // Positions, velocities, triangles, kinematic indices and stats. The header is the caller's.
  static void toStateMessage(const Simulation& sim, ClothState& msg);

  // ns `cloth`: the mesh as a TRIANGLE_LIST, one point per triangle corner. No per-vertex colours,
  // since rviz lights a triangle list only without them. Empty for a rope (no triangles).
  static bool toMeshMarker(const Simulation& sim, const std_msgs::Header& header,
                           visualization_msgs::Marker& marker);

  // ns `cloth_back`: rviz lights a TRIANGLE_LIST from one side only (seen from behind, the cloth
  // was black), so the back is the mesh's triangles wound the other way, a shade darker (the two
  // sides of a fold tell apart), drawn half a thickness behind the front along each particle's
  // normal: on the front's own points the two would fight for the same depth.
  static void toBackMarker(const Simulation& sim, const visualization_msgs::Marker& mesh,
                           visualization_msgs::Marker& back);

  // ns `particles`: id 0 the cloth particles (kinematic ones highlighted), id 1 the granular ones,
  // each a SPHERE_LIST whose diameter is twice the contact radius.
  static void toParticleMarkers(const Simulation& sim, const std_msgs::Header& header,
                                visualization_msgs::MarkerArray& markers);

  // ns `obstacles`: each obstacle in its own shape at its current pose (SPHERE, CUBE, a CYLINDER
  // and two SPHEREs for a capsule, a large thin CUBE for a plane). Obstacle k owns ids 3k..3k+2,
  // so every id keeps its shape for the whole run and rviz updates it in place.
  static void toObstacleMarkers(const Simulation& sim, const std_msgs::Header& header,
                                visualization_msgs::MarkerArray& markers);

  // ns `grippers`: a SPHERE of the grasp radius at each gripper (id = gripper index), green while
  // it holds particles, yellow while open; translucent so the grasped particles show.
  static void toGripperMarkers(const Simulation& sim, const std_msgs::Header& header,
                               visualization_msgs::MarkerArray& markers);

  // The whole ~markers message.
  static void toMarkerArray(const Simulation& sim, const std_msgs::Header& header,
                            visualization_msgs::MarkerArray& markers);
};

}  // namespace pbd_cloth
