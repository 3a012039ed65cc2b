#include "pbd_cloth/geometry/spatial_hash.h"

#include <algorithm>
#include <cmath>

namespace pbd_cloth {

namespace {

// Cell coordinates are clamped to this range so a far-away or non-finite position still maps to a
// valid (if crowded) cell instead of overflowing an int.
constexpr double kMaxCell = 1.0e9;

int toCell(double v) {
  const double f = std::floor(v);
  if (!(f > -kMaxCell)) return static_cast<int>(-kMaxCell);  // also catches NaN
  if (f > kMaxCell) return static_cast<int>(kMaxCell);
  return static_cast<int>(f);
}

}  // namespace

void SpatialHash::reserve(int items) {
  // About two buckets per entry keeps the buckets short; a box typically covers a few cells, and
  // the entry buffers hold 16 per item so that a step allocates nothing unless boxes grow long.
  std::size_t size = 64;
  while (size < 8 * static_cast<std::size_t>(std::max(items, 1))) size *= 2;
  mask_ = size - 1;
  bucket_start_.assign(size + 1, 0);
  entries_.reserve(16 * static_cast<std::size_t>(items));
  unsorted_.reserve(16 * static_cast<std::size_t>(items));
  lo_.reserve(items);
  hi_.reserve(items);
  lo_cell_.reserve(items);
  overflow_.reserve(items);
}

SpatialHash::Cell SpatialHash::cellOf(const Vec3& x) const {
  return Cell(toCell(x.x() * inverse_cell_), toCell(x.y() * inverse_cell_),
              toCell(x.z() * inverse_cell_));
}

void SpatialHash::build(const Vec3Array& lo, const Vec3Array& hi, int count, double cell_size) {
  if (bucket_start_.size() < 2 || 8 * static_cast<std::size_t>(count) > mask_ + 1) reserve(count);
  cell_size_ = cell_size;
  inverse_cell_ = 1.0 / cell_size;
  lo_.assign(lo.begin(), lo.begin() + count);
  hi_.assign(hi.begin(), hi.begin() + count);
  lo_cell_.resize(count);
  unsorted_.clear();
  overflow_.clear();
  for (int k = 0; k < count; ++k) {
    const Cell a = cellOf(lo[k]), b = cellOf(hi[k]);
    lo_cell_[k] = a;
    if (cellsSpanned(a, b) > kMaxCellsPerItem) {
      overflow_.push_back(k);
      continue;
    }
    for (int x = a.x(); x <= b.x(); ++x) {
      for (int y = a.y(); y <= b.y(); ++y) {
        for (int z = a.z(); z <= b.z(); ++z) unsorted_.push_back({k, Cell(x, y, z)});
      }
    }
  }
  // Counting sort of the entries by bucket: count, prefix sums, then place from the back.
  std::fill(bucket_start_.begin(), bucket_start_.end(), 0);
  for (const Entry& entry : unsorted_) ++bucket_start_[bucketOf(entry.cell) + 1];
  for (std::size_t b = 1; b < bucket_start_.size(); ++b) bucket_start_[b] += bucket_start_[b - 1];
  entries_.resize(unsorted_.size());
  for (std::size_t e = unsorted_.size(); e-- > 0;) {
    entries_[--bucket_start_[bucketOf(unsorted_[e].cell) + 1]] = unsorted_[e];
  }
  // Placing decremented every end down to its start: bucket_start_[b + 1] now holds the start of
  // bucket b. Shift left to restore start(b) = bucket_start_[b], end(b) = bucket_start_[b + 1].
  const std::size_t size = bucket_start_.size() - 1;
  for (std::size_t b = 0; b < size; ++b) bucket_start_[b] = bucket_start_[b + 1];
  bucket_start_[size] = static_cast<int>(entries_.size());
}

}  // namespace pbd_cloth
