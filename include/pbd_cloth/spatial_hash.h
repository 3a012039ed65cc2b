// Broad phase: a uniform grid stored as a hash table of fixed size (Teschner et al. 2003,
// "Optimized Spatial Hashing for Collision Detection of Deformable Objects"). Items are sorted into
// the table by counting sort into flat arrays, so once reserve() has sized it a build allocates
// nothing.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "pbd_cloth/particles.h"

namespace pbd_cloth {

class SpatialHash {
 public:
  using Cell = Eigen::Vector3i;

  // Sizes the table for up to `items` items.
  void reserve(int items);

  // Files item k (0 <= k < count) under the cell that contains points[k].
  void build(const Vec3Array& points, int count, double cell_size);

  double cellSize() const { return cell_size_; }
  int itemCount() const { return static_cast<int>(item_cell_.size()); }
  Cell cellOf(const Vec3& x) const;

  // Calls visit(item) exactly once for every item whose cell lies in the cell range spanned by the
  // points lo and hi (inclusive). Items of other cells that share a bucket are skipped by comparing
  // their cell, so a hash collision costs time but never a duplicate.
  template <class Visit>
  void forEachInRange(const Vec3& lo, const Vec3& hi, Visit&& visit) const;

 private:
  std::size_t bucketOf(const Cell& cell) const {
    // The three large primes of Teschner et al.
    const std::uint64_t h = (static_cast<std::uint64_t>(static_cast<std::int64_t>(cell.x())) *
                             73856093ULL) ^
                            (static_cast<std::uint64_t>(static_cast<std::int64_t>(cell.y())) *
                             19349663ULL) ^
                            (static_cast<std::uint64_t>(static_cast<std::int64_t>(cell.z())) *
                             83492791ULL);
    return static_cast<std::size_t>(h & mask_);
  }

  double cell_size_ = 1.0;
  double inverse_cell_ = 1.0;
  std::uint64_t mask_ = 0;
  std::vector<int> bucket_start_;  // table size + 1 entries: items of bucket b are
                                   // sorted_[bucket_start_[b] .. bucket_start_[b + 1])
  std::vector<int> sorted_;
  std::vector<Cell> item_cell_;
};

template <class Visit>
void SpatialHash::forEachInRange(const Vec3& lo, const Vec3& hi, Visit&& visit) const {
  const Cell a = cellOf(lo), b = cellOf(hi);
  const double cells = (static_cast<double>(b.x()) - a.x() + 1.0) *
                       (static_cast<double>(b.y()) - a.y() + 1.0) *
                       (static_cast<double>(b.z()) - a.z() + 1.0);
  const int count = itemCount();
  if (cells > 4.0 * count + 64.0) {
    // A range larger than the population (a runaway particle): scanning the items is cheaper.
    for (int k = 0; k < count; ++k) {
      const Cell& c = item_cell_[k];
      if ((c.array() >= a.array()).all() && (c.array() <= b.array()).all()) visit(k);
    }
    return;
  }
  for (int x = a.x(); x <= b.x(); ++x) {
    for (int y = a.y(); y <= b.y(); ++y) {
      for (int z = a.z(); z <= b.z(); ++z) {
        const Cell cell(x, y, z);
        const std::size_t bucket = bucketOf(cell);
        for (int s = bucket_start_[bucket]; s < bucket_start_[bucket + 1]; ++s) {
          const int k = sorted_[s];
          if (item_cell_[k] == cell) visit(k);
        }
      }
    }
  }
}

}  // namespace pbd_cloth
