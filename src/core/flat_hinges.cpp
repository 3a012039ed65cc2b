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

// Coordinate by coordinate, in the operation order of the AVX2 lanes below:
// dlambda = (g_1 (x_1 - x_0) + g_2 (x_2 - x_0)) + g_3 (x_3 - x_0) - decay lambda.
double projectPortable(const FlatHinge* hinge, int count, bool lambda_from_zero, bool track_change,
                       double* x, double* lambda) {
  double largest_sq = 0.0;
  for (int c = 0; c < count; ++c) {
    const FlatHinge& h = hinge[c];
    if (h.largest_move == 0.0) {
      if (lambda_from_zero) lambda[3 * c] = lambda[3 * c + 1] = lambda[3 * c + 2] = 0.0;
      continue;
    }
    double* corner[4] = {x + 3 * h.index[0], x + 3 * h.index[1], x + 3 * h.index[2],
                         x + 3 * h.index[3]};
    double dlambda[3];
    for (int d = 0; d < 3; ++d) {
      const double x0 = corner[0][d];
      const double sum = (h.gain[0] * (corner[1][d] - x0) + h.gain[1] * (corner[2][d] - x0)) +
                         h.gain[2] * (corner[3][d] - x0);
      if (lambda_from_zero) {
        dlambda[d] = sum;
        lambda[3 * c + d] = sum;
      } else {
        dlambda[d] = sum - h.decay * lambda[3 * c + d];
        lambda[3 * c + d] += dlambda[d];
      }
      for (int v = 0; v < 4; ++v) corner[v][d] += h.move[v] * dlambda[d];
    }
    if (track_change) {
      const double dlambda_sq =
          (dlambda[0] * dlambda[0] + dlambda[1] * dlambda[1]) + dlambda[2] * dlambda[2];
      largest_sq = std::max(largest_sq, h.largest_move * h.largest_move * dlambda_sq);
    }
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

PBD_AVX2 double projectAvx2(const FlatHinge* hinge, int count, bool lambda_from_zero,
                            bool track_change, double* x, double* lambda) {
  double largest_sq = 0.0;
  for (int c = 0; c < count; ++c) {
    const FlatHinge& h = hinge[c];
    double* hinge_lambda = lambda + 3 * c;
    if (h.largest_move == 0.0) {
      if (lambda_from_zero) storeXyz(hinge_lambda, _mm256_setzero_pd());
      continue;
    }
    double* corner[4] = {x + 3 * h.index[0], x + 3 * h.index[1], x + 3 * h.index[2],
                         x + 3 * h.index[3]};
    // Four different particles (flat_hinges.h): each read once, moved from what was read.
    const __m256d x0 = loadXyz(corner[0]);
    const __m256d x1 = loadXyz(corner[1]);
    const __m256d x2 = loadXyz(corner[2]);
    const __m256d x3 = loadXyz(corner[3]);
    const __m256d sum = _mm256_add_pd(
        _mm256_add_pd(_mm256_mul_pd(_mm256_set1_pd(h.gain[0]), _mm256_sub_pd(x1, x0)),
                      _mm256_mul_pd(_mm256_set1_pd(h.gain[1]), _mm256_sub_pd(x2, x0))),
        _mm256_mul_pd(_mm256_set1_pd(h.gain[2]), _mm256_sub_pd(x3, x0)));
    __m256d dlambda = sum;
    if (lambda_from_zero) {
      storeXyz(hinge_lambda, sum);
    } else {
      const __m256d old_lambda = loadXyz(hinge_lambda);
      dlambda = _mm256_sub_pd(sum, _mm256_mul_pd(_mm256_set1_pd(h.decay), old_lambda));
      storeXyz(hinge_lambda, _mm256_add_pd(old_lambda, dlambda));
    }
    storeXyz(corner[0], _mm256_add_pd(x0, _mm256_mul_pd(_mm256_set1_pd(h.move[0]), dlambda)));
    storeXyz(corner[1], _mm256_add_pd(x1, _mm256_mul_pd(_mm256_set1_pd(h.move[1]), dlambda)));
    storeXyz(corner[2], _mm256_add_pd(x2, _mm256_mul_pd(_mm256_set1_pd(h.move[2]), dlambda)));
    storeXyz(corner[3], _mm256_add_pd(x3, _mm256_mul_pd(_mm256_set1_pd(h.move[3]), dlambda)));
    if (track_change) {
      alignas(32) double d[4];
      _mm256_store_pd(d, dlambda);
      const double dlambda_sq = (d[0] * d[0] + d[1] * d[1]) + d[2] * d[2];
      largest_sq = std::max(largest_sq, h.largest_move * h.largest_move * dlambda_sq);
    }
  }
  return largest_sq;
}
#endif

}  // namespace

double projectFlatHinges(const FlatHinge* hinge, int count, bool lambda_from_zero,
                         bool track_change, bool simd, double* x, double* lambda) {
  double largest_sq = 0.0;
#ifdef PBD_CLOTH_HAVE_AVX2_PATH
  if (simd && stretchLinksUseAvx2()) {
    largest_sq = projectAvx2(hinge, count, lambda_from_zero, track_change, x, lambda);
  } else {
    largest_sq = projectPortable(hinge, count, lambda_from_zero, track_change, x, lambda);
  }
#else
  (void)simd;
  largest_sq = projectPortable(hinge, count, lambda_from_zero, track_change, x, lambda);
#endif
  return std::sqrt(largest_sq);
}

}  // namespace pbd_cloth
