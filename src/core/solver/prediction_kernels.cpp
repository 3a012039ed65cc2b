// The prediction and velocity update kernels (prediction_kernels.h): one body, inlined into an
// AVX2 build and the baseline. Built, as every *_kernels*.cpp, with -ffp-contract=off
// (CMakeLists.txt).
#include "pbd_cloth/solver/prediction_kernels.h"

namespace pbd_cloth {

namespace {

#if defined(__GNUC__)
#define PBD_INLINE inline __attribute__((always_inline))
#else
#define PBD_INLINE inline
#endif

// One coordinate k of a particle: the prediction x~ = x + h (e^{-c h} v + h g) of a substep, and
// the velocity update v <- v + (x - x~) / h that ends it (why in that form: Solver::
// updateVelocities). The update needs no stored x~: while a substep runs nothing writes v or the
// substep's start, so start + h v is the prediction again, to the bit (the same operands and
// operation as x += h v).
PBD_INLINE void predictCoordinate(int k, double dv, const PredictArgs& a, double* __restrict x,
                                  double* __restrict v, double* __restrict start) {
  start[k] = x[k];
  v[k] = a.keep * v[k] + dv;
  x[k] += a.h * v[k];
}

PBD_INLINE void updateCoordinate(int k, const PredictArgs& a, const double* __restrict x,
                                 double* __restrict v, const double* __restrict start) {
  v[k] += (x[k] - (start[k] + a.h * v[k])) * a.inv_h;
}

// Over particles [begin, end), four (twelve coordinates, three AVX2 registers) at a time, the
// rest one by one: one loop with no branch over distinct arrays (restrict), straight vector code.
// `update` ends the last substep first, `predict` starts the next: both in one pass over the
// arrays (Solver::updateAndPredict) read and write each coordinate once instead of twice.
template <bool update, bool predict>
PBD_INLINE void advanceFree(const PredictArgs& a) {
  double* __restrict x = a.x;
  double* __restrict v = a.v;
  double* __restrict start = a.start;
  const double dv[12] = {a.dv_x, a.dv_y, a.dv_z, a.dv_x, a.dv_y, a.dv_z,
                         a.dv_x, a.dv_y, a.dv_z, a.dv_x, a.dv_y, a.dv_z};
  auto advance = [&](int k, int q) {
    if (update) updateCoordinate(k, a, x, v, start);
    if (predict) predictCoordinate(k, dv[q], a, x, v, start);
  };
  int i = a.begin;
  for (; i + 4 <= a.end; i += 4) {
    for (int q = 0; q < 12; ++q) advance(3 * i + q, q);
  }
  for (; i < a.end; ++i) {
    for (int d = 0; d < 3; ++d) advance(3 * i + d, d);
  }
}

// The same on the particles' columns (Solver::advance in a step of links alone): x, v and
// start each hold the x column, then the y and the z column, `stride` apart; the same operations
// on each coordinate, so the same result to the bit.
template <bool update, bool predict>
PBD_INLINE void advanceFreeColumns(const PredictArgs& a, int stride) {
  double* __restrict x = a.x;
  double* __restrict v = a.v;
  double* __restrict start = a.start;
  const double dv[3] = {a.dv_x, a.dv_y, a.dv_z};
  for (int d = 0; d < 3; ++d) {
    const int end = d * stride + a.end;
    for (int k = d * stride + a.begin; k < end; ++k) {
      if (update) updateCoordinate(k, a, x, v, start);
      if (predict) predictCoordinate(k, dv[d], a, x, v, start);
    }
  }
}

// Every particle's prediction, update, or both, as if it were free (seed: v += h g, x += h v;
// XPBD Algorithm 1, lines 3-4 and 11). Solver::predict and Solver::updateVelocities then put the
// kinematic particles right. The body is inlined into two builds, AVX2 and the baseline, chosen
// at run time as the stretch links' (stretch_links.h; not function multiversioning, whose
// load-time resolvers the sanitizer builds cannot run); no FMA in either, so both round alike.
#if defined(__x86_64__) && defined(__GNUC__)
template <bool update, bool predict>
__attribute__((target("avx2"))) void advanceFreeAvx2(const PredictArgs& a) {
  advanceFree<update, predict>(a);
}

template <bool update, bool predict>
__attribute__((target("avx2"))) void advanceFreeColumnsAvx2(const PredictArgs& a, int stride) {
  advanceFreeColumns<update, predict>(a, stride);
}
#endif

template <bool update, bool predict>
void advanceFree(const PredictArgs& a, bool avx2) {
#if defined(__x86_64__) && defined(__GNUC__)
  if (avx2) return advanceFreeAvx2<update, predict>(a);
#else
  (void)avx2;
#endif
  advanceFree<update, predict>(a);
}

template <bool update, bool predict>
void advanceFreeColumns(const PredictArgs& a, int stride, bool avx2) {
#if defined(__x86_64__) && defined(__GNUC__)
  if (avx2) return advanceFreeColumnsAvx2<update, predict>(a, stride);
#else
  (void)avx2;
#endif
  advanceFreeColumns<update, predict>(a, stride);
}

}  // namespace

// Calls advanceFree<update, predict> (interleaved) or advanceFreeColumns with the flags as values.
void advanceFreeRange(const PredictArgs& a, bool update, bool predict, int column_stride,
                      bool avx2) {
  const bool columns = column_stride > 0;
  if (update && predict) {
    columns ? advanceFreeColumns<true, true>(a, column_stride, avx2)
            : advanceFree<true, true>(a, avx2);
  } else if (update) {
    columns ? advanceFreeColumns<true, false>(a, column_stride, avx2)
            : advanceFree<true, false>(a, avx2);
  } else {
    columns ? advanceFreeColumns<false, true>(a, column_stride, avx2)
            : advanceFree<false, true>(a, avx2);
  }
}

}  // namespace pbd_cloth
