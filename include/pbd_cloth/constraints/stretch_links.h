// Distance links in flat arrays, grouped in batches of links that share no particle, and the one
// projection every stretch-like link of the solver goes through: the cloth's stretch constraints
// (seed eq. C2; XPBD eq. 18) and the coarse levels' unilateral long-range links.
//
// Why batches: inside a batch no two links touch the same particle, so projecting them one after
// the other (Gauss-Seidel) gives exactly what projecting them all at once from the same positions
// gives. That lets four links go through one AVX2 register, or eight through one AVX-512 register
// (the square root and the division, the costly part, at once), and lets threads split a batch
// (solver.threads), with results that do not depend on either: the order of the links is the
// order of the list, whatever runs it. The
// projection reads and writes the positions in columns (PositionColumns, below), where four
// consecutive particles' coordinates load without shuffles.
//
// Runtime dispatch: the AVX-512 and AVX2 paths are compiled for their instruction set only (a
// function target attribute) and the widest the processor has is chosen at run time; any other
// x86-64 (a lab's older PC) or another architecture runs the portable loop. The source file is
// compiled without floating-point contraction, so every path rounds the same operations the same
// way and gives bit-identical results (test_core: StretchLinks.*).
#pragma once

#include <vector>

#include "pbd_cloth/model/particles.h"

namespace pbd_cloth {

struct StretchLinks {
  std::vector<int> i;  // particle indices of each link
  std::vector<int> j;
  std::vector<double> rest_length;  // m
  std::vector<int> original;        // each link's index in the list given to assign()
  std::vector<int> position;        // and back: position[original index] = index here
  // Batch b holds links [batch_begin[b], batch_begin[b + 1]); no two of them share a particle.
  std::vector<int> batch_begin;

  // Blocks of a grid cloth for threads (solver.threads). The rows are cut into blocks; a link
  // with both ends in one block belongs to that block's task, a link across two blocks to the
  // seam task between them. Phase 0 = the blocks, top to bottom, phase 1 = the seams: the tasks
  // of one phase share no particle (blocks hold different rows; seams are a block apart), so
  // they may run on different threads in any order with the same result. The sweep is always
  // this order (phase by phase, task by task, each task in the builder's top-down order),
  // whatever the thread count: results are bit-identical for every solver.threads. Only the
  // seams' links wait for the end of the sweep.
  // Task t holds batches [task_batch[t], task_batch[t + 1]); phase p tasks [phase_task[p],
  // phase_task[p + 1]). A mesh cloth or a grid under 8 rows is one task.
  std::vector<int> task_batch;
  std::vector<int> phase_task;

  // How a run of links is laid out in memory, found once in assign(). A grid's batches are rows
  // of links whose ends step through the particles regularly; eight (or four) such links are
  // loaded and stored as whole registers (one per coordinate of eight or four consecutive
  // particles in the columns, PositionColumns), without gathers. A segment of eight goes through
  // one AVX-512 register or two AVX2 ones, with the same result (its links share no particle).
  // kScalar: one link at a time (a mesh's links, the ends of a batch, a group with a coincident
  // pair). The patterns below are for four links; eight continue them (k < 8).
  enum class Layout : int {
    kScalar,       // [begin, end): any links, projected one by one
    kContiguous,   // 4 links: i = i0 + k, j = j0 + k (vertical and diagonal grid links)
    kInterleaved,  // 4 links: i = i0 + 2k, j = i0 + 2k + 1 (horizontal links of one parity)
    kStrided,      // 4 links: i = i0 + 2k, j = j0 + 2k (the single diagonal of every other cell)
    kCrossed,      // 4 links: i = i0 + k, j = m + (k xor 1) (both diagonals of every other cell,
                   // main then anti: the j ends are those of kContiguous swapped in pairs)
  };
  struct Segment {
    int begin = 0;
    int end = 0;
    Layout layout = Layout::kScalar;
  };
  std::vector<Segment> segments;   // in list order; a segment never spans two batches
  std::vector<int> batch_segment;  // batch b's segments: [batch_segment[b], batch_segment[b+1])

  // Per step (prepareStep): each link's end inverse masses and 1 / (w_i + w_j + alpha~), zero
  // for a link with no free end. The kinematic set and h are fixed within a step, so the
  // projection divides once per link (by its length), not twice.
  std::vector<double> inverse_mass_i;
  std::vector<double> inverse_mass_j;
  std::vector<double> inverse_denominator;

  int size() const { return static_cast<int>(i.size()); }
  int batchCount() const { return static_cast<int>(batch_begin.size()) - 1; }
  int taskCount() const { return static_cast<int>(task_batch.size()) - 1; }
  int phaseCount() const { return static_cast<int>(phase_task.size()) - 1; }
  int taskLinks(int t) const { return batch_begin[task_batch[t + 1]] - batch_begin[task_batch[t]]; }
  // Copies the links, grouped by task when grid_cols > 0 (a grid of grid_rows x grid_cols
  // particles first in the particle list), each task in the list's order, and cuts each task
  // into batches: the longest runs in which no particle repeats (so the sweep is the Gauss-Seidel
  // sweep the builder laid out); then finds each batch's register layouts.
  void assign(const std::vector<DistanceConstraint>& links, int particle_count, int grid_rows = 0,
              int grid_cols = 0);
  void clear();
  // Before the projections of a step: alpha~ = compliance / h^2 of its substeps (0 for PBD).
  void prepareStep(const double* inverse_mass, double alpha);

 private:
  void findSegments(int particle_count, int grid_rows, int grid_cols);
};

// How a call projects its links. Stretch constraint: C = |x_i - x_j| - l0, multiplier step
// dlambda = (-k C - alpha~ lambda) / (w_i + w_j + alpha~): XPBD with k = 1 and alpha~ = compliance
// / h^2 (eq. 18), PBD with alpha~ = 0 and k its pass stiffness, the seed's rigid stick with both.
// Unilateral links (the coarse levels) use C = max(0, |x_i - x_j| - l0): they only pull.
struct StretchProjection {
  double alpha = 0.0;      // alpha~ = compliance / h^2, as given to prepareStep
  double stiffness = 1.0;  // k
  bool unilateral = false;
  bool simd = true;    // false: the portable loop even where AVX2 is there (tests, benchmarks)
  bool avx512 = true;  // false: AVX2 at most, even where AVX-512 is there (solver.avx512)
  // Whether the pass measures its largest correction (StretchPassResult::max_change), which only
  // solver.tolerance reads: without it the pass leaves out a multiplication and two maxima per
  // link, and max_change stays 0.
  bool track_change = true;
  // The first pass of a substep, where every multiplier starts at zero (XPBD, Algorithm 1): lambda
  // is written and not read, so the substep needs no pass of its own to clear it.
  bool lambda_from_zero = false;
};

struct StretchPassResult {
  double max_change = 0.0;    // largest |dlambda| max(w_i, w_j): the largest particle move (m)
  int degenerate = 0;         // links skipped because their particles coincide (no direction)
  int first_degenerate = -1;  // the first of them in the sweep: its index here (see `original`)
  void merge(const StretchPassResult& other);
};

// The particles' positions as three columns, x[p], y[p] and z[p] (a structure of arrays), the
// form the projection works on: four consecutive particles' x (or y, or z) are one register load,
// where Vec3Array's interleaved x0 y0 z0 x1 ... needs three loads and six shuffles for four
// particles' coordinates, and as many to store them (doc/journal.md, "2026-11-29: Positions in
// columns").
struct PositionColumns {
  double* x = nullptr;
  double* y = nullptr;
  double* z = nullptr;
};

// Storage for the columns of `count` particles, sized outside the step (resize allocates;
// columns() does not).
class ColumnPositions {
 public:
  void resize(int count);
  int size() const { return count_; }
  PositionColumns columns();

 private:
  std::vector<double> storage_;
  int count_ = 0;
};

// Copies particles [begin, end) between Vec3Array storage (x0 y0 z0 x1 ...) and columns, exactly
// (AVX2 shuffles where there and simd, else a plain loop). Allocates nothing.
void positionsToColumns(const double* interleaved, int begin, int end, PositionColumns columns,
                        bool simd);
void positionsFromColumns(PositionColumns columns, int begin, int end, double* interleaved,
                          bool simd);

// Projects the links of batches [first_batch, end_batch) in order, after links.prepareStep:
// position is the particles' positions in columns, lambda one multiplier per link (accumulated;
// nullptr: links without a multiplier, taken as zero, e.g. the unilateral coarse links). Links
// with no free particle are skipped. Allocates nothing.
StretchPassResult projectStretchLinks(const StretchLinks& links, int first_batch, int end_batch,
                                      const StretchProjection& how, PositionColumns position,
                                      double* lambda);

// Whether projectStretchLinks can take the AVX2 path on this processor (with how.simd), and the
// AVX-512 one (AVX-512F; with how.simd and how.avx512).
bool stretchLinksUseAvx2();
bool stretchLinksUseAvx512();

}  // namespace pbd_cloth
