// The prediction and velocity update of the free particles over a range (seed: v += h g,
// x += h v; XPBD Algorithm 1, lines 3-4 and 11), in two builds, AVX2 and the baseline, chosen at
// run time; no FMA in either, so both round alike (integration.cpp puts the kinematic particles
// right around them).
#pragma once

namespace pbd_cloth {

struct PredictArgs {
  int begin = 0, end = 0;  // particles
  double keep = 1.0, h = 0.0, inv_h = 0.0, dv_x = 0.0, dv_y = 0.0, dv_z = 0.0;
  double *x = nullptr, *v = nullptr, *start = nullptr;  // flat coordinates
};

// Every particle of [a.begin, a.end) advanced as if it were free: the update that ends a substep,
// the prediction of the next, or both in one pass. column_stride > 0: x, v and start hold the x,
// y and z columns that far apart (a step of links alone); 0: interleaved x0 y0 z0 x1 ...
void advanceFreeRange(const PredictArgs& a, bool update, bool predict, int column_stride,
                      bool avx2);

}  // namespace pbd_cloth
