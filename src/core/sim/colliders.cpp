#include "pbd_cloth/sim/colliders.h"

namespace pbd_cloth {

Shape makeShape(const ObstacleConfig& obstacle) {
  Shape shape;
  shape.type = obstacle.shape;
  shape.radius = obstacle.radius;
  shape.half_length = 0.5 * obstacle.length;
  shape.half_extents = 0.5 * obstacle.size;
  const double norm = obstacle.normal.norm();
  shape.normal = norm > 0.0 ? Vec3(obstacle.normal / norm) : Vec3::UnitZ();
  shape.offset = norm > 0.0 ? obstacle.offset / norm : obstacle.offset;
  shape.mesh = obstacle.mesh_data;
  shape.padding = obstacle.padding;
  return shape;
}

}  // namespace pbd_cloth
