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
// With `interpolate` (solver.levels_interpolate, HPBD proper), the particles of the finer level
// that a level does not hold follow the displacement of their coarse cell (bilinear), and the
// coarse links weigh their ends by the cloth they carry. On config/swinging.yaml this gains energy
// above 20 substeps (doc/performance.md, "HPBD's interpolation"); without it the links move their
// two ends only.
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
  double project(Particles& p, bool interpolate, bool simd = true, bool track_change = true,
                 bool avx512 = true);
  // The same sweep without interpolation, on the cloth's positions in columns (a step of links
  // alone, Solver::linksAlone): the same operations, so the same result to the bit.
  double project(PositionColumns cloth, bool simd, bool track_change, bool avx512);

 private:
  struct Link {
    int i = 0;  // particle indices in the cloth
    int j = 0;
    int local_i = 0;  // positions in the level's list of particles
    int local_j = 0;
    double rest_length = 0.0;
  };
  // A particle of the finer level that this level does not hold: its coarse cell's four corners
  // (positions in this level's list of particles) and bilinear weights.
  struct Interpolated {
    int particle = 0;  // in the cloth
    int corner[4] = {0, 0, 0, 0};
    double weight[4] = {0.0, 0.0, 0.0, 0.0};
  };
  struct Level {
    std::vector<int> particles;  // cloth indices, row by row
    // The cloth particles each one carries, counted with their interpolation weights (HPBD's
    // coarse mass): its own, plus its share of every finer particle that follows it. A coarse
    // link weighs its ends by inverse_mass / carried, so the cloth it moves keeps its momentum.
    std::vector<double> carried;
    std::vector<Link> links;  // row by row
    // The same links, flat and batched (no interpolation), between positions in `particles`,
    // projected on a packed copy of those particles' positions and inverse masses.
    StretchLinks flat;
    ColumnPositions compact_position;  // the positions of `particles`, in columns
    std::vector<double> compact_inverse_mass;
    std::vector<Interpolated> finer_only;  // the finer level's particles not on this level
  };
  // One level's links on its packed positions (level.compact_position, filled by the caller).
  static double projectPacked(Level& level, bool simd, bool track_change, bool avx512);
  std::vector<Level> levels_;  // levels_[0] = level 1 (the finest coarse level)
  Vec3Array start_;            // cloth positions at the start of the cycle
  Vec3Array displacement_;     // of a level's particles since the start of the cycle
  int rows_ = 0, cols_ = 0, requested_ = 0;
  double spacing_ = 0.0;
};

}  // namespace pbd_cloth
