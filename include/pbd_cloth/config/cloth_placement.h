// Where the cloth of a scene starts: used by the builder (sim/cloth_builder.h), which places the
// particles there, and by validate(), which checks them against the bounds without building the
// cloth.
#pragma once

#include <Eigen/Core>

#include "pbd_cloth/config/scene_config.h"
#include "pbd_cloth/geometry/pose.h"
#include "pbd_cloth/geometry/vector_types.h"

namespace pbd_cloth {

// Where the cloth starts, with `rotation` = rotationFromRpy(cloth.rpy): grid particle (r, c) at
// origin + R (c s, -r s, 0), and a mesh vertex (file units) at origin + R (mesh_scale v). The
// builder places the particles there and validate() checks them against the bounds.
inline Vec3 gridStartPosition(const ClothConfig& cloth, const Eigen::Matrix3d& rotation, int r,
                              int c) {
  return cloth.origin + rotation * Vec3(c * cloth.spacing, -r * cloth.spacing, 0.0);
}
inline Vec3 meshStartPosition(const ClothConfig& cloth, const Eigen::Matrix3d& rotation,
                              const Vec3& vertex) {
  return cloth.origin + rotation * (cloth.mesh_scale * vertex);
}

}  // namespace pbd_cloth
