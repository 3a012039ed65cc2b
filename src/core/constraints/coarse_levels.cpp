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

// The coarse interval [lines[a], lines[a + 1]] holding `line`, and the fraction of the way along.
void locate(const std::vector<int>& lines, int line, int& a, double& fraction) {
  if (lines.size() < 2) {
    a = 0;
    fraction = 0.0;
    return;
  }
  a = static_cast<int>(std::upper_bound(lines.begin(), lines.end(), line) - lines.begin()) - 1;
  a = std::max(0, std::min(a, static_cast<int>(lines.size()) - 2));
  fraction = static_cast<double>(line - lines[a]) / (lines[a + 1] - lines[a]);
}

}  // namespace

void CoarseLevels::build(int rows, int cols, double spacing, int levels) {
  levels_.clear();
  rows_ = rows;
  cols_ = cols;
  spacing_ = spacing;
  requested_ = levels;
  if (levels <= 0 || rows <= 0 || cols <= 0) {
    start_.clear();
    displacement_.clear();
    return;
  }
  std::vector<int> finer_rows(rows), finer_cols(cols);
  for (int r = 0; r < rows; ++r) finer_rows[r] = r;
  for (int c = 0; c < cols; ++c) finer_cols[c] = c;
  std::size_t largest = 0;
  // Local index of each cloth particle on the finer level, and what it carries (1 on the cloth).
  std::vector<int> finer_local(static_cast<std::size_t>(rows) * cols);
  for (std::size_t i = 0; i < finer_local.size(); ++i) finer_local[i] = static_cast<int>(i);
  std::vector<double> finer_carried(finer_local.size(), 1.0);
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
        level.carried.push_back(finer_carried[finer_local[cloth(a, b)]]);
      }
    }
    auto add = [&](int a0, int b0, int a1, int b1) {
      const double dr = level_rows[a1] - level_rows[a0], dc = level_cols[b1] - level_cols[b0];
      Link link;
      link.i = cloth(a0, b0);
      link.j = cloth(a1, b1);
      link.local_i = local(a0, b0);
      link.local_j = local(a1, b1);
      link.rest_length = spacing * std::sqrt(dr * dr + dc * dc);
      level.links.push_back(link);
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
    // The finer level's particles this level does not hold, with their coarse cell.
    for (int finer_r : finer_rows) {
      for (int finer_c : finer_cols) {
        const bool on_row = std::binary_search(level_rows.begin(), level_rows.end(), finer_r);
        const bool on_col = std::binary_search(level_cols.begin(), level_cols.end(), finer_c);
        if (on_row && on_col) continue;
        Interpolated f;
        f.particle = finer_r * cols + finer_c;
        int a = 0, b = 0;
        double fr = 0.0, fc = 0.0;
        locate(level_rows, finer_r, a, fr);
        locate(level_cols, finer_c, b, fc);
        const int a1 = std::min(a + 1, nr - 1), b1 = std::min(b + 1, nc - 1);
        f.corner[0] = local(a, b);
        f.corner[1] = local(a, b1);
        f.corner[2] = local(a1, b);
        f.corner[3] = local(a1, b1);
        f.weight[0] = (1.0 - fr) * (1.0 - fc);
        f.weight[1] = (1.0 - fr) * fc;
        f.weight[2] = fr * (1.0 - fc);
        f.weight[3] = fr * fc;
        for (int corner = 0; corner < 4; ++corner) {
          level.carried[f.corner[corner]] +=
              f.weight[corner] * finer_carried[finer_local[f.particle]];
        }
        level.finer_only.push_back(f);
      }
    }
    std::vector<DistanceConstraint> flat;
    flat.reserve(level.links.size());
    for (const Link& link : level.links) {
      flat.push_back({link.local_i, link.local_j, link.rest_length});
    }
    level.flat.assign(flat, static_cast<int>(level.particles.size()));
    level.compact_position.resize(static_cast<int>(level.particles.size()));
    level.compact_inverse_mass.assign(level.particles.size(), 0.0);
    largest = std::max(largest, level.particles.size());
    finer_carried = level.carried;
    for (std::size_t q = 0; q < level.particles.size(); ++q) {
      finer_local[level.particles[q]] = static_cast<int>(q);
    }
    levels_.push_back(std::move(level));
    finer_rows = level_rows;
    finer_cols = level_cols;
  }
  start_.assign(static_cast<std::size_t>(rows) * cols, Vec3::Zero());
  displacement_.assign(largest, Vec3::Zero());
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

double CoarseLevels::project(Particles& p, bool interpolate, bool simd, bool track_change,
                             bool avx512) {
  if (levels_.empty()) return 0.0;
  if (interpolate) {
    for (int i : levels_.front().particles) start_[i] = p.position[i];
  }
  double max_change = 0.0;
  for (int k = static_cast<int>(levels_.size()) - 1; k >= 0; --k) {
    Level& level = levels_[k];
    if (!interpolate) {
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
      continue;
    }
    // Unilateral: a coarse link only pulls its ends together, never pushes them apart.
    for (const Link& link : level.links) {
      // Interpolated, an end moves the cloth it carries; alone, it moves itself.
      const double wi = interpolate ? p.inverse_mass[link.i] / level.carried[link.local_i]
                                    : p.inverse_mass[link.i];
      const double wj = interpolate ? p.inverse_mass[link.j] / level.carried[link.local_j]
                                    : p.inverse_mass[link.j];
      const double w = wi + wj;
      if (w < kMinInverseMass) continue;
      const Vec3 delta = p.position[link.i] - p.position[link.j];
      const double length = delta.norm();
      if (!(length >= kMinLength)) continue;  // coincident (or not finite): no direction
      // Slack links get a zero correction rather than a branch: whether a link is taut changes
      // from link to link, and a mispredicted branch costs more than the arithmetic.
      const double excess = std::max(0.0, length - link.rest_length);
      const Vec3 correction = (excess / (w * length)) * delta;
      p.position[link.i] -= wi * correction;
      p.position[link.j] += wj * correction;
      max_change = std::max(max_change, excess * std::max(wi, wj) / w);
    }
    if (!interpolate) continue;
    const int count = static_cast<int>(level.particles.size());
    for (int q = 0; q < count; ++q) {
      const int i = level.particles[q];
      displacement_[q] = p.position[i] - start_[i];
    }
    // The finer level's other particles have not moved in this cycle yet: they follow their
    // coarse cell, so the finer level starts from the coarse shape with its own detail kept.
    for (const Interpolated& f : level.finer_only) {
      if (p.inverse_mass[f.particle] == 0.0) continue;
      p.position[f.particle] +=
          f.weight[0] * displacement_[f.corner[0]] + f.weight[1] * displacement_[f.corner[1]] +
          f.weight[2] * displacement_[f.corner[2]] + f.weight[3] * displacement_[f.corner[3]];
    }
  }
  return max_change;
}

}  // namespace pbd_cloth
