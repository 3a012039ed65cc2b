// The basic vector types of the whole package: Eigen's, in double precision.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>  // cross products
#include <vector>

namespace pbd_cloth {

using Vec3 = Eigen::Vector3d;
// Double precision throughout: at 1000 Hz x 100 substeps one substep moves a particle h^2 g = 1e-9
// m, below float32 resolution near 1 m (REFERENCE_CASES.md, "Precision").
using Vec3Array = std::vector<Vec3>;

}  // namespace pbd_cloth
