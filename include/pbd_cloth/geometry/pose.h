// Rigid placements: a Pose (position and unit quaternion, as the scene and ROS give it), a Frame
// (the same placement as a rotation matrix, for transforming many points), and their
// interpolation over a step.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "pbd_cloth/geometry/vector_types.h"

namespace pbd_cloth {

struct Pose {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();

  // The pose `local`, given in this pose's frame, expressed in the frame this pose is given in.
  Pose compose(const Pose& local) const {
    Pose out;
    out.position = position + orientation * local.position;
    out.orientation = (orientation * local.orientation).normalized();
    return out;
  }
};

// Pose interpolation used by trajectories and substeps: linear position, slerp orientation.
Pose interpolate(const Pose& a, const Pose& b, double s);

// A rigid placement: world = rotation * local + translation.
struct Frame {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Vec3 translation = Vec3::Zero();

  Vec3 toLocal(const Vec3& x) const { return rotation.transpose() * (x - translation); }
  Vec3 toWorld(const Vec3& x) const { return rotation * x + translation; }
};

// Rotation from roll, pitch and yaw (cloth.rpy): roll about x, then pitch about y, then yaw about
// z, R = Rz(yaw) Ry(pitch) Rx(roll).
Eigen::Matrix3d rotationFromRpy(const Eigen::Vector3d& rpy);

Frame frameFromPose(const Pose& pose);
// Pose at fraction s of the motion a -> b: linear position, slerp orientation (of the normalised
// quaternions, unlike interpolate: a frame must be a rotation whatever the poses' lengths).
Frame interpolateFrame(const Pose& a, const Pose& b, double s);

}  // namespace pbd_cloth
