// Vertex-triangle self-collision of the collision seed (eq. vertex_triangle_constraint):
// C(q, p1, p2, p3) = s (q - p1) . n - h >= 0 with the triangle's unit normal n, the cloth thickness
// h, and the side s = +-1 the vertex was on at the start of the step, so a vertex pushed through a
// triangle within a step is pulled back to the side it came from instead of out of the far side.
#pragma once

#include <vector>

#include "pbd_cloth/contact.h"
#include "pbd_cloth/particles.h"
#include "pbd_cloth/spatial_hash.h"

namespace pbd_cloth {

struct VertexTrianglePair {
  int vertex = 0;
  int triangle[3] = {0, 0, 0};
  double side = 1.0;  // s: +1 in front of the triangle (its normal side), -1 behind
  double allowance = 0.0;  // approach closer than h tolerated this step (allowanceFor)
  ContactState state;
};

class SelfCollision {
 public:
  void reserve(const Particles& particles, const ClothTopology& topology);

  // Broad phase, once per step: each cloth vertex whose swept box [lo, hi] comes within the
  // thickness of a triangle's swept box, except the triangle's own vertices and their grid
  // neighbours (a neighbour is within h of the triangle whenever the cloth bends, yet cannot fold
  // onto it: the bending and stretch constraints own that pair). The side s comes from the
  // positions at the step start.
  void findPairs(const Particles& particles, const ClothTopology& topology, const Vec3Array& lo,
                 const Vec3Array& hi, double thickness);

  // Pre-stabilisation: pushes vertices closer than h to a triangle apart by at most max_shift, on
  // the positions before the step's first prediction (no velocity gained).
  void preStabilize(Particles& particles, double thickness, double max_shift) const;
  // After pre-stabilisation: how much closer than h each vertex over its triangle may stay this
  // step (allowanceFor, `slop` a fraction of h; never on the wrong side), measured in `positions`
  // (those of the step start).
  void measureAllowances(const Vec3Array& positions, double thickness, double slop);

  // One projection pass, then friction; returns the largest correction.
  double project(Particles& particles, double thickness, int substep,
                 const FrictionConfig& friction);

  // Deepest violation h - s (q - p1) . n over pairs whose vertex projects inside its triangle (m).
  double maxPenetration(const Particles& particles, double thickness) const;
  int pairCount() const { return static_cast<int>(pairs_.size()); }

 private:
  SpatialHash hash_;
  Vec3Array grown_lo_;  // vertex boxes grown by h / 2
  Vec3Array grown_hi_;
  std::vector<VertexTrianglePair> pairs_;
};

}  // namespace pbd_cloth
