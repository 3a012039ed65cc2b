#include "pbd_cloth/constraints/taut_chains.h"

#include <algorithm>
#include <limits>

namespace pbd_cloth {

void TautChains::build(const Particles& p, const ClothTopology& topology) {
  lines_.clear();
  rest_along_.clear();
  held_.clear();
  const int rows = topology.rows, cols = topology.cols;
  if (rows <= 0 || cols <= 0 || rows * cols > p.cloth_count) return;
  // Each particle's stretch link to its right-hand and to its lower neighbour (NaN: none, so a
  // chain across the gap is never taut: every comparison with NaN is false).
  const double none = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> right(static_cast<std::size_t>(rows) * cols, none);
  std::vector<double> down(right.size(), none);
  for (const DistanceConstraint& link : topology.stretch) {
    const int i = std::min(link.i, link.j), j = std::max(link.i, link.j);
    if (j >= rows * cols) continue;
    if (j == i + 1 && i % cols != cols - 1) right[i] = link.rest_length;
    if (j == i + cols) down[i] = link.rest_length;
  }
  auto addLine = [&](int first, int stride, int count, const std::vector<double>& next) {
    if (count < 3) return;  // no particle between two ends
    lines_.push_back({first, stride, count, static_cast<int>(rest_along_.size())});
    double along = 0.0;
    for (int k = 0; k < count; ++k) {
      rest_along_.push_back(along);
      if (k + 1 < count) along += next[first + k * stride];
    }
  };
  for (int r = 0; r < rows; ++r) addLine(r * cols, 1, cols, right);
  for (int c = 0; c < cols; ++c) addLine(c, cols, rows, down);
  held_.reserve(static_cast<std::size_t>(rows) * cols);
}

int TautChains::hold(Particles& p) {
  held_.clear();
  for (const Line& line : lines_) {
    int last = -1;  // the line's last kinematic particle so far
    for (int k = 0; k < line.count; ++k) {
      if (!p.isKinematic(line.first + k * line.stride)) continue;
      if (last >= 0 && k - last > 1) holdBetween(p, line, last, k);
      last = k;
    }
  }
  return static_cast<int>(held_.size());
}

void TautChains::holdBetween(Particles& p, const Line& line, int a, int b) {
  const double* along = rest_along_.data() + line.rest;
  const double length = along[b] - along[a];
  const int qa = line.first + a * line.stride, qb = line.first + b * line.stride;
  const Vec3 from = p.kinematic_from[qb] - p.kinematic_from[qa];
  const Vec3 to = p.kinematic_to[qb] - p.kinematic_to[qa];
  const double taut = (1.0 - kTautTolerance) * length;
  if (!(from.norm() >= taut && to.norm() >= taut)) return;  // slack, or a link missing (NaN)
  for (int k = a + 1; k < b; ++k) {
    const int q = line.first + k * line.stride;
    const double s = (along[k] - along[a]) / length;
    p.kinematic_from[q] = p.kinematic_from[qa] + s * from;
    p.kinematic_to[q] = p.kinematic_to[qa] + s * to;
    p.position[q] = p.kinematic_from[q];
    p.inverse_mass[q] = 0.0;
    held_.push_back({q, qa, qb, s});
  }
}

void TautChains::release(Particles& p) {
  // held_ stays until the next hold(): the step's reactions on the held particles belong to the
  // ends that hold the chain (Simulation::gripperForce).
  for (const Held& h : held_) p.inverse_mass[h.particle] = 1.0 / p.mass[h.particle];
}

}  // namespace pbd_cloth
