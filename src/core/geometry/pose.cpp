#include "pbd_cloth/geometry/pose.h"

namespace pbd_cloth {

Pose interpolate(const Pose& a, const Pose& b, double s) {
  Pose out;
  out.position = (1.0 - s) * a.position + s * b.position;
  out.orientation = a.orientation.slerp(s, b.orientation);
  return out;
}

Eigen::Matrix3d rotationFromRpy(const Eigen::Vector3d& rpy) {
  return (Eigen::AngleAxisd(rpy.z(), Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(rpy.y(), Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(rpy.x(), Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

Frame frameFromPose(const Pose& pose) {
  Frame frame;
  frame.rotation = pose.orientation.normalized().toRotationMatrix();
  frame.translation = pose.position;
  return frame;
}

Frame interpolateFrame(const Pose& a, const Pose& b, double s) {
  Frame frame;
  frame.rotation =
      a.orientation.normalized().slerp(s, b.orientation.normalized()).toRotationMatrix();
  frame.translation = (1.0 - s) * a.position + s * b.position;
  return frame;
}

}  // namespace pbd_cloth
