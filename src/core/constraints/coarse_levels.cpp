#include "pbd_cloth/constraints/coarse_levels.h"

#include <algorithm>
#include <cmath>

namespace pbd_cloth {

namespace {

// Below this length a link has no direction (coincident particles): skipped, as in the solver.
constexpr double kMinLength = 1e-12;
constexpr double kMinInverseMass = 1e-300;

// Every other entry of a level's rows (or columns), keeping the last: 0, 2, ..., n - 1 for an odd
// count; for an even one the last gap is 3 instead of 1 (0, 2, ..., n - 4, n - 1), so no coarse
// cell is thinner than the finer level's. Two entries or fewer cannot be coarsened.
std::vector<int> coarsen(const std::vector<int>& lines) {
  const int n = static_cast<int>(lines.size());
  if (n <= 2) return lines;
  std::vector<int> kept;
  for (int k = 0; k + 1 < n; k += 2) kept.push_back(lines[k]);
  if (n % 2 == 0) kept.back() = lines[n - 1];
  if (kept.back() != lines[n - 1]) kept.push_back(lines[n - 1]);
  return kept;
}

}  // namespace

void CoarseLevels::build(int rows, int cols, double spacing, int levels) {
  levels_.clear();
  rows_ = rows;
  cols_ = cols;
  spacing_ = spacing;
  requested_ = levels;
  if (levels <= 0 || rows <= 0 || cols <= 0) return;
  std::vector<int> finer_rows(rows), finer_cols(cols);
  for (int r = 0; r < rows; ++r) finer_rows[r] = r;
  for (int c = 0; c < cols; ++c) finer_cols[c] = c;
  for (int k = 0; k < levels; ++k) {
    const std::vector<int> level_rows = coarsen(finer_rows), level_cols = coarsen(finer_cols);
    if (level_rows.size() == finer_rows.size() && level_cols.size() == finer_cols.size()) break;
    Level level;
    const int nr = static_cast<int>(level_rows.size()), nc = static_cast<int>(level_cols.size());
    auto cloth = [&](int a, int b) { return level_rows[a] * cols + level_cols[b]; };
    auto local = [nc](int a, int b) { return a * nc + b; };
    for (int a = 0; a < nr; ++a) {
      for (int b = 0; b < nc; ++b) {
        level.particles.push_back(cloth(a, b));
      }
    }
    // The links join positions in the level's own particle list (the packed copy they are
    // projected on, projectPacked).
    std::vector<DistanceConstraint> flat;
    auto add = [&](int a0, int b0, int a1, int b1) {
      const double dr = level_rows[a1] - level_rows[a0], dc = level_cols[b1] - level_cols[b0];
      flat.push_back({local(a0, b0), local(a1, b1), spacing * std::sqrt(dr * dr + dc * dc)});
    };
    // Row by row from the first (the pinned edge of the shipped scenes), and within a row in runs
    // of links that share no particle, as the cloth's own sweep (cloth_builder.cpp): links of even
    // then odd columns, every link down to the next row, both diagonals of even then odd cells.
    // Consecutive projections are then independent and overlap in the processor, and in the
    // level's own particle list (row by row) runs of four are whole registers (stretch_links.h).
    for (int a = 0; a < nr; ++a) {
      for (int parity = 0; parity < 2; ++parity) {
        for (int b = parity; b + 1 < nc; b += 2) add(a, b, a, b + 1);
      }
      if (a + 1 == nr) continue;
      for (int b = 0; b < nc; ++b) add(a, b, a + 1, b);
      // Both diagonals of a cell, main then anti, even cells then odd: four in a row step through
      // the upper row one by one and the lower one swapped in pairs (the kCrossed registers).
      for (int parity = 0; parity < 2; ++parity) {
        for (int b = parity; b + 1 < nc; b += 2) {
          add(a, b, a + 1, b + 1);
          add(a, b + 1, a + 1, b);
        }
      }
    }
    level.flat.assign(flat, static_cast<int>(level.particles.size()));
    level.compact_position.resize(static_cast<int>(level.particles.size()));
    level.compact_inverse_mass.assign(level.particles.size(), 0.0);
    levels_.push_back(std::move(level));
    finer_rows = level_rows;
    finer_cols = level_cols;
  }
}

void CoarseLevels::prepareStep(const Particles& p) {
  for (Level& level : levels_) {
    const int count = static_cast<int>(level.particles.size());
    for (int q = 0; q < count; ++q) {
      level.compact_inverse_mass[q] = p.inverse_mass[level.particles[q]];
    }
    level.flat.prepareStep(level.compact_inverse_mass.data(), 0.0);
  }
}

double CoarseLevels::projectPacked(Level& level, bool simd, bool track_change, bool avx512) {
  StretchProjection how;
  how.unilateral = true;
  how.simd = simd;
  how.avx512 = avx512;
  how.track_change = track_change;
  return projectStretchLinks(level.flat, 0, level.flat.batchCount(), how,
                             level.compact_position.columns(), nullptr)
      .max_change;
}

double CoarseLevels::project(PositionColumns cloth, bool simd, bool track_change, bool avx512) {
  double max_change = 0.0;
  for (int k = static_cast<int>(levels_.size()) - 1; k >= 0; --k) {
    Level& level = levels_[k];
    const int count = static_cast<int>(level.particles.size());
    const PositionColumns packed = level.compact_position.columns();
    const int* particles = level.particles.data();
    for (int q = 0; q < count; ++q) {
      packed.x[q] = cloth.x[particles[q]];
      packed.y[q] = cloth.y[particles[q]];
      packed.z[q] = cloth.z[particles[q]];
    }
    max_change = std::max(max_change, projectPacked(level, simd, track_change, avx512));
    for (int q = 0; q < count; ++q) {
      cloth.x[particles[q]] = packed.x[q];
      cloth.y[particles[q]] = packed.y[q];
      cloth.z[particles[q]] = packed.z[q];
    }
  }
  return max_change;
}

double CoarseLevels::project(Particles& p, bool simd, bool track_change, bool avx512) {
  if (levels_.empty()) return 0.0;
  double max_change = 0.0;
  for (int k = static_cast<int>(levels_.size()) - 1; k >= 0; --k) {
    Level& level = levels_[k];
    // Each end moves itself: the cloth's own projection (stretch_links.h) with C = max(0, C),
    // k = 1, no compliance and no multiplier, on a packed copy of the level's particles. The
    // links touch no other particle, so the copy changes no operation (same result as in
    // place) and lets the level's rows go four links to a register: in the cloth's array a
    // level's particles lie 2^k apart, and scattered links go one at a time at twice the cost.
    const int count = static_cast<int>(level.particles.size());
    const PositionColumns packed = level.compact_position.columns();
    for (int q = 0; q < count; ++q) {
      const Vec3& x = p.position[level.particles[q]];
      packed.x[q] = x[0];
      packed.y[q] = x[1];
      packed.z[q] = x[2];
    }
    max_change = std::max(max_change, projectPacked(level, simd, track_change, avx512));
    for (int q = 0; q < count; ++q) {
      p.position[level.particles[q]] = Vec3(packed.x[q], packed.y[q], packed.z[q]);
    }
  }
  return max_change;
}

}  // namespace pbd_cloth
