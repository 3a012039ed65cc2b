#include "pbd_cloth/spatial_hash.h"

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
  // About two buckets per item keeps the buckets short.
  std::size_t size = 64;
  while (size < 2 * static_cast<std::size_t>(std::max(items, 1))) size *= 2;
  mask_ = size - 1;
  bucket_start_.assign(size + 1, 0);
  sorted_.reserve(items);
  item_cell_.reserve(items);
}

SpatialHash::Cell SpatialHash::cellOf(const Vec3& x) const {
  return Cell(toCell(x.x() * inverse_cell_), toCell(x.y() * inverse_cell_),
              toCell(x.z() * inverse_cell_));
}

void SpatialHash::build(const Vec3Array& points, int count, double cell_size) {
  if (bucket_start_.size() < 2 || 2 * static_cast<std::size_t>(count) > mask_ + 1) reserve(count);
  cell_size_ = cell_size;
  inverse_cell_ = 1.0 / cell_size;
  item_cell_.resize(count);
  sorted_.resize(count);
  // Counting sort: count the items per bucket, prefix sums, then place them.
  std::fill(bucket_start_.begin(), bucket_start_.end(), 0);
  for (int k = 0; k < count; ++k) {
    item_cell_[k] = cellOf(points[k]);
    ++bucket_start_[bucketOf(item_cell_[k]) + 1];
  }
  for (std::size_t b = 1; b < bucket_start_.size(); ++b) bucket_start_[b] += bucket_start_[b - 1];
  // Place from the back so each bucket keeps item order, using the starts as running ends.
  for (int k = count - 1; k >= 0; --k) {
    const std::size_t bucket = bucketOf(item_cell_[k]);
    sorted_[--bucket_start_[bucket + 1]] = k;
  }
  // Placing decremented every end down to its start: bucket_start_[b + 1] now holds the start of
  // bucket b. Shift left to restore start(b) = bucket_start_[b], end(b) = bucket_start_[b + 1].
  const std::size_t size = bucket_start_.size() - 1;
  for (std::size_t b = 0; b < size; ++b) bucket_start_[b] = bucket_start_[b + 1];
  bucket_start_[size] = count;
}

}  // namespace pbd_cloth
