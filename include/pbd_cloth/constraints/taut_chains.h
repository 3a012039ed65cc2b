// Taut chains (solver.taut_chains): a row or column of a grid cloth whose links are inextensible
// and whose two kinematic ends (pins or grasped particles) are as far apart as the links' rest
// lengths add up to. By the triangle inequality, |x_b - x_a| <= sum of the links' lengths, with
// equality only when every link lies on the segment from a to b at its rest length: such a chain
// has exactly one shape that satisfies its links, the straight one. Its particles are held there,
// as kinematic particles for the step, instead of being left to a Gauss-Seidel sweep that can
// only approach that shape (the stretch along an exactly taut row falls with the square of its
// sag, so each pass removes little of it: doc/journal.md, "2026-12-06: Taut chains held straight").
// Ends pulled farther apart than the rest lengths allow hold the chain straight and evenly
// stretched, the least-squares answer of links that cannot all be met.
#pragma once

#include <vector>

#include "pbd_cloth/model/particles.h"

namespace pbd_cloth {

class TautChains {
 public:
  // Relative slack under which a chain counts as taut: the ends' distance is at least
  // (1 - kTautTolerance) times the rest lengths' sum at the start and at the end of the step.
  static constexpr double kTautTolerance = 1e-9;

  struct Held {
    int particle = 0;
    int end_a = 0;  // the chain's kinematic ends
    int end_b = 0;
    double along = 0.0;  // its rest distance from end_a over the chain's: 0 at a, 1 at b
  };

  // The grid's rows and columns whose consecutive particles are all linked by stretch links (a
  // mesh cloth has none); sizes every buffer, so hold() and release() never allocate.
  void build(const Particles& p, const ClothTopology& topology);
  // Makes the interior particles of every taut chain kinematic for the coming step, moving from
  // their place on the segment between the ends' kinematic_from positions to the same place
  // between their kinematic_to positions (a particle off that segment is put on it first: the
  // one shape the links allow). Call after the step's kinematic targets are set. Returns how many
  // particles it holds.
  int hold(Particles& p);
  // Frees the held particles again (their mass restored); call after the step.
  void release(Particles& p);
  // A step that holds nothing (the option off, or links that can stretch): no held list.
  void forget() { held_.clear(); }
  const std::vector<Held>& held() const { return held_; }

 private:
  struct Line {
    int first = 0;   // particle index of the line's first particle
    int stride = 1;  // index step along the line: 1 along a row, cols down a column
    int count = 0;   // particles on the line
    int rest = 0;    // offset of its cumulative rest lengths in rest_along_
  };
  std::vector<Line> lines_;
  std::vector<double> rest_along_;  // per line and particle: rest length from the line's start
  std::vector<Held> held_;
  void holdBetween(Particles& p, const Line& line, int a, int b);
};

}  // namespace pbd_cloth
