// The projection of the flat bending hinges (every hinge of a grid cloth), on flat arrays: the
// vector constraint C = scale b, b = sum_k K_k x_k (the isometric bending of Bergou et al. 2006 as
// a linear constraint; solver.cpp, projectBend, says why), with XPBD's multiplier step (Macklin et
// al. 2016, eq. 18) dlambda = (-k C - alpha~ lambda) / (w + alpha~), w = scale^2 sum_k w_k K_k^2,
// and each corner moved by w_k K_k scale dlambda.
//
// Why a file of its own: the hinge's three coordinates go through one AVX2 register (x y z and an
// unused lane), a third of the scalar loop's arithmetic. As for the stretch links
// (stretch_links.h), the AVX2 path is chosen at run time where the processor has it, any other
// runs the portable loop, and the file is compiled without floating-point contraction, so both
// give the same result to the bit (test_core: FlatHinges.*).
#pragma once

#include "pbd_cloth/particles.h"

namespace pbd_cloth {

// What a step fixes for each hinge c (Solver::prepareBendStep): inverse_denominator[c] = 1 / (w +
// alpha~) (0: no free corner, skipped), factor[4c + k] = w_k K_k, largest_factor[c] = max_k
// |factor[4c + k]|.
struct FlatHingeStep {
  const double* inverse_denominator = nullptr;
  const double* factor = nullptr;
  const double* largest_factor = nullptr;
};

// One Gauss-Seidel sweep over hinges [0, count) in order: x the positions (x0 y0 z0 x1 ...),
// lambda three multipliers per hinge (accumulated). k: PBD's pass stiffness (1 for XPBD), alpha:
// alpha~ as given to the step's denominators. Returns the largest corner move (m). simd false:
// the portable loop even where AVX2 is there. Allocates nothing.
double projectFlatHinges(const BendConstraint* bend, int count, const FlatHingeStep& step, double k,
                         double alpha, bool simd, double* x, double* lambda);

}  // namespace pbd_cloth
