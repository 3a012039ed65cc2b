// Coarse levels of a grid cloth for the stretch solve (solver.levels): long-range links in a
// hierarchy, after hierarchical position-based dynamics (Mueller 2008). Level k keeps every other
// row and column of level k - 1 (level 0 is the cloth), always with the first and the last, and
// links each kept particle to its neighbours on that level along rows, columns and both diagonals
// of every coarse cell, at the rest distance of the flat grid: particles 2^k cloth links apart.
// The links are unilateral (projected only while longer than their rest distance: the cloth
// between two linked particles may fold, never stretch), so they hold only for inextensible cloth
// and never fight the cloth's own constraints: every state that satisfies those satisfies them.
//
// A pass projects the levels coarsest first, then the cloth's own links. Gauss-Seidel on the
// cloth alone carries a correction one link per pass, so a stretch spread over the whole cloth (a
// sagging taut edge, a wave down a column) needs many passes; a link of level k removes the
// stretch of 2^k cloth links in one projection.
//
// Each link moves its two ends only: HPBD's interpolation of a level's displacement to the finer
// particles gained energy on config/swinging.yaml above 20 substeps and left the product
// (doc/journal.md, "HPBD's interpolation").
#pragma once

#include <vector>

#include "pbd_cloth/constraints/stretch_links.h"
#include "pbd_cloth/model/particles.h"

namespace pbd_cloth {

class CoarseLevels {
 public:
  // Builds `levels` coarse levels of a rows x cols grid of the given spacing (fewer when the grid
  // runs out of rows or columns: a level needs two of each). levels = 0 clears them.
  void build(int rows, int cols, double spacing, int levels);
  int levelCount() const { return static_cast<int>(levels_.size()); }
  int rows() const { return rows_; }
  int cols() const { return cols_; }
  int requested() const { return requested_; }
  double spacing() const { return spacing_; }

  // Before a step's sweeps: the links' inverse masses (the kinematic set is fixed for a step).
  void prepareStep(const Particles& p);
  // One sweep over the coarse levels, coarsest first, on the cloth particles (kinematic particles
  // do not move). Returns the largest correction of a coarse link (0 without track_change: only
  // solver.tolerance reads it). simd, avx512: solver.simd, solver.avx512.
  double project(Particles& p, bool simd = true, bool track_change = true, bool avx512 = true);
  // The same sweep on the cloth's positions in columns (a step of links
  // alone, Solver::linksAlone): the same operations, so the same result to the bit.
  double project(PositionColumns cloth, bool simd, bool track_change, bool avx512);

 private:
  struct Level {
    std::vector<int> particles;  // cloth indices, row by row
    // The level's links, row by row as build() adds them, flat and batched, between positions in
    // `particles`, projected on a packed copy of those particles' positions and inverse masses.
    StretchLinks flat;
    ColumnPositions compact_position;  // the positions of `particles`, in columns
    std::vector<double> compact_inverse_mass;
  };
  // One level's links on its packed positions (level.compact_position, filled by the caller).
  static double projectPacked(Level& level, bool simd, bool track_change, bool avx512);
  std::vector<Level> levels_;  // levels_[0] = level 1 (the finest coarse level)
  int rows_ = 0, cols_ = 0, requested_ = 0;
  double spacing_ = 0.0;
};

}  // namespace pbd_cloth
