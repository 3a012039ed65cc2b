#include "pbd_cloth/flat_hinges.h"

#include <algorithm>
#include <cmath>

#include "pbd_cloth/stretch_links.h"

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define PBD_CLOTH_HAVE_AVX2_PATH 1
#endif

namespace pbd_cloth {

namespace {

// Coordinate by coordinate, in the operation order of the AVX2 lanes below: b = K_1 (x_1 - x_0) +
// K_2 (x_2 - x_0) + K_3 (x_3 - x_0) (the K_k sum to zero), summed left to right.
double projectPortable(const BendConstraint* bend, int count, const FlatHingeStep& step, double k,
                       double alpha, double* x, double* lambda) {
  double largest_sq = 0.0;
  const double minus_k = -k;
  for (int c = 0; c < count; ++c) {
    const double inverse_denominator = step.inverse_denominator[c];
    if (inverse_denominator == 0.0) continue;
    const BendConstraint& con = bend[c];
    double* corner[4] = {x + 3 * con.index[0], x + 3 * con.index[1], x + 3 * con.index[2],
                         x + 3 * con.index[3]};
    const double* factor = step.factor + 4 * c;
    double direction[3];
    for (int d = 0; d < 3; ++d) {
      const double x0 = corner[0][d];
      const double b = con.weight[1] * (corner[1][d] - x0) + con.weight[2] * (corner[2][d] - x0) +
                       con.weight[3] * (corner[3][d] - x0);
      const double constraint = con.scale * b;
      const double dlambda =
          (minus_k * constraint - alpha * lambda[3 * c + d]) * inverse_denominator;
      lambda[3 * c + d] += dlambda;
      direction[d] = con.scale * dlambda;
      for (int v = 0; v < 4; ++v) corner[v][d] += factor[v] * direction[d];
    }
    const double direction_sq =
        (direction[0] * direction[0] + direction[1] * direction[1]) + direction[2] * direction[2];
    const double largest = step.largest_factor[c];
    largest_sq = std::max(largest_sq, largest * largest * direction_sq);
  }
  return largest_sq;
}

#ifdef PBD_CLOTH_HAVE_AVX2_PATH
#define PBD_AVX2 __attribute__((target("avx2")))

// x y z of one particle in lanes 0-2 (lane 3 zero): a 16-byte and an 8-byte access, never the
// double after z (the last particle of the array is safe). Masked loads and stores would do the
// same, at several times the cost on some processors (measured here: slower than scalar code).
PBD_AVX2 inline __m256d loadXyz(const double* p) {
  return _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(p)), _mm_load_sd(p + 2), 1);
}

PBD_AVX2 inline void storeXyz(double* p, __m256d v) {
  _mm_storeu_pd(p, _mm256_castpd256_pd128(v));
  _mm_store_sd(p + 2, _mm256_extractf128_pd(v, 1));
}

PBD_AVX2 double projectAvx2(const BendConstraint* bend, int count, const FlatHingeStep& step,
                            double k, double alpha, double* x, double* lambda) {
  const __m256d minus_k = _mm256_set1_pd(-k);
  const __m256d alpha_lanes = _mm256_set1_pd(alpha);
  double largest_sq = 0.0;
  for (int c = 0; c < count; ++c) {
    const double inverse_denominator = step.inverse_denominator[c];
    if (inverse_denominator == 0.0) continue;
    const BendConstraint& con = bend[c];
    double* corner[4] = {x + 3 * con.index[0], x + 3 * con.index[1], x + 3 * con.index[2],
                         x + 3 * con.index[3]};
    const __m256d x0 = loadXyz(corner[0]);
    const __m256d x1 = loadXyz(corner[1]);
    const __m256d x2 = loadXyz(corner[2]);
    const __m256d x3 = loadXyz(corner[3]);
    const __m256d b = _mm256_add_pd(
        _mm256_add_pd(_mm256_mul_pd(_mm256_set1_pd(con.weight[1]), _mm256_sub_pd(x1, x0)),
                      _mm256_mul_pd(_mm256_set1_pd(con.weight[2]), _mm256_sub_pd(x2, x0))),
        _mm256_mul_pd(_mm256_set1_pd(con.weight[3]), _mm256_sub_pd(x3, x0)));
    const __m256d scale = _mm256_set1_pd(con.scale);
    const __m256d constraint = _mm256_mul_pd(scale, b);
    double* hinge_lambda = lambda + 3 * c;
    const __m256d old_lambda = loadXyz(hinge_lambda);
    const __m256d dlambda = _mm256_mul_pd(
        _mm256_sub_pd(_mm256_mul_pd(minus_k, constraint), _mm256_mul_pd(alpha_lanes, old_lambda)),
        _mm256_set1_pd(inverse_denominator));
    storeXyz(hinge_lambda, _mm256_add_pd(old_lambda, dlambda));
    const __m256d direction = _mm256_mul_pd(scale, dlambda);
    // Corner by corner, each read again before its update: the scalar loop's order, also if two
    // corners were one particle.
    const double* factor = step.factor + 4 * c;
    for (int v = 0; v < 4; ++v) {
      const __m256d moved =
          _mm256_add_pd(loadXyz(corner[v]), _mm256_mul_pd(_mm256_set1_pd(factor[v]), direction));
      storeXyz(corner[v], moved);
    }
    alignas(32) double d[4];
    _mm256_store_pd(d, direction);
    const double direction_sq = (d[0] * d[0] + d[1] * d[1]) + d[2] * d[2];
    const double largest = step.largest_factor[c];
    largest_sq = std::max(largest_sq, largest * largest * direction_sq);
  }
  return largest_sq;
}
#endif

}  // namespace

double projectFlatHinges(const BendConstraint* bend, int count, const FlatHingeStep& step, double k,
                         double alpha, bool simd, double* x, double* lambda) {
  double largest_sq = 0.0;
#ifdef PBD_CLOTH_HAVE_AVX2_PATH
  if (simd && stretchLinksUseAvx2()) {
    largest_sq = projectAvx2(bend, count, step, k, alpha, x, lambda);
  } else {
    largest_sq = projectPortable(bend, count, step, k, alpha, x, lambda);
  }
#else
  (void)simd;
  largest_sq = projectPortable(bend, count, step, k, alpha, x, lambda);
#endif
  return std::sqrt(largest_sq);
}

}  // namespace pbd_cloth
