// The stretch links' projection kernels: the portable loop and the AVX2 and AVX-512 sweeps, which
// round alike (built with -ffp-contract=off, as every *_kernels*.cpp: CMakeLists.txt), and the
// copies into and out of the columns.
#include "pbd_cloth/constraints/stretch_links.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "pbd_cloth/parallel/cpu_features.h"

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define PBD_CLOTH_HAVE_AVX2_PATH 1
#endif

namespace pbd_cloth {

namespace {

// Below this length a link has no direction: skipped and reported (coincident particles).
constexpr double kMinLength = 1e-12;

// One link, in the exact operation order of the AVX2 lanes below (same roundings, so the paths
// agree to the bit): d = x_i - x_j, C = |d| - l0 (or max(0, C)), dlambda = (-k C - alpha~ lambda)
// / (w_i + w_j + alpha~) (XPBD eq. 18, the division done once per step in prepareStep), and each
// end moves by its inverse mass times dlambda along the unit gradient n = d / |d|.
inline void projectOne(int c, const StretchLinks& links, const StretchProjection& how,
                       PositionColumns x, double* lambda, StretchPassResult& result) {
  const double inverse_denominator = links.inverse_denominator[c];
  // A link skipped this pass keeps its multiplier: zero at a substep's first pass.
  const bool clear = how.lambda_from_zero && lambda != nullptr;
  if (inverse_denominator == 0.0) {  // no free end
    if (clear) lambda[c] = 0.0;
    return;
  }
  const int a = links.i[c], b = links.j[c];
  const double dx = x.x[a] - x.x[b], dy = x.y[a] - x.y[b], dz = x.z[a] - x.z[b];
  const double length = std::sqrt((dx * dx + dy * dy) + dz * dz);
  if (length < kMinLength) {
    // No direction to push along: skipped this pass (the other links pull them apart), counted.
    if (result.degenerate++ == 0) result.first_degenerate = c;
    if (clear) lambda[c] = 0.0;
    return;
  }
  double constraint = length - links.rest_length[c];
  if (how.unilateral) constraint = std::max(0.0, constraint);
  const double old_lambda = lambda != nullptr && !how.lambda_from_zero ? lambda[c] : 0.0;
  const double dlambda =
      (-how.stiffness * constraint - how.alpha * old_lambda) * inverse_denominator;
  if (lambda != nullptr) lambda[c] = old_lambda + dlambda;
  const double s = dlambda / length;
  const double wi = links.inverse_mass_i[c], wj = links.inverse_mass_j[c];
  const double fa = wi * s, fb = wj * s;
  x.x[a] += fa * dx;
  x.y[a] += fa * dy;
  x.z[a] += fa * dz;
  x.x[b] -= fb * dx;
  x.y[b] -= fb * dy;
  x.z[b] -= fb * dz;
  if (how.track_change) {
    result.max_change = std::max(result.max_change, std::abs(dlambda) * std::max(wi, wj));
  }
}

void projectPortable(const StretchLinks& links, int first_batch, int end_batch,
                     const StretchProjection& how, PositionColumns x, double* lambda,
                     StretchPassResult& result) {
  const int begin = links.batch_begin[first_batch], end = links.batch_begin[end_batch];
  for (int c = begin; c < end; ++c) projectOne(c, links, how, x, lambda, result);
}

#ifdef PBD_CLOTH_HAVE_AVX2_PATH
#define PBD_AVX2 __attribute__((target("avx2")))

// Four particles' coordinates as stored in a Vec3Array (12 doubles from p, x0 y0 z0 x1 y1 ...)
// as three registers x, y, z (three loads and six shuffles), and back: the copies into and out of
// the columns the projection works on.
PBD_AVX2 inline void loadInterleavedFour(const double* p, __m256d& x, __m256d& y, __m256d& z) {
  const __m256d a = _mm256_loadu_pd(p);      // x0 y0 z0 x1
  const __m256d b = _mm256_loadu_pd(p + 4);  // y1 z1 x2 y2
  const __m256d c = _mm256_loadu_pd(p + 8);  // z2 x3 y3 z3
  const __m256d z0x1z2x3 = _mm256_permute2f128_pd(a, c, 0x21);
  const __m256d x0y0x2y2 = _mm256_blend_pd(a, b, 0xC);
  const __m256d y1z1y3z3 = _mm256_blend_pd(b, c, 0xC);
  x = _mm256_shuffle_pd(x0y0x2y2, z0x1z2x3, 0xA);
  y = _mm256_shuffle_pd(x0y0x2y2, y1z1y3z3, 0x5);
  z = _mm256_shuffle_pd(z0x1z2x3, y1z1y3z3, 0xA);
}

PBD_AVX2 inline void storeInterleavedFour(double* p, __m256d x, __m256d y, __m256d z) {
  const __m256d x0y0x2y2 = _mm256_shuffle_pd(x, y, 0x0);
  const __m256d z0x1z2x3 = _mm256_shuffle_pd(z, x, 0xA);
  const __m256d y1z1y3z3 = _mm256_shuffle_pd(y, z, 0xF);
  _mm256_storeu_pd(p, _mm256_permute2f128_pd(x0y0x2y2, z0x1z2x3, 0x20));
  _mm256_storeu_pd(p + 4, _mm256_blend_pd(y1z1y3z3, x0y0x2y2, 0xC));
  _mm256_storeu_pd(p + 8, _mm256_permute2f128_pd(z0x1z2x3, y1z1y3z3, 0x31));
}

// The AVX2 copies move whole groups of four particles and return the first particle they did not
// copy; the caller's plain loop copies the rest, the same loop as on a CPU without AVX2.
PBD_AVX2 int toColumnsAvx2(const double* interleaved, int begin, int end, PositionColumns to) {
  int p = begin;
  for (; p + 4 <= end; p += 4) {
    __m256d x, y, z;
    loadInterleavedFour(interleaved + 3 * p, x, y, z);
    _mm256_storeu_pd(to.x + p, x);
    _mm256_storeu_pd(to.y + p, y);
    _mm256_storeu_pd(to.z + p, z);
  }
  return p;
}

PBD_AVX2 int fromColumnsAvx2(PositionColumns from, int begin, int end, double* interleaved) {
  int p = begin;
  for (; p + 4 <= end; p += 4) {
    storeInterleavedFour(interleaved + 3 * p, _mm256_loadu_pd(from.x + p),
                         _mm256_loadu_pd(from.y + p), _mm256_loadu_pd(from.z + p));
  }
  return p;
}

// What the sweep reads of the links and of the projection's settings, as plain locals: read
// through `links` and `how` instead, each array's address and each setting would be loaded again
// for every group of links, since a register store may alias anything in memory.
struct SweepInputs {
  const int* i;
  const int* j;
  const StretchLinks::Segment* segments;
  const double* rest_length;
  const double* inverse_denominator;
  const double* inverse_mass_i;
  const double* inverse_mass_j;
  double* lambda;    // nullptr: multipliers not kept
  bool read_lambda;  // lambda kept and not starting from zero in this pass
  bool unilateral;
  bool track_change;
  double minus_stiffness;  // -k
  double alpha;            // alpha~
};

SweepInputs sweepInputs(const StretchLinks& links, const StretchProjection& how, double* lambda) {
  SweepInputs in;
  in.i = links.i.data();
  in.j = links.j.data();
  in.segments = links.segments.data();
  in.rest_length = links.rest_length.data();
  in.inverse_denominator = links.inverse_denominator.data();
  in.inverse_mass_i = links.inverse_mass_i.data();
  in.inverse_mass_j = links.inverse_mass_j.data();
  in.lambda = lambda;
  in.read_lambda = lambda != nullptr && !how.lambda_from_zero;
  in.unilateral = how.unilateral;
  in.track_change = how.track_change;
  in.minus_stiffness = -how.stiffness;
  in.alpha = how.alpha;
  return in;
}

// The projection's settings in every lane of a register, broadcast once per sweep.
template <class L>
struct Settings {
  typename L::Reg minus_stiffness;  // -k
  typename L::Reg alpha;            // alpha~
  explicit Settings(const SweepInputs& in) {
    L::broadcast(in.minus_stiffness, minus_stiffness);
    L::broadcast(in.alpha, alpha);
  }
};

// The register width as a type, so that the sweep below is written once for both: FourLanes
// (AVX2, 256 bits) and EightLanes (AVX-512, 512 bits). Each holds what GCC's vector operators do
// not: the width's loads, stores, shuffles, square root, maximum and comparison. Registers are
// passed by reference: the generic code (compiled for no instruction set of its own, inlined into
// the sweep of each width by `flatten`) never passes a vector by value.
struct FourLanes {
  using Reg = __m256d;
  static constexpr int kLinks = 4;
  PBD_AVX2 static void load(const double* p, Reg& r) { r = _mm256_loadu_pd(p); }
  PBD_AVX2 static void store(double* p, const Reg& r) { _mm256_storeu_pd(p, r); }
  PBD_AVX2 static void zero(Reg& r) { r = _mm256_setzero_pd(); }
  PBD_AVX2 static void broadcast(double value, Reg& r) { r = _mm256_set1_pd(value); }
  // Lane order 1 0 3 2 (kCrossed's j ends).
  PBD_AVX2 static void swapPairs(Reg& r) { r = _mm256_permute_pd(r, 0x5); }
  // One coordinate of eight consecutive particles (two registers) split into the even ones (0 2 4
  // 6) and the odd ones (1 3 5 7), and joined again.
  PBD_AVX2 static void split(const Reg& low, const Reg& high, Reg& even, Reg& odd) {
    even = _mm256_permute4x64_pd(_mm256_unpacklo_pd(low, high), 0xD8);
    odd = _mm256_permute4x64_pd(_mm256_unpackhi_pd(low, high), 0xD8);
  }
  PBD_AVX2 static void join(const Reg& even, const Reg& odd, Reg& low, Reg& high) {
    const __m256d e0o0e2o2 = _mm256_unpacklo_pd(even, odd);
    const __m256d e1o1e3o3 = _mm256_unpackhi_pd(even, odd);
    low = _mm256_permute2f128_pd(e0o0e2o2, e1o1e3o3, 0x20);
    high = _mm256_permute2f128_pd(e0o0e2o2, e1o1e3o3, 0x31);
  }
  PBD_AVX2 static void sqrt(const Reg& r, Reg& root) { root = _mm256_sqrt_pd(r); }
  PBD_AVX2 static void max(const Reg& a, const Reg& b, Reg& r) { r = _mm256_max_pd(a, b); }
  PBD_AVX2 static void abs(const Reg& r, Reg& magnitude) {
    magnitude = _mm256_andnot_pd(_mm256_set1_pd(-0.0), r);
  }
  PBD_AVX2 static bool allAtLeast(const Reg& r, double bound) {
    return _mm256_movemask_pd(_mm256_cmp_pd(r, _mm256_set1_pd(bound), _CMP_GE_OQ)) == 0xF;
  }
  PBD_AVX2 static double largest(const Reg& r) {
    alignas(32) double lanes[kLinks];
    _mm256_store_pd(lanes, r);
    return *std::max_element(lanes, lanes + kLinks);
  }
};

// AVX-512F only (every AVX-512 processor has it). The masked forms with every lane set are the
// plain instructions: GCC 12's unmasked _mm512_sqrt_pd, _mm512_max_pd and _mm512_permute_pd
// start from _mm512_undefined_pd and warn that it is used uninitialized (-Wmaybe-uninitialized).
#define PBD_AVX512 __attribute__((target("avx512f")))
struct EightLanes {
  using Reg = __m512d;
  static constexpr int kLinks = 8;
  static constexpr __mmask8 kAll = 0xFF;
  PBD_AVX512 static void load(const double* p, Reg& r) { r = _mm512_loadu_pd(p); }
  PBD_AVX512 static void store(double* p, const Reg& r) { _mm512_storeu_pd(p, r); }
  PBD_AVX512 static void zero(Reg& r) { r = _mm512_setzero_pd(); }
  PBD_AVX512 static void broadcast(double value, Reg& r) { r = _mm512_set1_pd(value); }
  PBD_AVX512 static void swapPairs(Reg& r) { r = _mm512_maskz_permute_pd(kAll, r, 0x55); }
  PBD_AVX512 static void split(const Reg& low, const Reg& high, Reg& even, Reg& odd) {
    even = _mm512_permutex2var_pd(low, _mm512_set_epi64(14, 12, 10, 8, 6, 4, 2, 0), high);
    odd = _mm512_permutex2var_pd(low, _mm512_set_epi64(15, 13, 11, 9, 7, 5, 3, 1), high);
  }
  PBD_AVX512 static void join(const Reg& even, const Reg& odd, Reg& low, Reg& high) {
    low = _mm512_permutex2var_pd(even, _mm512_set_epi64(11, 3, 10, 2, 9, 1, 8, 0), odd);
    high = _mm512_permutex2var_pd(even, _mm512_set_epi64(15, 7, 14, 6, 13, 5, 12, 4), odd);
  }
  PBD_AVX512 static void sqrt(const Reg& r, Reg& root) { root = _mm512_maskz_sqrt_pd(kAll, r); }
  PBD_AVX512 static void max(const Reg& a, const Reg& b, Reg& r) {
    r = _mm512_maskz_max_pd(kAll, a, b);
  }
  PBD_AVX512 static void abs(const Reg& r, Reg& magnitude) { magnitude = _mm512_abs_pd(r); }
  PBD_AVX512 static bool allAtLeast(const Reg& r, double bound) {
    return _mm512_cmp_pd_mask(r, _mm512_set1_pd(bound), _CMP_GE_OQ) == kAll;
  }
  PBD_AVX512 static double largest(const Reg& r) {
    alignas(64) double lanes[kLinks];
    _mm512_store_pd(lanes, r);
    return *std::max_element(lanes, lanes + kLinks);
  }
};

// The arithmetic of projectOne on a register of links at once, in the same operations and order
// (so the same roundings: the paths agree to the bit): a = their i ends, b = their j ends (x, y,
// z registers, updated in place). The operators are GCC's vector arithmetic, which the sweep's
// instruction set compiles to its own (vsubpd ymm, or zmm). Returns false, touching nothing,
// when a link of the register has coincident ends (projectOne then reports it).
template <class L>
inline bool projectLinks(int c, const SweepInputs& in, const Settings<L>& k, typename L::Reg* a,
                         typename L::Reg* b, typename L::Reg& max_change) {
  using Reg = typename L::Reg;
  const Reg d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
  Reg length;
  L::sqrt((d[0] * d[0] + d[1] * d[1]) + d[2] * d[2], length);
  if (!L::allAtLeast(length, kMinLength)) return false;
  const Reg zero = {};
  Reg rest, inverse_denominator, wi, wj, old_lambda = zero;
  L::load(in.rest_length + c, rest);
  Reg constraint = length - rest;
  if (in.unilateral) L::max(zero, constraint, constraint);
  if (in.read_lambda) L::load(in.lambda + c, old_lambda);
  L::load(in.inverse_denominator + c, inverse_denominator);
  const Reg dlambda = (k.minus_stiffness * constraint - k.alpha * old_lambda) * inverse_denominator;
  if (in.lambda != nullptr) L::store(in.lambda + c, old_lambda + dlambda);
  const Reg s = dlambda / length;
  L::load(in.inverse_mass_i + c, wi);
  L::load(in.inverse_mass_j + c, wj);
  const Reg fa = wi * s, fb = wj * s;
  for (int q = 0; q < 3; ++q) {
    a[q] = a[q] + fa * d[q];
    b[q] = b[q] - fb * d[q];
  }
  // A skipped link (no free end) has inverse_denominator 0: dlambda 0, nothing moves.
  if (in.track_change) {
    Reg magnitude, larger_w;
    L::abs(dlambda, magnitude);
    L::max(wi, wj, larger_w);
    L::max(max_change, magnitude * larger_w, max_change);
  }
  return true;
}

// One register's worth of consecutive particles from p (L::kLinks of them), a register per
// coordinate: three plain loads, no shuffle.
template <class L>
inline void loadRow(PositionColumns x, int p, typename L::Reg* r) {
  L::load(x.x + p, r[0]);
  L::load(x.y + p, r[1]);
  L::load(x.z + p, r[2]);
}

template <class L>
inline void storeRow(PositionColumns x, int p, const typename L::Reg* r) {
  L::store(x.x + p, r[0]);
  L::store(x.y + p, r[1]);
  L::store(x.z + p, r[2]);
}

// Two registers' worth of consecutive particles from p: the even ones and the odd ones, as x, y,
// z registers each.
template <class L>
struct EvenOdd {
  typename L::Reg even[3];
  typename L::Reg odd[3];
};

template <class L>
inline void loadEvenOdd(PositionColumns x, int p, EvenOdd<L>& e) {
  const double* column[3] = {x.x, x.y, x.z};
  for (int d = 0; d < 3; ++d) {
    typename L::Reg low, high;
    L::load(column[d] + p, low);
    L::load(column[d] + p + L::kLinks, high);
    L::split(low, high, e.even[d], e.odd[d]);
  }
}

template <class L>
inline void storeEvenOdd(PositionColumns x, int p, const EvenOdd<L>& e) {
  double* column[3] = {x.x, x.y, x.z};
  for (int d = 0; d < 3; ++d) {
    typename L::Reg low, high;
    L::join(e.even[d], e.odd[d], low, high);
    L::store(column[d] + p, low);
    L::store(column[d] + p + L::kLinks, high);
  }
}

// L::kLinks links from c laid out as `layout` (findSegments), loaded as whole registers,
// projected and stored back. Returns false, touching nothing, on coincident ends.
template <class L>
inline bool projectRegister(StretchLinks::Layout layout, int c, const SweepInputs& in,
                            const Settings<L>& k, PositionColumns x, typename L::Reg& max_change) {
  using Reg = typename L::Reg;
  const int pa = in.i[c], pb = in.j[c];
  switch (layout) {
    case StretchLinks::Layout::kContiguous: {
      Reg a[3], b[3];
      loadRow<L>(x, pa, a);
      loadRow<L>(x, pb, b);
      if (!projectLinks<L>(c, in, k, a, b, max_change)) return false;
      storeRow<L>(x, pa, a);
      storeRow<L>(x, pb, b);
      return true;
    }
    case StretchLinks::Layout::kCrossed: {
      // j ends m+1, m, m+3, m+2, ...: a register from m, swapped within each pair.
      const int pm = in.j[c + 1];
      Reg a[3], b[3];
      loadRow<L>(x, pa, a);
      loadRow<L>(x, pm, b);
      for (int d = 0; d < 3; ++d) L::swapPairs(b[d]);
      if (!projectLinks<L>(c, in, k, a, b, max_change)) return false;
      for (int d = 0; d < 3; ++d) L::swapPairs(b[d]);
      storeRow<L>(x, pa, a);
      storeRow<L>(x, pm, b);
      return true;
    }
    case StretchLinks::Layout::kInterleaved: {
      EvenOdd<L> e;
      loadEvenOdd<L>(x, pa, e);
      if (!projectLinks<L>(c, in, k, e.even, e.odd, max_change)) return false;
      storeEvenOdd<L>(x, pa, e);
      return true;
    }
    case StretchLinks::Layout::kStrided: {
      EvenOdd<L> ea, eb;
      loadEvenOdd<L>(x, pa, ea);
      loadEvenOdd<L>(x, pb, eb);
      if (!projectLinks<L>(c, in, k, ea.even, eb.even, max_change)) return false;
      storeEvenOdd<L>(x, pa, ea);
      storeEvenOdd<L>(x, pb, eb);
      return true;
    }
    case StretchLinks::Layout::kScalar:
      break;
  }
  return false;
}

// The sweep over batches [first_batch, end_batch): a segment of Wide::kLinks links (or a multiple)
// in Wide registers, one of four in Narrow ones, the rest link by link. Any register split gives
// the same result: the links of a segment share no particle.
template <class Wide, class Narrow>
inline void sweepRegisters(const StretchLinks& links, int first_batch, int end_batch,
                           const StretchProjection& how, PositionColumns x, double* lambda,
                           StretchPassResult& result) {
  const SweepInputs in = sweepInputs(links, how, lambda);
  const Settings<Wide> wide_settings(in);
  const Settings<Narrow> narrow_settings(in);
  typename Wide::Reg wide_change;
  typename Narrow::Reg narrow_change;
  Wide::zero(wide_change);
  Narrow::zero(narrow_change);
  auto oneByOne = [&](int begin, int end) {
    for (int k = begin; k < end; ++k) projectOne(k, links, how, x, lambda, result);
  };
  const int first = links.batch_segment[first_batch], last = links.batch_segment[end_batch];
  for (int g = first; g < last; ++g) {
    const StretchLinks::Segment segment = in.segments[g];
    if (segment.layout == StretchLinks::Layout::kScalar) {
      oneByOne(segment.begin, segment.end);
    } else if (segment.end - segment.begin == Wide::kLinks) {
      if (!projectRegister<Wide>(segment.layout, segment.begin, in, wide_settings, x,
                                 wide_change)) {
        oneByOne(segment.begin, segment.end);
      }
    } else {
      for (int c = segment.begin; c < segment.end; c += Narrow::kLinks) {
        if (!projectRegister<Narrow>(segment.layout, c, in, narrow_settings, x, narrow_change)) {
          oneByOne(c, c + Narrow::kLinks);
        }
      }
    }
  }
  result.max_change =
      std::max({result.max_change, Wide::largest(wide_change), Narrow::largest(narrow_change)});
}

// The sweep of each width, compiled for its instruction set with everything it calls inlined
// (flatten): the generic code above becomes AVX2 code here and AVX-512 code below.
__attribute__((flatten)) PBD_AVX2 void projectAvx2(const StretchLinks& links, int first_batch,
                                                   int end_batch, const StretchProjection& how,
                                                   PositionColumns x, double* lambda,
                                                   StretchPassResult& result) {
  sweepRegisters<FourLanes, FourLanes>(links, first_batch, end_batch, how, x, lambda, result);
}

__attribute__((flatten)) PBD_AVX512 void projectAvx512(const StretchLinks& links, int first_batch,
                                                       int end_batch, const StretchProjection& how,
                                                       PositionColumns x, double* lambda,
                                                       StretchPassResult& result) {
  sweepRegisters<EightLanes, FourLanes>(links, first_batch, end_batch, how, x, lambda, result);
}
#endif

}  // namespace

bool stretchLinksUseAvx512() { return cpuHasAvx512F(); }
bool stretchLinksUseAvx2() { return cpuHasAvx2(); }

StretchPassResult projectStretchLinks(const StretchLinks& links, int first_batch, int end_batch,
                                      const StretchProjection& how, PositionColumns position,
                                      double* lambda) {
  StretchPassResult result;
  if (first_batch >= end_batch) return result;
#ifdef PBD_CLOTH_HAVE_AVX2_PATH
  if (how.simd && how.avx512 && stretchLinksUseAvx512()) {
    projectAvx512(links, first_batch, end_batch, how, position, lambda, result);
    return result;
  }
  if (how.simd && stretchLinksUseAvx2()) {
    projectAvx2(links, first_batch, end_batch, how, position, lambda, result);
    return result;
  }
#endif
  projectPortable(links, first_batch, end_batch, how, position, lambda, result);
  return result;
}

void positionsToColumns(const double* interleaved, int begin, int end, PositionColumns columns,
                        bool simd) {
  int p = begin;
#ifdef PBD_CLOTH_HAVE_AVX2_PATH
  if (simd && stretchLinksUseAvx2()) p = toColumnsAvx2(interleaved, begin, end, columns);
#else
  (void)simd;
#endif
  for (; p < end; ++p) {
    columns.x[p] = interleaved[3 * p];
    columns.y[p] = interleaved[3 * p + 1];
    columns.z[p] = interleaved[3 * p + 2];
  }
}

void positionsFromColumns(PositionColumns columns, int begin, int end, double* interleaved,
                          bool simd) {
  int p = begin;
#ifdef PBD_CLOTH_HAVE_AVX2_PATH
  if (simd && stretchLinksUseAvx2()) p = fromColumnsAvx2(columns, begin, end, interleaved);
#else
  (void)simd;
#endif
  for (; p < end; ++p) {
    interleaved[3 * p] = columns.x[p];
    interleaved[3 * p + 1] = columns.y[p];
    interleaved[3 * p + 2] = columns.z[p];
  }
}

}  // namespace pbd_cloth
