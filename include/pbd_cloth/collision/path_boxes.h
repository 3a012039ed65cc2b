// The boxes of the free particles' paths over a substep, grown by each one's radius, and their
// union: what the obstacles' first pass culls with (Collisions::projectBlockFirstPass), a block of
// particles at a time.
//
// Why a file of its own: the pass computes one box a particle at every substep, for every particle
// of a cloth lying on its obstacles (fabric_table: 11 % of the step in the scalar loop before, the
// running union's minimum and maximum and the box's store and reload its bound). With x y z in the
// lanes of one 256-bit register a box is two loads, four operations and two stores. As for the
// stretch links and the flat hinges the path is chosen at run time: AVX-512VL (masked loads of x y
// z) where the processor has it, else AVX2, else the portable loop. Minimum, maximum, sum and
// difference are exact, so all three give the same boxes to the bit (test_core: PathBoxes.*).
#pragma once

#include <Eigen/Core>
#include <cstdint>

#include "pbd_cloth/model/particles.h"

namespace pbd_cloth {

// One particle's path box: lo = min(start, x) - r, hi = max(start, x) + r, coordinate by
// coordinate, in lanes 0-2 (lane 3 is padding, which no test reads). Aligned for one register.
struct alignas(32) PathBox {
  double lo[4];
  double hi[4];
  Eigen::Map<const Eigen::Array3d> low() const { return Eigen::Map<const Eigen::Array3d>(lo); }
  Eigen::Map<const Eigen::Array3d> high() const { return Eigen::Map<const Eigen::Array3d>(hi); }
};

// One particle's path box into Eigen arrays: the portable kernel's arithmetic, which the obstacle
// pass also uses for one particle and one obstacle (Collisions::projectObstaclesOn), so that a
// block's box holds each of its particles' to the last bit. Eigen's minimum and maximum are
// std::min and std::max: min(x, start) is start where start < x, else x.
inline void pathBox(const Vec3& x, const Vec3& start, double r, Eigen::Array3d& lo,
                    Eigen::Array3d& hi) {
  lo = x.cwiseMin(start).array() - r;
  hi = x.cwiseMax(start).array() + r;
}

// Which loop computes a block's boxes: the best the processor has (bestPathBoxKernel), or a
// slower one for the tests and for solver.simd / solver.avx512 false.
enum class PathBoxKernel { kPortable, kAvx2, kAvx512Vl };

// The fastest kernel this processor runs, within what simd and avx512 allow (solver.simd,
// solver.avx512).
PathBoxKernel bestPathBoxKernel(bool simd, bool avx512);

// The path boxes of the free particles of [begin, end) (inverse mass not 0) into box[i - begin],
// from substep_start[i] to position[i] grown by radius[i]; kinematic particles' slots are left
// as they were. Their union into lo, hi (lo = +inf, hi = -inf when every particle is kinematic).
// Returns true when some box is not one (a coordinate not a number, or lo above hi): the union,
// whose minimum and maximum drop a NaN, then does not hold it. Allocates nothing.
bool computePathBoxes(PathBoxKernel kernel, const Particles& particles, int begin, int end,
                      PathBox* box, Eigen::Array3d& lo, Eigen::Array3d& hi);
// The same from `start` instead of substep_start: with start = position, each particle's sphere's
// box x -/+ r (min(x, x) is x), as the pre-stabilization culls by.
bool computePathBoxes(PathBoxKernel kernel, const Particles& particles, const Vec3Array& start,
                      int begin, int end, PathBox* box, Eigen::Array3d& lo, Eigen::Array3d& hi);

// A world box [lo, hi] in PathBox's lanes, lane 3 from -inf to +inf so that it neither keeps a
// particle's box out nor leaves one outside (an obstacle's bounds, the scene's bounds).
PathBox boxOfBounds(const Vec3& lo, const Vec3& hi);

// The most obstacles reachedObstacles tests (a bit each).
constexpr int kMostReachTests = 64;

// For each free particle of [begin, end), from the boxes computePathBoxes wrote with the same
// kernel: bit q of reach[i - begin] set when its box reaches obstacle[q] (q < min(count,
// kMostReachTests); the boxes share a point, as !boxesApart), and inside[i - begin] = 1 when its
// box lies inside `bounds` (lo >= bounds.lo and hi <= bounds.hi), else 0. Comparisons with a NaN
// are false, as in the scalar tests (boxesApart): a NaN coordinate keeps no obstacle out, and
// a box with one is inside nothing.
// Kinematic particles' slots are left as they were. Allocates nothing.
void reachedObstacles(PathBoxKernel kernel, const Particles& particles, int begin, int end,
                      const PathBox* box, const PathBox* obstacle, int count, const PathBox& bounds,
                      std::uint64_t* reach, unsigned char* inside);

}  // namespace pbd_cloth
