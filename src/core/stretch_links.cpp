#include "pbd_cloth/stretch_links.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define PBD_CLOTH_HAVE_AVX2_PATH 1
#endif

namespace pbd_cloth {

namespace {

// Below this length a link has no direction: skipped and reported (coincident particles).
constexpr double kMinLength = 1e-12;
// Below this a link's generalized inverse mass is zero (both ends kinematic): skipped.
constexpr double kMinInverseMass = 1e-300;

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

// Four consecutive particles from p, one register per coordinate: three plain loads, no shuffle.
PBD_AVX2 inline void loadFour(PositionColumns x, int p, __m256d* r) {
  r[0] = _mm256_loadu_pd(x.x + p);
  r[1] = _mm256_loadu_pd(x.y + p);
  r[2] = _mm256_loadu_pd(x.z + p);
}

PBD_AVX2 inline void storeFour(PositionColumns x, int p, const __m256d* r) {
  _mm256_storeu_pd(x.x + p, r[0]);
  _mm256_storeu_pd(x.y + p, r[1]);
  _mm256_storeu_pd(x.z + p, r[2]);
}

// One coordinate of eight consecutive particles (two registers of four) split into the even ones
// (0 2 4 6) and the odd ones (1 3 5 7), and joined again.
PBD_AVX2 inline void splitEvenOdd(__m256d low, __m256d high, __m256d& even, __m256d& odd) {
  even = _mm256_permute4x64_pd(_mm256_unpacklo_pd(low, high), 0xD8);
  odd = _mm256_permute4x64_pd(_mm256_unpackhi_pd(low, high), 0xD8);
}

PBD_AVX2 inline void joinEvenOdd(__m256d even, __m256d odd, __m256d& low, __m256d& high) {
  const __m256d e0o0e2o2 = _mm256_unpacklo_pd(even, odd);
  const __m256d e1o1e3o3 = _mm256_unpackhi_pd(even, odd);
  low = _mm256_permute2f128_pd(e0o0e2o2, e1o1e3o3, 0x20);
  high = _mm256_permute2f128_pd(e0o0e2o2, e1o1e3o3, 0x31);
}

// Eight consecutive particles from p: the even ones and the odd ones, as x, y, z registers each.
struct EightParticles {
  __m256d even[3];
  __m256d odd[3];
};

PBD_AVX2 inline void loadEight(PositionColumns x, int p, EightParticles& e) {
  const double* column[3] = {x.x, x.y, x.z};
  for (int d = 0; d < 3; ++d) {
    splitEvenOdd(_mm256_loadu_pd(column[d] + p), _mm256_loadu_pd(column[d] + p + 4), e.even[d],
                 e.odd[d]);
  }
}

PBD_AVX2 inline void storeEight(PositionColumns x, int p, const EightParticles& e) {
  double* column[3] = {x.x, x.y, x.z};
  for (int d = 0; d < 3; ++d) {
    __m256d low, high;
    joinEvenOdd(e.even[d], e.odd[d], low, high);
    _mm256_storeu_pd(column[d] + p, low);
    _mm256_storeu_pd(column[d] + p + 4, high);
  }
}

// What the sweep reads of the links and of the projection's settings, as plain locals: read
// through `links` and `how` instead, each array's address and each setting would be loaded again
// for every four links, since a register store (_mm256_storeu_pd) may alias anything in memory.
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
  __m256d minus_stiffness;  // -k in every lane
  __m256d alpha;            // alpha~ in every lane
};

// The arithmetic of projectOne on four links at once: a = their i ends, b = their j ends (x, y,
// z registers, updated in place). Returns false, touching nothing, when a link of the four has
// coincident ends (projectOne then reports it).
PBD_AVX2 inline bool projectFour(int c, const SweepInputs& in, __m256d* a, __m256d* b,
                                 __m256d& max_change) {
  const __m256d dx = _mm256_sub_pd(a[0], b[0]);
  const __m256d dy = _mm256_sub_pd(a[1], b[1]);
  const __m256d dz = _mm256_sub_pd(a[2], b[2]);
  const __m256d length = _mm256_sqrt_pd(_mm256_add_pd(
      _mm256_add_pd(_mm256_mul_pd(dx, dx), _mm256_mul_pd(dy, dy)), _mm256_mul_pd(dz, dz)));
  const __m256d long_enough = _mm256_cmp_pd(length, _mm256_set1_pd(kMinLength), _CMP_GE_OQ);
  if (_mm256_movemask_pd(long_enough) != 0xF) return false;
  const __m256d zero = _mm256_setzero_pd();
  __m256d constraint = _mm256_sub_pd(length, _mm256_loadu_pd(in.rest_length + c));
  if (in.unilateral) constraint = _mm256_max_pd(zero, constraint);
  const __m256d old_lambda = in.read_lambda ? _mm256_loadu_pd(in.lambda + c) : zero;
  const __m256d dlambda = _mm256_mul_pd(_mm256_sub_pd(_mm256_mul_pd(in.minus_stiffness, constraint),
                                                      _mm256_mul_pd(in.alpha, old_lambda)),
                                        _mm256_loadu_pd(in.inverse_denominator + c));
  if (in.lambda != nullptr) _mm256_storeu_pd(in.lambda + c, _mm256_add_pd(old_lambda, dlambda));
  const __m256d s = _mm256_div_pd(dlambda, length);
  const __m256d wi = _mm256_loadu_pd(in.inverse_mass_i + c);
  const __m256d wj = _mm256_loadu_pd(in.inverse_mass_j + c);
  const __m256d fa = _mm256_mul_pd(wi, s), fb = _mm256_mul_pd(wj, s);
  const __m256d d[3] = {dx, dy, dz};
  for (int k = 0; k < 3; ++k) {
    a[k] = _mm256_add_pd(a[k], _mm256_mul_pd(fa, d[k]));
    b[k] = _mm256_sub_pd(b[k], _mm256_mul_pd(fb, d[k]));
  }
  // A skipped link (no free end) has inverse_denominator 0: dlambda 0, nothing moves.
  if (in.track_change) {
    const __m256d magnitude = _mm256_andnot_pd(_mm256_set1_pd(-0.0), dlambda);
    max_change = _mm256_max_pd(max_change, _mm256_mul_pd(magnitude, _mm256_max_pd(wi, wj)));
  }
  return true;
}

PBD_AVX2 void projectAvx2(const StretchLinks& links, int first_batch, int end_batch,
                          const StretchProjection& how, PositionColumns x, double* lambda,
                          StretchPassResult& result) {
  __m256d max_change = _mm256_setzero_pd();
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
  in.minus_stiffness = _mm256_set1_pd(-how.stiffness);
  in.alpha = _mm256_set1_pd(how.alpha);
  const int first = links.batch_segment[first_batch], last = links.batch_segment[end_batch];
  for (int g = first; g < last; ++g) {
    const StretchLinks::Segment& segment = in.segments[g];
    const int c = segment.begin;
    const int pa = in.i[c], pb = in.j[c];
    bool done = true;
    switch (segment.layout) {
      case StretchLinks::Layout::kScalar:
        for (int k = segment.begin; k < segment.end; ++k) {
          projectOne(k, links, how, x, lambda, result);
        }
        break;
      case StretchLinks::Layout::kContiguous: {
        __m256d a[3], b[3];
        loadFour(x, pa, a);
        loadFour(x, pb, b);
        done = projectFour(c, in, a, b, max_change);
        if (done) {
          storeFour(x, pa, a);
          storeFour(x, pb, b);
        }
        break;
      }
      case StretchLinks::Layout::kCrossed: {
        // j ends m+1, m, m+3, m+2: four from m, swapped within each pair (lane order 1 0 3 2).
        const int pm = in.j[c + 1];
        __m256d a[3], b[3];
        loadFour(x, pa, a);
        loadFour(x, pm, b);
        for (int d = 0; d < 3; ++d) b[d] = _mm256_permute_pd(b[d], 0x5);
        done = projectFour(c, in, a, b, max_change);
        if (done) {
          for (int d = 0; d < 3; ++d) b[d] = _mm256_permute_pd(b[d], 0x5);
          storeFour(x, pa, a);
          storeFour(x, pm, b);
        }
        break;
      }
      case StretchLinks::Layout::kInterleaved: {
        EightParticles e;
        loadEight(x, pa, e);
        done = projectFour(c, in, e.even, e.odd, max_change);
        if (done) storeEight(x, pa, e);
        break;
      }
      case StretchLinks::Layout::kStrided: {
        EightParticles ea, eb;
        loadEight(x, pa, ea);
        loadEight(x, pb, eb);
        done = projectFour(c, in, ea.even, eb.even, max_change);
        if (done) {
          storeEight(x, pa, ea);
          storeEight(x, pb, eb);
        }
        break;
      }
    }
    if (!done) {
      for (int k = segment.begin; k < segment.end; ++k) {
        projectOne(k, links, how, x, lambda, result);
      }
    }
  }
  alignas(32) double lanes[4];
  _mm256_store_pd(lanes, max_change);
  for (double lane : lanes) result.max_change = std::max(result.max_change, lane);
}
#endif

}  // namespace

void StretchLinks::clear() {
  i.clear();
  j.clear();
  rest_length.clear();
  original.clear();
  position.clear();
  batch_begin.assign(1, 0);
  task_batch.assign(1, 0);
  phase_task.assign(1, 0);
  segments.clear();
  batch_segment.assign(1, 0);
  inverse_mass_i.clear();
  inverse_mass_j.clear();
  inverse_denominator.clear();
}

namespace {

// Rows per block: eight blocks where the grid has the rows for them (two threads take four each),
// at least four rows each (a seam's links touch two rows; seams two rows apart share none), else
// one block (the whole grid, one task).
int blockRows(int grid_rows) { return grid_rows >= 32 ? (grid_rows + 7) / 8 : grid_rows; }

}  // namespace

void StretchLinks::assign(const std::vector<DistanceConstraint>& links, int particle_count,
                          int grid_rows, int grid_cols) {
  clear();
  const int count = static_cast<int>(links.size());
  auto inside = [particle_count](int p) { return p >= 0 && p < particle_count; };
  // Each link's task: phase 0 tasks (even blocks), phase 1 (odd blocks), phase 2 (seams).
  const int grid_size = grid_rows * grid_cols;
  const int rows_per_block = grid_cols > 0 ? std::max(1, blockRows(grid_rows)) : 1;
  const int blocks = grid_cols > 0 ? (grid_rows + rows_per_block - 1) / rows_per_block : 1;
  auto blockOf = [&](int p) { return p < grid_size ? p / grid_cols / rows_per_block : -1; };
  // Task numbering: blocks 0 .. blocks - 1, then seams b | b + 1 for b = 0 .. blocks - 2.
  const int task_count = blocks > 1 ? blocks + (blocks - 1) : 1;
  std::vector<int> task_of(count, 0);
  bool decomposable = blocks > 1;
  for (int c = 0; c < count && decomposable; ++c) {
    const int a = blockOf(links[c].i), b = blockOf(links[c].j);
    if (a < 0 || b < 0 || std::abs(a - b) > 1) {
      decomposable = false;  // a link off the grid or across more than one seam: one task
    } else if (a == b) {
      task_of[c] = a;
    } else {
      task_of[c] = blocks + std::min(a, b);
    }
  }
  const int tasks = decomposable ? task_count : 1;
  if (!decomposable) std::fill(task_of.begin(), task_of.end(), 0);
  // Stable grouping by task.
  std::vector<int> task_start(tasks + 1, 0);
  for (int c = 0; c < count; ++c) ++task_start[task_of[c] + 1];
  for (int t = 0; t < tasks; ++t) task_start[t + 1] += task_start[t];
  original.assign(count, 0);
  position.assign(count, 0);
  {
    std::vector<int> next(task_start.begin(), task_start.end() - 1);
    for (int c = 0; c < count; ++c) {
      const int at = next[task_of[c]]++;
      original[at] = c;
      position[c] = at;
    }
  }
  i.reserve(count);
  j.reserve(count);
  rest_length.reserve(count);
  // batch_of[p]: the batch that last touched particle p (-1: none yet).
  std::vector<int> batch_of(std::max(particle_count, 0), -1);
  int current = 0;
  for (int t = 0; t < tasks; ++t) {
    for (int at = task_start[t]; at < task_start[t + 1]; ++at) {
      const DistanceConstraint& link = links[original[at]];
      i.push_back(link.i);
      j.push_back(link.j);
      rest_length.push_back(link.rest_length);
      const bool starts_task = at == task_start[t];
      const bool shares = !inside(link.i) || !inside(link.j) || batch_of[link.i] == current ||
                          batch_of[link.j] == current;
      if (at > 0 && (starts_task || shares)) {  // this link starts the next batch
        batch_begin.push_back(at);
        ++current;
      }
      if (inside(link.i)) batch_of[link.i] = current;
      if (inside(link.j)) batch_of[link.j] = current;
    }
    // The task ends with the batches so far (an empty task has none).
    task_batch.push_back(task_start[t + 1] > 0 ? current + 1 : 0);
  }
  batch_begin.push_back(count);
  if (count == 0) task_batch.assign(tasks + 1, 0);
  // Phases: the blocks [0, blocks), then the seams [blocks, tasks).
  if (tasks > 1) {
    phase_task = {0, blocks, tasks};
  } else {
    phase_task = {0, tasks};
  }
  inverse_mass_i.assign(count, 0.0);
  inverse_mass_j.assign(count, 0.0);
  inverse_denominator.assign(count, 0.0);
  findSegments(particle_count, tasks > 1 ? grid_rows : 0, tasks > 1 ? grid_cols : 0);
}

void StretchPassResult::merge(const StretchPassResult& other) {
  max_change = std::max(max_change, other.max_change);
  if (other.degenerate > 0 && (degenerate == 0 || other.first_degenerate < first_degenerate)) {
    first_degenerate = other.first_degenerate;
  }
  degenerate += other.degenerate;
}

// The register layout of four links from c, if they have one: the particles each register
// touches (4 or 8 from i0, 4 or 8 from j0) must lie inside the particles, and the two windows
// must not overlap (or be the same window, interleaved).
// A strided window loads and stores eight particles of which its links use every other one: the
// four between are written back as they were read. With threads (tasks of grid rows, grid_cols >
// 0) another task may move those meanwhile, and the store would undo its move: a strided window
// must then lie in one grid row, which no other task of its phase touches (tasks hold different
// rows; seams are a block apart).
void StretchLinks::findSegments(int particle_count, int grid_rows, int grid_cols) {
  const int grid_size = grid_rows * grid_cols;
  auto oneRow = [&](int first, int count) {
    if (grid_cols <= 0) return true;  // one task: nothing runs beside it
    const int last = first + count - 1;
    return first < grid_size && last < grid_size && first / grid_cols == last / grid_cols;
  };
  auto layoutAt = [&](int c) {
    const int i0 = i[c], j0 = j[c];
    bool contiguous = true, strided = true, interleaved = true, crossed = true;
    const int m = j[c + 1];  // kCrossed: the first of the four j ends in memory
    for (int k = 1; k < 4; ++k) {
      contiguous = contiguous && i[c + k] == i0 + k && j[c + k] == j0 + k;
      strided = strided && i[c + k] == i0 + 2 * k && j[c + k] == j0 + 2 * k;
    }
    for (int k = 0; k < 4; ++k) crossed = crossed && i[c + k] == i0 + k && j[c + k] == m + (k ^ 1);
    interleaved = strided && j0 == i0 + 1;
    const int gap = std::abs(j0 - i0);
    // Both windows of `width` particles, from i0 and from j_first, inside the particles.
    auto fits = [&](int width, int j_first) {
      return i0 >= 0 && j_first >= 0 && i0 + width <= particle_count &&
             j_first + width <= particle_count;
    };
    if (contiguous && gap >= 4 && fits(4, j0)) return Layout::kContiguous;
    if (crossed && std::abs(m - i0) >= 4 && fits(4, m)) return Layout::kCrossed;
    if (interleaved && fits(8, j0)) return Layout::kInterleaved;
    if (strided && gap >= 8 && fits(8, j0) && oneRow(i0, 8) && oneRow(j0, 8)) {
      return Layout::kStrided;
    }
    return Layout::kScalar;
  };
  for (int b = 0; b < batchCount(); ++b) {
    const int end = batch_begin[b + 1];
    int c = batch_begin[b];
    while (c < end) {
      const Layout layout = c + 4 <= end ? layoutAt(c) : Layout::kScalar;
      if (layout != Layout::kScalar) {
        segments.push_back({c, c + 4, layout});
        c += 4;
      } else if (!segments.empty() && segments.back().layout == Layout::kScalar &&
                 segments.back().end == c &&
                 static_cast<int>(segments.size()) > batch_segment.back()) {
        ++segments.back().end;  // extends this batch's open scalar segment
        ++c;
      } else {
        segments.push_back({c, c + 1, Layout::kScalar});
        ++c;
      }
    }
    batch_segment.push_back(static_cast<int>(segments.size()));
  }
}

void StretchLinks::prepareStep(const double* inverse_mass, double alpha) {
  const int count = size();
  for (int c = 0; c < count; ++c) {
    const double wi = inverse_mass[i[c]], wj = inverse_mass[j[c]];
    inverse_mass_i[c] = wi;
    inverse_mass_j[c] = wj;
    inverse_denominator[c] = wi + wj < kMinInverseMass ? 0.0 : 1.0 / (wi + wj + alpha);
  }
}

bool stretchLinksUseAvx2() {
#ifdef PBD_CLOTH_HAVE_AVX2_PATH
  static const bool has_avx2 = __builtin_cpu_supports("avx2");
  return has_avx2;
#else
  return false;
#endif
}

StretchPassResult projectStretchLinks(const StretchLinks& links, int first_batch, int end_batch,
                                      const StretchProjection& how, PositionColumns position,
                                      double* lambda) {
  StretchPassResult result;
  if (first_batch >= end_batch) return result;
#ifdef PBD_CLOTH_HAVE_AVX2_PATH
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
#endif
  for (; p < end; ++p) {
    interleaved[3 * p] = columns.x[p];
    interleaved[3 * p + 1] = columns.y[p];
    interleaved[3 * p + 2] = columns.z[p];
  }
}

void ColumnPositions::resize(int count) {
  count_ = count;
  storage_.assign(3 * static_cast<std::size_t>(std::max(count, 0)), 0.0);
}

PositionColumns ColumnPositions::columns() {
  double* base = storage_.data();
  return {base, base + count_, base + 2 * static_cast<std::size_t>(count_)};
}

}  // namespace pbd_cloth
