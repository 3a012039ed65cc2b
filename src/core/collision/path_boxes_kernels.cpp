#include "pbd_cloth/collision/path_boxes.h"

#include <algorithm>
#include <limits>

#include "pbd_cloth/parallel/cpu_features.h"

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define PBD_CLOTH_HAVE_AVX2_PATH 1
#endif

namespace pbd_cloth {

namespace {

bool pathBoxesPortable(const Particles& p, const Vec3Array& start, int begin, int end, PathBox* box,
                       Eigen::Array3d& lo, Eigen::Array3d& hi) {
  const double inf = std::numeric_limits<double>::infinity();
  lo = Eigen::Array3d::Constant(inf);
  hi = Eigen::Array3d::Constant(-inf);
  bool every = false;
  for (int i = begin; i < end; ++i) {
    if (p.inverse_mass[i] == 0.0) continue;
    Eigen::Array3d particle_lo, particle_hi;
    pathBox(p.position[i], start[i], p.radius[i], particle_lo, particle_hi);
    PathBox& b = box[i - begin];
    for (int d = 0; d < 3; ++d) {
      b.lo[d] = particle_lo[d];
      b.hi[d] = particle_hi[d];
    }
    b.lo[3] = b.hi[3] = 0.0;
    // (Bitwise, not short-circuit: no branch per particle.)
    every |= !(particle_lo[0] <= particle_hi[0]) | !(particle_lo[1] <= particle_hi[1]) |
             !(particle_lo[2] <= particle_hi[2]);
    lo = lo.min(particle_lo);
    hi = hi.max(particle_hi);
  }
  return every;
}

void reachedPortable(const Particles& p, int begin, int end, const PathBox* box,
                     const PathBox* obstacle, int count, const PathBox& bounds,
                     std::uint64_t* reach, unsigned char* inside) {
  for (int i = begin; i < end; ++i) {
    if (p.inverse_mass[i] == 0.0) continue;
    const double* l = box[i - begin].lo;
    const double* h = box[i - begin].hi;
    std::uint64_t bits = 0;
    for (int q = 0; q < count; ++q) {
      const double* olo = obstacle[q].lo;
      const double* ohi = obstacle[q].hi;
      const bool apart = (h[0] < olo[0]) | (h[1] < olo[1]) | (h[2] < olo[2]) | (l[0] > ohi[0]) |
                         (l[1] > ohi[1]) | (l[2] > ohi[2]);
      bits |= static_cast<std::uint64_t>(!apart) << q;
    }
    reach[i - begin] = bits;
    inside[i - begin] = (l[0] >= bounds.lo[0]) & (l[1] >= bounds.lo[1]) & (l[2] >= bounds.lo[2]) &
                        (h[0] <= bounds.hi[0]) & (h[1] <= bounds.hi[1]) & (h[2] <= bounds.hi[2]);
  }
}

#ifdef PBD_CLOTH_HAVE_AVX2_PATH
#define PBD_AVX2 __attribute__((target("avx2")))
#define PBD_AVX512VL __attribute__((target("avx512f,avx512vl")))

// What the kernel does to registers, in functions compiled for the instruction set (the kernel
// below is generic code, inlined into each target's function by `flatten`, and passes registers
// by reference only: a vector passed by value outside an AVX function changes the ABI, and
// neither compiler expands an AVX intrinsic in a function not compiled for AVX).
// The operand order of the minimum and the maximum matches std::min and std::max (and so
// Eigen's): vminpd(a, b) is a < b ? a : b, so min(x, start) = std::min(x, start) is
// vminpd(start, x), and the union's std::min(lo, box) is vminpd(box, lo): the same choices, NaN
// and signed zeros included, as the portable loop's.
struct Avx2Registers {
  PBD_AVX2 static void broadcast(double value, __m256d& r) { r = _mm256_set1_pd(value); }
  PBD_AVX2 static void min(const __m256d& a, const __m256d& b, __m256d& r) {
    r = _mm256_min_pd(a, b);
  }
  PBD_AVX2 static void max(const __m256d& a, const __m256d& b, __m256d& r) {
    r = _mm256_max_pd(a, b);
  }
  PBD_AVX2 static void store(double* p, const __m256d& r) { _mm256_store_pd(p, r); }
  // not_box |= !(lo <= hi), lane by lane (unordered: true with a NaN).
  PBD_AVX2 static void orNotBox(const __m256d& lo, const __m256d& hi, __m256d& not_box) {
    not_box = _mm256_or_pd(not_box, _mm256_cmp_pd(lo, hi, _CMP_NLE_UQ));
  }
  PBD_AVX2 static bool anyXyz(const __m256d& r) { return (_mm256_movemask_pd(r) & 0x7) != 0; }
};

// How a register takes one particle's x y z (lane 3 zero); neither reads the double after z, so
// the array's last particle is safe. AVX2: a 16-byte and an 8-byte load; AVX-512VL: one masked
// load of three lanes.
struct Avx2Xyz : Avx2Registers {
  PBD_AVX2 static void load(const double* p, __m256d& r) {
    r = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(p)), _mm_load_sd(p + 2), 1);
  }
};
struct Avx512VlXyz : Avx2Registers {
  PBD_AVX512VL static void load(const double* p, __m256d& r) { r = _mm256_maskz_loadu_pd(0x7, p); }
};

// pathBoxesPortable's operations lane by lane (the difference and the sum through GCC's vector
// operators, compiled to the caller's instruction set: exact, as the scalar ones).
template <class A>
inline bool pathBoxesSimd(const Particles& p, const Vec3Array& start_array, int begin, int end,
                          PathBox* box, Eigen::Array3d& lo_out, Eigen::Array3d& hi_out) {
  const double* x = p.position.data()->data();
  const double* start = start_array.data()->data();
  const double* inverse_mass = p.inverse_mass.data();
  const double* radius = p.radius.data();
  __m256d lo, hi, not_box, xi, si, r, smaller, larger;
  A::broadcast(std::numeric_limits<double>::infinity(), lo);
  A::broadcast(-std::numeric_limits<double>::infinity(), hi);
  A::broadcast(0.0, not_box);
  for (int i = begin; i < end; ++i) {
    if (inverse_mass[i] == 0.0) continue;
    A::load(x + 3 * static_cast<std::ptrdiff_t>(i), xi);
    A::load(start + 3 * static_cast<std::ptrdiff_t>(i), si);
    A::broadcast(radius[i], r);
    A::min(si, xi, smaller);
    A::max(si, xi, larger);
    const __m256d l = smaller - r;
    const __m256d h = larger + r;
    A::store(box[i - begin].lo, l);
    A::store(box[i - begin].hi, h);
    A::orNotBox(l, h, not_box);
    A::min(l, lo, lo);
    A::max(h, hi, hi);
  }
  alignas(32) double lo_lanes[4], hi_lanes[4];
  A::store(lo_lanes, lo);
  A::store(hi_lanes, hi);
  lo_out = Eigen::Map<const Eigen::Array3d>(lo_lanes);
  hi_out = Eigen::Map<const Eigen::Array3d>(hi_lanes);
  return A::anyXyz(not_box);
}

// reachedPortable's comparisons, four lanes at once (ordered: false with a NaN, as there).
PBD_AVX2 void reachedAvx2(const Particles& p, int begin, int end, const PathBox* box,
                          const PathBox* obstacle, int count, const PathBox& bounds,
                          std::uint64_t* reach, unsigned char* inside) {
  const double* inverse_mass = p.inverse_mass.data();
  const __m256d bounds_lo = _mm256_load_pd(bounds.lo), bounds_hi = _mm256_load_pd(bounds.hi);
  for (int i = begin; i < end; ++i) {
    if (inverse_mass[i] == 0.0) continue;
    const __m256d l = _mm256_load_pd(box[i - begin].lo);
    const __m256d h = _mm256_load_pd(box[i - begin].hi);
    std::uint64_t bits = 0;
    for (int q = 0; q < count; ++q) {
      const __m256d apart =
          _mm256_or_pd(_mm256_cmp_pd(h, _mm256_load_pd(obstacle[q].lo), _CMP_LT_OQ),
                       _mm256_cmp_pd(l, _mm256_load_pd(obstacle[q].hi), _CMP_GT_OQ));
      bits |= static_cast<std::uint64_t>(_mm256_movemask_pd(apart) == 0) << q;
    }
    reach[i - begin] = bits;
    const __m256d in = _mm256_and_pd(_mm256_cmp_pd(l, bounds_lo, _CMP_GE_OQ),
                                     _mm256_cmp_pd(h, bounds_hi, _CMP_LE_OQ));
    inside[i - begin] = _mm256_movemask_pd(in) == 0xF;
  }
}

__attribute__((flatten)) PBD_AVX2 bool pathBoxesAvx2(const Particles& p, const Vec3Array& start,
                                                     int begin, int end, PathBox* box,
                                                     Eigen::Array3d& lo, Eigen::Array3d& hi) {
  return pathBoxesSimd<Avx2Xyz>(p, start, begin, end, box, lo, hi);
}

__attribute__((flatten)) PBD_AVX512VL bool pathBoxesAvx512Vl(const Particles& p,
                                                             const Vec3Array& start, int begin,
                                                             int end, PathBox* box,
                                                             Eigen::Array3d& lo,
                                                             Eigen::Array3d& hi) {
  return pathBoxesSimd<Avx512VlXyz>(p, start, begin, end, box, lo, hi);
}
#endif

}  // namespace

PathBoxKernel bestPathBoxKernel(bool simd, bool avx512) {
#ifdef PBD_CLOTH_HAVE_AVX2_PATH
  if (simd && avx512 && cpuHasAvx512Vl()) return PathBoxKernel::kAvx512Vl;
  if (simd && cpuHasAvx2()) return PathBoxKernel::kAvx2;
#else
  (void)simd;
  (void)avx512;
#endif
  return PathBoxKernel::kPortable;
}

PathBox boxOfBounds(const Vec3& lo, const Vec3& hi) {
  PathBox box;
  for (int d = 0; d < 3; ++d) {
    box.lo[d] = lo[d];
    box.hi[d] = hi[d];
  }
  box.lo[3] = -std::numeric_limits<double>::infinity();
  box.hi[3] = std::numeric_limits<double>::infinity();
  return box;
}

void reachedObstacles(PathBoxKernel kernel, const Particles& particles, int begin, int end,
                      const PathBox* box, const PathBox* obstacle, int count, const PathBox& bounds,
                      std::uint64_t* reach, unsigned char* inside) {
  count = std::min(count, kMostReachTests);
#ifdef PBD_CLOTH_HAVE_AVX2_PATH
  // (AVX-512VL adds nothing here: the boxes are whole aligned registers already.)
  if (kernel != PathBoxKernel::kPortable) {
    reachedAvx2(particles, begin, end, box, obstacle, count, bounds, reach, inside);
    return;
  }
#else
  (void)kernel;
#endif
  reachedPortable(particles, begin, end, box, obstacle, count, bounds, reach, inside);
}

bool computePathBoxes(PathBoxKernel kernel, const Particles& particles, int begin, int end,
                      PathBox* box, Eigen::Array3d& lo, Eigen::Array3d& hi) {
  return computePathBoxes(kernel, particles, particles.substep_start, begin, end, box, lo, hi);
}

bool computePathBoxes(PathBoxKernel kernel, const Particles& particles, const Vec3Array& start,
                      int begin, int end, PathBox* box, Eigen::Array3d& lo, Eigen::Array3d& hi) {
#ifdef PBD_CLOTH_HAVE_AVX2_PATH
  switch (kernel) {
    case PathBoxKernel::kAvx512Vl:
      return pathBoxesAvx512Vl(particles, start, begin, end, box, lo, hi);
    case PathBoxKernel::kAvx2:
      return pathBoxesAvx2(particles, start, begin, end, box, lo, hi);
    case PathBoxKernel::kPortable:
      break;
  }
#else
  (void)kernel;
#endif
  return pathBoxesPortable(particles, start, begin, end, box, lo, hi);
}

}  // namespace pbd_cloth
