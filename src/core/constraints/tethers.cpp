#include "pbd_cloth/constraints/tethers.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>

namespace pbd_cloth {

namespace {
constexpr double kInfinity = std::numeric_limits<double>::infinity();
}  // namespace

void TetherBuilder::reserve(const Particles& particles, const ClothTopology& topology, int groups,
                            std::vector<Tether>& tethers) {
  const int n = particles.cloth_count;
  for (std::vector<int>* v : {&anchors_, &parent_, &group_, &group_of_root_, &nearest_}) {
    v->reserve(n);
  }
  nearest_distance_.reserve(n);
  groups = std::max(groups, 1);
  if (topology.from_mesh) {
    linkEdges(topology, n);
    distance_.reserve(static_cast<std::size_t>(groups) * n);
    source_.reserve(static_cast<std::size_t>(groups) * n);
    heap_.reserve(n + 2 * topology.stretch.size());
  }
  tethers.reserve(static_cast<std::size_t>(groups) * n);
}

int TetherBuilder::countGroups(const Particles& particles, const ClothTopology& topology,
                               const std::vector<int>& holder) {
  findGroups(particles, topology, holder);
  return groups_;
}

void TetherBuilder::build(const Particles& particles, const ClothTopology& topology, double spacing,
                          std::vector<Tether>& tethers, const std::vector<int>& holder) {
  tethers.clear();
  findGroups(particles, topology, holder);
  if (anchors_.empty()) return;
  if (topology.from_mesh) {
    buildMesh(particles, topology, tethers);
  } else {
    buildGrid(particles, topology, spacing, tethers);
  }
}

// Union-find over the stretch links whose two ends are both kinematic and held by the same body;
// groups numbered in the order of their first anchor.
void TetherBuilder::findGroups(const Particles& particles, const ClothTopology& topology,
                               const std::vector<int>& holder) {
  const int n = particles.cloth_count;
  parent_.resize(n);
  for (int i = 0; i < n; ++i) parent_[i] = i;
  auto root = [this](int i) {
    while (parent_[i] != i) i = parent_[i] = parent_[parent_[i]];  // path halving
    return i;
  };
  for (const DistanceConstraint& c : topology.stretch) {
    if (!particles.isKinematic(c.i) || !particles.isKinematic(c.j)) continue;
    if (!holder.empty() && holder[c.i] != holder[c.j]) continue;
    parent_[root(c.i)] = root(c.j);
  }
  anchors_.clear();
  group_.assign(n, -1);
  group_of_root_.assign(n, -1);
  groups_ = 0;
  for (int i = 0; i < n; ++i) {
    if (!particles.isKinematic(i)) continue;
    anchors_.push_back(i);
    int& g = group_of_root_[root(i)];
    if (g < 0) g = groups_++;
    group_[i] = g;
  }
}

// The grid is built flat, so the rest distance between two particles is the straight one on the
// flat grid (its geodesic): spacing * sqrt(dr^2 + dc^2).
void TetherBuilder::buildGrid(const Particles& particles, const ClothTopology& topology,
                              double spacing, std::vector<Tether>& tethers) {
  const int n = particles.cloth_count, cols = topology.cols;
  nearest_.assign(groups_, -1);
  nearest_distance_.assign(groups_, kInfinity);
  for (int i = 0; i < n; ++i) {
    if (particles.isKinematic(i)) continue;
    for (int a : anchors_) {
      const double dr = (i / cols) - (a / cols), dc = (i % cols) - (a % cols);
      const double distance = spacing * std::sqrt(dr * dr + dc * dc);
      const int g = group_[a];
      if (distance < nearest_distance_[g]) {  // strictly: the first anchor of a tie
        nearest_distance_[g] = distance;
        nearest_[g] = a;
      }
    }
    for (int a : anchors_) {
      const int g = group_[a];
      if (nearest_[g] != a) continue;
      tethers.push_back({i, a, nearest_distance_[g]});
      nearest_[g] = -1;
      nearest_distance_[g] = kInfinity;
    }
  }
}

void TetherBuilder::linkEdges(const ClothTopology& topology, int n) {
  edge_offsets_.assign(n + 1, 0);
  for (const DistanceConstraint& c : topology.stretch) {
    ++edge_offsets_[c.i + 1];
    ++edge_offsets_[c.j + 1];
  }
  for (int i = 0; i < n; ++i) edge_offsets_[i + 1] += edge_offsets_[i];
  edge_fill_.assign(edge_offsets_.begin(), edge_offsets_.end() - 1);
  edge_targets_.resize(edge_offsets_[n]);
  edge_lengths_.resize(edge_offsets_[n]);
  for (const DistanceConstraint& c : topology.stretch) {
    edge_targets_[edge_fill_[c.i]] = c.j;
    edge_lengths_[edge_fill_[c.i]++] = c.rest_length;
    edge_targets_[edge_fill_[c.j]] = c.i;
    edge_lengths_[edge_fill_[c.j]++] = c.rest_length;
  }
}

void TetherBuilder::groupDistances(int group, int n) {
  double* distance = distance_.data() + static_cast<std::size_t>(group) * n;
  int* source = source_.data() + static_cast<std::size_t>(group) * n;
  const auto later = std::greater<std::pair<double, int>>();  // a min-heap on the distance
  heap_.clear();
  for (int a : anchors_) {
    if (group_[a] != group) continue;
    distance[a] = 0.0;
    source[a] = a;
    heap_.emplace_back(0.0, a);
  }
  std::make_heap(heap_.begin(), heap_.end(), later);
  while (!heap_.empty()) {
    std::pop_heap(heap_.begin(), heap_.end(), later);
    const auto [d, v] = heap_.back();
    heap_.pop_back();
    if (d > distance[v]) continue;  // an outdated entry (lazy deletion)
    for (int k = edge_offsets_[v]; k < edge_offsets_[v + 1]; ++k) {
      const int w = edge_targets_[k];
      const double next = d + edge_lengths_[k];
      if (next < distance[w]) {
        distance[w] = next;
        source[w] = source[v];
        heap_.emplace_back(next, w);
        std::push_heap(heap_.begin(), heap_.end(), later);
      }
    }
  }
}

// The rest distance is the shortest path along the mesh edges, an upper bound of the geodesic on
// the surface (a zig-zag of edges is longer than the straight path across the triangles). Straight
// distance would be wrong for a curved or folded garment: the two layers of a T-shirt are 2 cm
// apart in space but half a shirt apart along the cloth.
void TetherBuilder::buildMesh(const Particles& particles, const ClothTopology& topology,
                              std::vector<Tether>& tethers) {
  const int n = particles.cloth_count;
  if (static_cast<int>(edge_offsets_.size()) != n + 1) linkEdges(topology, n);
  const std::size_t cells = static_cast<std::size_t>(groups_) * n;
  distance_.assign(cells, kInfinity);
  source_.assign(cells, -1);
  for (int g = 0; g < groups_; ++g) groupDistances(g, n);
  for (int i = 0; i < n; ++i) {
    if (particles.isKinematic(i)) continue;
    for (int a : anchors_) {
      const std::size_t cell = static_cast<std::size_t>(group_[a]) * n + i;
      if (source_[cell] == a) tethers.push_back({i, a, distance_[cell]});
    }
  }
}

}  // namespace pbd_cloth
