#include "pbd_cloth/constraints/stretch_links.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace pbd_cloth {

namespace {

// Below this a link's generalized inverse mass is zero (both ends kinematic): skipped.
constexpr double kMinInverseMass = 1e-300;

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

// The register layout of n links from c (n = 8, else 4), if they have one: the particles each
// register touches (n or 2n from i0, n or 2n from j0) must lie inside the particles, and the two
// windows must not overlap (or be the same window, interleaved). Eight are tried first: one
// AVX-512 register, or two AVX2 ones.
// A strided window loads and stores 2n particles of which its links use every other one: the n
// between are written back as they were read. With threads (tasks of grid rows, grid_cols > 0)
// another task may move those meanwhile, and the store would undo its move: a strided window
// must then lie in one grid row, which no other task of its phase touches (tasks hold different
// rows; seams are a block apart).
void StretchLinks::findSegments(int particle_count, int grid_rows, int grid_cols) {
  const int grid_size = grid_rows * grid_cols;
  auto oneRow = [&](int first, int count) {
    if (grid_cols <= 0) return true;  // one task: nothing runs beside it
    const int last = first + count - 1;
    return first < grid_size && last < grid_size && first / grid_cols == last / grid_cols;
  };
  auto layoutAt = [&](int c, int n) {
    const int i0 = i[c], j0 = j[c];
    bool contiguous = true, strided = true, interleaved = true, crossed = true;
    const int m = j[c + 1];  // kCrossed: the first of the n j ends in memory
    for (int k = 1; k < n; ++k) {
      contiguous = contiguous && i[c + k] == i0 + k && j[c + k] == j0 + k;
      strided = strided && i[c + k] == i0 + 2 * k && j[c + k] == j0 + 2 * k;
    }
    for (int k = 0; k < n; ++k) crossed = crossed && i[c + k] == i0 + k && j[c + k] == m + (k ^ 1);
    interleaved = strided && j0 == i0 + 1;
    const int gap = std::abs(j0 - i0);
    // Both windows of `width` particles, from i0 and from j_first, inside the particles.
    auto fits = [&](int width, int j_first) {
      return i0 >= 0 && j_first >= 0 && i0 + width <= particle_count &&
             j_first + width <= particle_count;
    };
    if (contiguous && gap >= n && fits(n, j0)) return Layout::kContiguous;
    if (crossed && std::abs(m - i0) >= n && fits(n, m)) return Layout::kCrossed;
    if (interleaved && fits(2 * n, j0)) return Layout::kInterleaved;
    if (strided && gap >= 2 * n && fits(2 * n, j0) && oneRow(i0, 2 * n) && oneRow(j0, 2 * n)) {
      return Layout::kStrided;
    }
    return Layout::kScalar;
  };
  for (int b = 0; b < batchCount(); ++b) {
    const int end = batch_begin[b + 1];
    int c = batch_begin[b];
    while (c < end) {
      int n = 8;
      Layout layout = c + 8 <= end ? layoutAt(c, 8) : Layout::kScalar;
      if (layout == Layout::kScalar) {
        n = 4;
        layout = c + 4 <= end ? layoutAt(c, 4) : Layout::kScalar;
      }
      if (layout != Layout::kScalar) {
        segments.push_back({c, c + n, layout});
        c += n;
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

void ColumnPositions::resize(int count) {
  count_ = count;
  storage_.assign(3 * static_cast<std::size_t>(std::max(count, 0)), 0.0);
}

PositionColumns ColumnPositions::columns() {
  double* base = storage_.data();
  return {base, base + count_, base + 2 * static_cast<std::size_t>(count_)};
}

}  // namespace pbd_cloth
