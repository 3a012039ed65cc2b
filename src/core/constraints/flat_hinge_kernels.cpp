// The flat hinges' projection kernels (portable, AVX2, AVX-512VL), which round alike (built with
// -ffp-contract=off, as every *_kernels*.cpp: CMakeLists.txt), and the per-step terms they read
// (makeFlatHinge), under the same flags.
#include "pbd_cloth/constraints/flat_hinges.h"

#include <algorithm>
#include <cmath>

#include "pbd_cloth/constraints/stretch_links.h"
#include "pbd_cloth/parallel/cpu_features.h"

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define PBD_CLOTH_HAVE_AVX2_PATH 1
#endif

namespace pbd_cloth {

namespace {

// Coordinate by coordinate, in the operation order of the AVX2 lanes below:
// dlambda = (g_1 (x_1 - x_0) + g_2 (x_2 - x_0)) + g_3 (x_3 - x_0) - decay lambda.
double projectPortable(const FlatHinge* hinge, int count, bool lambda_from_zero,
                       bool keep_multipliers, bool track_change, double* x, double* lambda) {
  double largest_sq = 0.0;
  for (int c = 0; c < count; ++c) {
    const FlatHinge& h = hinge[c];
    const bool keep = keep_multipliers || h.reaction;
    if (h.largest_move == 0.0) {
      if (lambda_from_zero && keep) lambda[3 * c] = lambda[3 * c + 1] = lambda[3 * c + 2] = 0.0;
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
        if (keep) lambda[3 * c + d] = sum;
      } else {
        dlambda[d] = sum - h.decay * lambda[3 * c + d];
        if (keep) lambda[3 * c + d] += dlambda[d];
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
#define PBD_AVX512VL __attribute__((target("avx512f,avx512vl")))

// How a register takes one particle's x y z (lane 3 zero) and a hinge's setting: the two
// instruction sets differ only here. Neither reads or writes the double after z, so the last
// particle of the array is safe.
// AVX2: a 16-byte and an 8-byte access. Its masked loads and stores would do the same, at
// several times the cost on some processors (measured here: slower than scalar code).
// (Registers pass by reference: a function that takes or returns one by value, compiled without
// AVX, would have another calling convention; GCC warns of it, -Wpsabi.)
struct Avx2Xyz {
  PBD_AVX2 static void load(const double* p, __m256d& v) {
    v = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(p)), _mm_load_sd(p + 2), 1);
  }
  PBD_AVX2 static void store(double* p, const __m256d& v) {
    _mm_storeu_pd(p, _mm256_castpd256_pd128(v));
    _mm_store_sd(p + 2, _mm256_extractf128_pd(v, 1));
  }
  PBD_AVX2 static void loadLambda(const double* p, __m256d& v) { load(p, v); }
  PBD_AVX2 static void storeLambda(double* p, const __m256d& v) { store(p, v); }
  PBD_AVX2 static void broadcast(double value, __m256d& v) { v = _mm256_set1_pd(value); }
  PBD_AVX2 static double squaredNorm(const __m256d& v) {
    alignas(32) double d[4];
    _mm256_store_pd(d, v);
    return (d[0] * d[0] + d[1] * d[1]) + d[2] * d[2];
  }
};

// AVX-512VL: one masked access of three lanes each way, where AVX2 needs two and a shuffle. The
// pass reads 4 corners and writes 4 a hinge, and those accesses and the instructions around them,
// not its arithmetic, bound it (doc/journal.md, "2026-11-29: Flat hinges through masked accesses").
struct Avx512VlXyz {
  static constexpr __mmask8 kXyz = 0x7;
  PBD_AVX512VL static void load(const double* p, __m256d& v) { v = _mm256_maskz_loadu_pd(kXyz, p); }
  PBD_AVX512VL static void store(double* p, const __m256d& v) { _mm256_mask_storeu_pd(p, kXyz, v); }
  // A hinge's multipliers, three doubles each, lie back to back: a masked store spans the next
  // hinge's first one, and a masked load of that is then held until the store has left (the
  // pass at more than one iteration took twice AVX2's time). The two exact accesses instead.
  PBD_AVX512VL static void loadLambda(const double* p, __m256d& v) { Avx2Xyz::load(p, v); }
  PBD_AVX512VL static void storeLambda(double* p, const __m256d& v) { Avx2Xyz::store(p, v); }
  PBD_AVX512VL static void broadcast(double value, __m256d& v) { v = _mm256_set1_pd(value); }
  PBD_AVX512VL static double squaredNorm(const __m256d& v) { return Avx2Xyz::squaredNorm(v); }
};

// projectPortable's arithmetic with a hinge's three coordinates in the lanes of one register, in
// the same operations and order (GCC's vector operators, compiled to the caller's instruction
// set: no contraction into fused multiply-adds, so the same roundings and the same bits).
// kKeepAll: every hinge writes its multipliers (a later pass reads them), with no test a hinge.
template <class A, bool kKeepAll>
inline double sweepHinges(const FlatHinge* hinge, int count, bool lambda_from_zero,
                          bool track_change, double* x, double* lambda) {
  double largest_sq = 0.0;
  __m256d zero, gain[3], decay, move[4];
  A::broadcast(0.0, zero);
  for (int c = 0; c < count; ++c) {
    const FlatHinge& h = hinge[c];
    double* hinge_lambda = lambda + 3 * c;
    const bool keep = kKeepAll || h.reaction;
    if (h.largest_move == 0.0) {
      if (lambda_from_zero && keep) A::storeLambda(hinge_lambda, zero);
      continue;
    }
    double* corner[4] = {x + 3 * h.index[0], x + 3 * h.index[1], x + 3 * h.index[2],
                         x + 3 * h.index[3]};
    // Four different particles (flat_hinges.h): each read once, moved from what was read.
    __m256d x0, x1, x2, x3;
    A::load(corner[0], x0);
    A::load(corner[1], x1);
    A::load(corner[2], x2);
    A::load(corner[3], x3);
    for (int k = 0; k < 3; ++k) A::broadcast(h.gain[k], gain[k]);
    for (int k = 0; k < 4; ++k) A::broadcast(h.move[k], move[k]);
    const __m256d sum = (gain[0] * (x1 - x0) + gain[1] * (x2 - x0)) + gain[2] * (x3 - x0);
    __m256d dlambda = sum;
    if (lambda_from_zero) {
      if (keep) A::storeLambda(hinge_lambda, sum);
    } else {
      __m256d old_lambda;
      A::loadLambda(hinge_lambda, old_lambda);
      A::broadcast(h.decay, decay);
      dlambda = sum - decay * old_lambda;
      if (keep) A::storeLambda(hinge_lambda, old_lambda + dlambda);
    }
    A::store(corner[0], x0 + move[0] * dlambda);
    A::store(corner[1], x1 + move[1] * dlambda);
    A::store(corner[2], x2 + move[2] * dlambda);
    A::store(corner[3], x3 + move[3] * dlambda);
    if (track_change) {
      largest_sq = std::max(largest_sq, h.largest_move * h.largest_move * A::squaredNorm(dlambda));
    }
  }
  return largest_sq;
}

template <class A>
inline double projectHinges(const FlatHinge* hinge, int count, bool lambda_from_zero,
                            bool keep_multipliers, bool track_change, double* x, double* lambda) {
  return keep_multipliers
             ? sweepHinges<A, true>(hinge, count, lambda_from_zero, track_change, x, lambda)
             : sweepHinges<A, false>(hinge, count, lambda_from_zero, track_change, x, lambda);
}

__attribute__((flatten)) PBD_AVX2 double projectAvx2(const FlatHinge* hinge, int count,
                                                     bool lambda_from_zero, bool keep_multipliers,
                                                     bool track_change, double* x, double* lambda) {
  return projectHinges<Avx2Xyz>(hinge, count, lambda_from_zero, keep_multipliers, track_change, x,
                                lambda);
}

__attribute__((flatten)) PBD_AVX512VL double projectAvx512Vl(const FlatHinge* hinge, int count,
                                                             bool lambda_from_zero,
                                                             bool keep_multipliers,
                                                             bool track_change, double* x,
                                                             double* lambda) {
  return projectHinges<Avx512VlXyz>(hinge, count, lambda_from_zero, keep_multipliers, track_change,
                                    x, lambda);
}
#endif

}  // namespace

bool flatHingesUseAvx512Vl() { return cpuHasAvx512Vl(); }

FlatHinge makeFlatHinge(const BendConstraint& con, const double* inverse_mass, double alpha,
                        double k, double min_weight) {
  FlatHinge hinge;
  double w = 0.0, largest = 0.0;
  const bool reaction = joinsKinematicToFree(con, inverse_mass);
  for (int v = 0; v < 4; ++v) {
    const double wv = inverse_mass[con.index[v]];
    w += wv * con.weight[v] * con.weight[v];
    hinge.index[v] = con.index[v];
    hinge.move[v] = wv * con.weight[v] * con.scale;
    largest = std::max(largest, std::abs(hinge.move[v]));
  }
  w *= con.scale * con.scale;
  if (w < min_weight) {  // no free corner: skipped (largest_move 0)
    FlatHinge skipped;
    skipped.reaction = reaction;
    return skipped;
  }
  hinge.reaction = reaction;
  const double inverse_denominator = 1.0 / (w + alpha);
  for (int v = 0; v < 3; ++v)
    hinge.gain[v] = -k * con.scale * con.weight[v + 1] * inverse_denominator;
  hinge.decay = alpha * inverse_denominator;
  hinge.largest_move = largest;
  return hinge;
}

double projectFlatHinges(const FlatHinge* hinge, int count, bool lambda_from_zero,
                         bool keep_multipliers, bool track_change, bool simd, bool avx512,
                         double* x, double* lambda) {
  double largest_sq = 0.0;
#ifdef PBD_CLOTH_HAVE_AVX2_PATH
  if (simd && avx512 && flatHingesUseAvx512Vl()) {
    largest_sq =
        projectAvx512Vl(hinge, count, lambda_from_zero, keep_multipliers, track_change, x, lambda);
  } else if (simd && stretchLinksUseAvx2()) {
    largest_sq =
        projectAvx2(hinge, count, lambda_from_zero, keep_multipliers, track_change, x, lambda);
  } else {
    largest_sq =
        projectPortable(hinge, count, lambda_from_zero, keep_multipliers, track_change, x, lambda);
  }
#else
  (void)simd;
  (void)avx512;
  largest_sq =
      projectPortable(hinge, count, lambda_from_zero, keep_multipliers, track_change, x, lambda);
#endif
  return std::sqrt(largest_sq);
}

}  // namespace pbd_cloth
