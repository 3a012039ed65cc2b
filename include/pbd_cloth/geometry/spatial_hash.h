// Broad phase: a uniform grid stored as a hash table of fixed size (Teschner et al. 2003,
// "Optimized Spatial Hashing for Collision Detection of Deformable Objects"). Each item is a box
// filed under every cell it overlaps; the entries are sorted into the table by counting sort into
// flat arrays, so once the buffers have grown to the scene's needs a build allocates nothing.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "pbd_cloth/geometry/vector_types.h"

namespace pbd_cloth {

class SpatialHash {
 public:
  using Cell = Eigen::Vector3i;

  // Sizes the table and the entry buffers for about `items` items.
  void reserve(int items);

  // Files item k (0 <= k < count), the box [lo[k], hi[k]], under every cell it overlaps. The cell
  // should be about the size of a typical box: a few fast particles with long swept boxes then
  // cost a few more entries, not a coarser grid for everyone. A box spanning more than
  // kMaxCellsPerItem cells goes to an overflow list that every query checks.
  void build(const Vec3Array& lo, const Vec3Array& hi, int count, double cell_size);

  double cellSize() const { return cell_size_; }
  Cell cellOf(const Vec3& x) const;

  // Calls visit(item) exactly once for every item whose box overlaps [lo, hi]. A pair is reported
  // only from the cell holding the lower corner of the two boxes' intersection, so an item filed
  // in several cells is not reported twice, and entries of other cells that share a bucket are
  // skipped by comparing their cell.
  template <class Visit>
  void forEachOverlapping(const Vec3& lo, const Vec3& hi, Visit&& visit) const;

  static constexpr int kMaxCellsPerItem = 64;

 private:
  struct Entry {
    int item;
    Cell cell;
  };

  std::size_t bucketOf(const Cell& cell) const {
    // The three large primes of Teschner et al.
    const std::uint64_t h =
        (static_cast<std::uint64_t>(static_cast<std::int64_t>(cell.x())) * 73856093ULL) ^
        (static_cast<std::uint64_t>(static_cast<std::int64_t>(cell.y())) * 19349663ULL) ^
        (static_cast<std::uint64_t>(static_cast<std::int64_t>(cell.z())) * 83492791ULL);
    return static_cast<std::size_t>(h & mask_);
  }
  static bool overlap(const Vec3& lo_a, const Vec3& hi_a, const Vec3& lo_b, const Vec3& hi_b) {
    return (lo_a.array() <= hi_b.array()).all() && (lo_b.array() <= hi_a.array()).all();
  }
  static double cellsSpanned(const Cell& a, const Cell& b) {
    return (static_cast<double>(b.x()) - a.x() + 1.0) * (static_cast<double>(b.y()) - a.y() + 1.0) *
           (static_cast<double>(b.z()) - a.z() + 1.0);
  }

  double cell_size_ = 1.0;
  double inverse_cell_ = 1.0;
  std::uint64_t mask_ = 0;
  std::vector<int> bucket_start_;  // table size + 1: entries of bucket b are
                                   // entries_[bucket_start_[b] .. bucket_start_[b + 1])
  std::vector<Entry> entries_;
  std::vector<Entry> unsorted_;
  std::vector<int> overflow_;  // items whose boxes span too many cells
  Vec3Array lo_;               // the boxes, for the exact overlap test
  Vec3Array hi_;
  std::vector<Cell> lo_cell_;  // cell of each box's lower corner
};

template <class Visit>
void SpatialHash::forEachOverlapping(const Vec3& lo, const Vec3& hi, Visit&& visit) const {
  for (int k : overflow_) {
    if (overlap(lo, hi, lo_[k], hi_[k])) visit(k);
  }
  const Cell a = cellOf(lo), b = cellOf(hi);
  const int count = static_cast<int>(lo_.size());
  if (cellsSpanned(a, b) > 4.0 * count + 64.0) {
    // A query box larger than the population (a runaway particle): scanning is cheaper.
    for (int k = 0; k < count; ++k) {
      if (overlap(lo, hi, lo_[k], hi_[k]) &&
          cellsSpanned(cellOf(lo_[k]), cellOf(hi_[k])) <= kMaxCellsPerItem) {
        visit(k);
      }
    }
    return;
  }
  for (int x = a.x(); x <= b.x(); ++x) {
    for (int y = a.y(); y <= b.y(); ++y) {
      for (int z = a.z(); z <= b.z(); ++z) {
        const Cell cell(x, y, z);
        const std::size_t bucket = bucketOf(cell);
        for (int s = bucket_start_[bucket]; s < bucket_start_[bucket + 1]; ++s) {
          const Entry& entry = entries_[s];
          if (entry.cell != cell) continue;
          const int k = entry.item;
          if (!overlap(lo, hi, lo_[k], hi_[k])) continue;
          // cellOf is monotonic: the cell of the intersection's lower corner is the larger of the
          // two boxes' lower cells, axis by axis.
          if (a.cwiseMax(lo_cell_[k]) != cell) continue;  // reported from another cell
          visit(k);
        }
      }
    }
  }
}

}  // namespace pbd_cloth
