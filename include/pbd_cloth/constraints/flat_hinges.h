// The projection of the flat bending hinges (every hinge of a grid cloth), on flat arrays: the
// vector constraint C = scale b, b = sum_k K_k x_k (the isometric bending of Bergou et al. 2006 as
// a linear constraint; bend_projection.cpp, projectBend, says why), with XPBD's multiplier step
// (Macklin et al. 2016, eq. 18) dlambda = (-k C - alpha~ lambda) / (w + alpha~), w = scale^2 sum_k
// w_k K_k^2, and each corner moved by w_k K_k scale dlambda.
//
// Why a file of its own: the hinge's three coordinates go through one 256-bit register (x y z and
// an unused lane), a third of the scalar loop's arithmetic. As for the stretch links
// (stretch_links.h), the path is chosen at run time: AVX-512VL (masked loads and stores of x y z)
// where the processor has it, else AVX2, else the portable loop; the file is compiled without
// floating-point contraction, so all three give the same result to the bit (test_core:
// FlatHinges.*).
#pragma once

#include "pbd_cloth/model/particles.h"

namespace pbd_cloth {

// What a step fixes for one hinge (Solver::prepareBendStep), so that a projection is a few
// multiply-adds: with w = scale^2 sum_k w_k K_k^2 and D = w + alpha~ (PBD: D = w, alpha~ = 0),
//   dlambda = sum_{k=1..3} gain_k (x_k - x_0) - decay lambda,  gain_k = -k scale K_k / D,
//                                                              decay = alpha~ / D,
// which is XPBD's (-k C - alpha~ lambda) / D for C = scale b, and each corner moves by
// move_k dlambda, move_k = w_k K_k scale. largest_move = max_k |move_k|; 0: no free corner
// (skipped). The corners are four different particles (makeBendConstraint refuses a hinge whose
// two triangles are one), so a hinge's corners can be read once and written once.
struct FlatHinge {
  int index[4] = {0, 0, 0, 0};
  double gain[3] = {0.0, 0.0, 0.0};
  double decay = 0.0;
  double move[4] = {0.0, 0.0, 0.0, 0.0};
  double largest_move = 0.0;
  // A corner kinematic and another free: the hinge's multiplier gives the kinematic corner's
  // reaction (Solver::addMultiplierReactions), so it is written in every pass, the last too.
  bool reaction = false;
};

// What a step fixes for the flat hinge `con` (the formulas above): inverse_mass the particles'
// inverse masses, alpha = alpha~ (XPBD's compliance / h^2; 0 for PBD), k the stiffness factor (1
// for XPBD). A hinge whose w is below min_weight has no free corner: it comes back skipped
// (largest_move 0). Solver::prepareBendStep makes every hinge's with it; so does the
// microbenchmark that times the pass.
FlatHinge makeFlatHinge(const BendConstraint& con, const double* inverse_mass, double alpha,
                        double k, double min_weight);

// One Gauss-Seidel sweep over hinges [0, count) in order: x the positions (x0 y0 z0 x1 ...),
// lambda three multipliers per hinge (accumulated; lambda_from_zero: the substep's first pass,
// whose multipliers start at zero: they are written, not read, so nobody need zero them first).
// keep_multipliers false: no later pass of the substep reads them (its last pass), so only the
// hinges with `reaction` write theirs: two stores a hinge fewer, in a pass its accesses bound
// (fabric_table's step 3.7 % cheaper with one pass a substep).
// Returns the largest corner move (m) when track_change (only solver.tolerance's adaptive count
// reads it), else 0 without computing it. simd false: the portable loop even where AVX2 is
// there; avx512 false: AVX2 even where AVX-512VL is there (solver.avx512). Allocates nothing.
double projectFlatHinges(const FlatHinge* hinge, int count, bool lambda_from_zero,
                         bool keep_multipliers, bool track_change, bool simd, bool avx512,
                         double* x, double* lambda);

// True where the processor has AVX-512F and AVX-512VL: projectFlatHinges then takes the masked
// path when simd and avx512 are set (AVX2, stretchLinksUseAvx2, otherwise).
bool flatHingesUseAvx512Vl();

}  // namespace pbd_cloth
