#include "pbd_cloth/collision/self_collision.h"

#include "pbd_cloth/collision/buffer_capacity.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <iterator>
#include <utility>

namespace pbd_cloth {

namespace {

// A triangle whose sine of the smallest angle is below ~1e-8 has no usable normal: skipped.
constexpr double kDegenerate = 1e-16;
// Edges closer to parallel than ~3 degrees (squared sine) have no stable common normal: the
// vertex-triangle contacts of their end points keep such layers apart instead.
constexpr double kParallel = 0.0027;
// Edges keep their side only within this many thicknesses of each other (see project()), and a
// contact pushes at most kMaxPush thicknesses per pass.
constexpr double kEdgeBand = 3.0;
constexpr double kMaxPush = 0.5;
// The projected point may lie this far (in barycentric units) outside the triangle and still count
// as inside, so a vertex over a shared edge is never missed by both triangles through rounding.
constexpr double kInsideTolerance = 1e-6;

// A contact in the current positions: the unit normal n (before the side is applied), the signed
// distance n . sum_k c_k x_k, the coefficients c_k of the four points, and whether the contact is
// active (vertex over the triangle, edges' closest points interior to both).
struct ContactGeometry {
  Vec3 normal = Vec3::UnitZ();
  double distance = 0.0;
  double coefficient[4] = {0.0, 0.0, 0.0, 0.0};
  bool inside = false;
};

// The vertex q over the plane of the triangle (p1, p2, p3): n = p21 x p31 / |p21 x p31| (seed),
// distance (q - p1) . n, coefficients 1 and minus the barycentric weights of q's projection.
bool vertexTriangle(const Vec3& q, const Vec3& p1, const Vec3& p2, const Vec3& p3,
                    ContactGeometry& g) {
  const Vec3 e1 = p2 - p1, e2 = p3 - p1, v = q - p1;
  const Vec3 cross = e1.cross(e2);
  const double d00 = e1.squaredNorm(), d11 = e2.squaredNorm(), d01 = e1.dot(e2);
  const double area2 = cross.squaredNorm();
  if (!(area2 > kDegenerate * d00 * d11)) return false;  // zero-area (or non-finite) triangle
  g.normal = cross / std::sqrt(area2);
  g.distance = v.dot(g.normal);
  const double d20 = v.dot(e1), d21 = v.dot(e2);
  const double denominator = d00 * d11 - d01 * d01;
  const double b2 = (d11 * d20 - d01 * d21) / denominator;
  const double b3 = (d00 * d21 - d01 * d20) / denominator;
  const double b1 = 1.0 - b2 - b3;
  g.coefficient[0] = 1.0;
  g.coefficient[1] = -b1;
  g.coefficient[2] = -b2;
  g.coefficient[3] = -b3;
  g.inside = b1 >= -kInsideTolerance && b2 >= -kInsideTolerance && b3 >= -kInsideTolerance;
  return true;
}

// Edges p1p2 and q1q2: n = p21 x q21 normalised, distance (p1 - q1) . n, and the closest points
// p1 + a p21, q1 + b q21 of the two lines (Ericson 2005, sec. 5.1.9), active when a and b are
// interior (an end point is the vertex-triangle contacts' business).
bool edgeEdge(const Vec3& p1, const Vec3& p2, const Vec3& q1, const Vec3& q2, ContactGeometry& g) {
  const Vec3 d1 = p2 - p1, d2 = q2 - q1, r = p1 - q1;
  const Vec3 cross = d1.cross(d2);
  const double aa = d1.squaredNorm(), ee = d2.squaredNorm();
  const double sine2 = cross.squaredNorm();
  if (!(sine2 > kParallel * aa * ee)) return false;
  g.normal = cross / std::sqrt(sine2);
  g.distance = r.dot(g.normal);
  const double bb = d1.dot(d2), cc = d1.dot(r), ff = d2.dot(r);
  const double denominator = aa * ee - bb * bb;
  const double a = (bb * ff - cc * ee) / denominator;
  const double b = (aa * ff - bb * cc) / denominator;
  g.coefficient[0] = 1.0 - a;
  g.coefficient[1] = a;
  g.coefficient[2] = -(1.0 - b);
  g.coefficient[3] = -b;
  g.inside = a > kInsideTolerance && a < 1.0 - kInsideTolerance && b > kInsideTolerance &&
             b < 1.0 - kInsideTolerance;
  return true;
}

bool geometry(const SelfContactPair& pair, const Vec3Array& x, ContactGeometry& g) {
  const int* k = pair.index;
  return pair.edge_edge ? edgeEdge(x[k[0]], x[k[1]], x[k[2]], x[k[3]], g)
                        : vertexTriangle(x[k[0]], x[k[1]], x[k[2]], x[k[3]], g);
}

// Generalised inverse mass sum_k c_k^2 w_k of the four-point contact.
double inverseMass(const SelfContactPair& pair, const ContactGeometry& g, const Particles& p) {
  double w = 0.0;
  for (int k = 0; k < 4; ++k) {
    w += g.coefficient[k] * g.coefficient[k] * p.inverse_mass[pair.index[k]];
  }
  return w;
}

// Moves the four points so that sum_k c_k x_k changes by `change` (a vector): x_k += w_k c_k
// change / w. With `reaction`, a kinematic point, which stays, gets c_k change / w there (its
// gradient times the multiplier).
// The lever of kinematic corners: a particle of the pair moves by w_i |c_i| / w times the
// correction (w = sum_k w_k c_k^2, c the pair's coefficients). With a free vertex that factor is
// at most 1; but a pinned or held vertex against a triangle whose nearest corner is pinned or held
// too leaves only the free corners, with barycentric coefficients near 0, to move: each by about
// 1 / c_k times the correction. A cloth crushed with its two pinned corners together threw a
// neighbour of a pin at 800 to 14,000 m/s that way (fault recovery then undid every step from
// there on: SelfCollision.CrushedClothStopsEachSearchAtItsBudget). No particle moves by more than
// kMaxLeverage times the correction: the rest of such a contact waits for the next passes, as a
// deep contact does (kMaxPush). 4 leaves every pair of the tests and shipped scenes as it was.
constexpr double kMaxLeverage = 4.0;

void distribute(const SelfContactPair& pair, const ContactGeometry& g, double w, const Vec3& change,
                Particles& p, Vec3Array* reaction = nullptr) {
  double leverage = 0.0;
  for (int k = 0; k < 4; ++k) {
    leverage = std::max(leverage, p.inverse_mass[pair.index[k]] * std::abs(g.coefficient[k]) / w);
  }
  const double scale = leverage > kMaxLeverage ? kMaxLeverage / leverage : 1.0;
  for (int k = 0; k < 4; ++k) {
    const int i = pair.index[k];
    p.position[i] += (scale * p.inverse_mass[i] * g.coefficient[k] / w) * change;
    if (reaction != nullptr && p.inverse_mass[i] == 0.0) {
      (*reaction)[i] += (scale * g.coefficient[k] / w) * change;
    }
  }
}

// Edge-edge pairs far apart, the common case of a step-start list (self_collision.h): their
// boxes, and the sign of (p1 - q1) . (p21 x q21) without the closest points. apart() says the two
// segments' boxes are more than `gap` apart along some axis, so their distance is more than gap.
bool edgesApart(const SelfContactPair& pair, const Vec3Array& x, double gap) {
  const Vec3& p1 = x[pair.index[0]];
  const Vec3& p2 = x[pair.index[1]];
  const Vec3& q1 = x[pair.index[2]];
  const Vec3& q2 = x[pair.index[3]];
  const Vec3 p_lo = p1.cwiseMin(p2), p_hi = p1.cwiseMax(p2);
  const Vec3 q_lo = q1.cwiseMin(q2), q_hi = q1.cwiseMax(q2);
  return ((q_lo - p_hi).array() > gap).any() || ((p_lo - q_hi).array() > gap).any();
}

// A vertex more than `gap` from its triangle's box along some axis.
bool vertexApart(const SelfContactPair& pair, const Vec3Array& x, double gap) {
  const Vec3& v = x[pair.index[0]];
  const Vec3& a = x[pair.index[1]];
  const Vec3& b = x[pair.index[2]];
  const Vec3& c = x[pair.index[3]];
  const Vec3 lo = a.cwiseMin(b).cwiseMin(c), hi = a.cwiseMax(b).cwiseMax(c);
  return ((lo - v).array() > gap).any() || ((v - hi).array() > gap).any();
}

// The sign of r . n, n = cross / |cross| (|cross|^2 = cross_sq), as the geometry computes it:
// r . cross has that sign unless it is within rounding of zero (each form is within a few ulp of
// sum |r_i cross_i|), and only there the normalised form decides. 0 when it is 0.
double signAlong(const Vec3& r, const Vec3& cross, double cross_sq) {
  double distance = r.dot(cross);
  const double terms = r.cwiseProduct(cross).cwiseAbs().sum();
  if (!(std::abs(distance) > 1e-12 * terms)) distance = r.dot(cross / std::sqrt(cross_sq));
  return distance > 0.0 ? 1.0 : (distance < 0.0 ? -1.0 : 0.0);
}

// The sign of the distance edgeEdge gives, (p1 - q1) . n with n = p21 x q21 / |p21 x q21|
// (the same sign to the bit), in `side`, without the closest points; false where edgeEdge fails
// (edges too near parallel).
bool edgeSide(const SelfContactPair& pair, const Vec3Array& x, double& side) {
  const Vec3& p1 = x[pair.index[0]];
  const Vec3& q1 = x[pair.index[2]];
  const Vec3 d1 = x[pair.index[1]] - p1, d2 = x[pair.index[3]] - q1;
  const Vec3 cross = d1.cross(d2);
  const double sine2 = cross.squaredNorm();
  if (!(sine2 > kParallel * d1.squaredNorm() * d2.squaredNorm())) return false;
  side = signAlong(p1 - q1, cross, sine2);
  return true;
}

// The sign of the distance vertexTriangle gives, (q - p1) . n with n = p21 x p31 / |p21 x p31|,
// in `side`, without the barycentric weights; false where vertexTriangle fails (a degenerate
// triangle).
bool vertexSide(const SelfContactPair& pair, const Vec3Array& x, double& side) {
  const Vec3& p1 = x[pair.index[1]];
  const Vec3 e1 = x[pair.index[2]] - p1, e2 = x[pair.index[3]] - p1;
  const Vec3 cross = e1.cross(e2);
  const double area2 = cross.squaredNorm();
  if (!(area2 > kDegenerate * e1.squaredNorm() * e2.squaredNorm())) return false;
  side = signAlong(x[pair.index[0]] - p1, cross, area2);
  return true;
}

bool allKinematic(const Particles& p, int a, int b, int c, int d) {
  return p.inverse_mass[a] == 0.0 && p.inverse_mass[b] == 0.0 && p.inverse_mass[c] == 0.0 &&
         p.inverse_mass[d] == 0.0;
}

}  // namespace

void SelfCollision::reserve(const Particles& particles, const ClothTopology& topology) {
  const int triangles = topology.triangleCount();
  edges_.clear();
  for (int t = 0; t < triangles; ++t) {
    for (int e = 0; e < 3; ++e) {
      const int a = static_cast<int>(topology.triangles[3 * t + e]);
      const int b = static_cast<int>(topology.triangles[3 * t + (e + 1) % 3]);
      edges_.push_back({std::min(a, b), std::max(a, b)});
    }
  }
  std::sort(edges_.begin(), edges_.end());
  edges_.erase(std::unique(edges_.begin(), edges_.end()), edges_.end());
  const int edges = static_cast<int>(edges_.size());

  tree_.build(topology.triangles, particles.position);
  // Owners: each vertex and each edge to the first triangle (in the tree's leaf order) that has
  // it, so a leaf pair lists it once (findPairs).
  owned_vertices_.assign(triangles, {-1, -1, -1});
  owned_edges_.assign(triangles, {-1, -1, -1});
  std::vector<char> vertex_owned(particles.cloth_count, 0), edge_owned(edges, 0);
  for (int slot = 0; slot < triangles; ++slot) {
    const int t = tree_.triangle(slot);
    for (int e = 0; e < 3; ++e) {
      const int a = static_cast<int>(topology.triangles[3 * t + e]);
      const int b = static_cast<int>(topology.triangles[3 * t + (e + 1) % 3]);
      if (a < particles.cloth_count && !vertex_owned[a]) {
        vertex_owned[a] = 1;
        owned_vertices_[t][e] = a;
      }
      const std::array<int, 2> edge{std::min(a, b), std::max(a, b)};
      const int index =
          static_cast<int>(std::lower_bound(edges_.begin(), edges_.end(), edge) - edges_.begin());
      if (!edge_owned[index]) {
        edge_owned[index] = 1;
        owned_edges_[t][e] = index;
      }
    }
  }
  // findPairsNear's maps.
  vertex_triangle_offsets_.assign(particles.cloth_count + 1, 0);
  for (unsigned v : topology.triangles) {
    if (static_cast<int>(v) < particles.cloth_count) ++vertex_triangle_offsets_[v + 1];
  }
  for (int v = 0; v < particles.cloth_count; ++v) {
    vertex_triangle_offsets_[v + 1] += vertex_triangle_offsets_[v];
  }
  vertex_triangles_.assign(vertex_triangle_offsets_.back(), 0);
  {
    std::vector<int> next(vertex_triangle_offsets_.begin(), vertex_triangle_offsets_.end() - 1);
    for (int t = 0; t < triangles; ++t) {
      for (int e = 0; e < 3; ++e) {
        const int v = static_cast<int>(topology.triangles[3 * t + e]);
        if (v < particles.cloth_count) vertex_triangles_[next[v]++] = t;
      }
    }
  }
  owner_leaf_.assign(particles.cloth_count, -1);
  for (int t = 0; t < triangles; ++t) {
    for (int v : owned_vertices_[t]) {
      if (v >= 0) owner_leaf_[v] = tree_.leafOf(t);
    }
  }
  leaf_changed_.assign(tree_.nodeCount(), 0);
  particle_renewed_.assign(particles.cloth_count, 0);
  renewed_.clear();
  renewed_.reserve(particles.cloth_count);
  changed_leaves_.clear();
  changed_leaves_.reserve(tree_.nodeCount());
  grown_lo_.reserve(particles.cloth_count);
  grown_hi_.reserve(particles.cloth_count);
  triangle_lo_.reserve(triangles);
  triangle_hi_.reserve(triangles);
  edge_lo_.reserve(edges);
  edge_hi_.reserve(edges);
  // Typical scenes need 2-4 candidates per triangle and edge; a cloth falling fast into a fold
  // needs more: the list then grows in that step, and releaseExcessCapacity gives the excess
  // back between steps once it is over.
  reserved_pairs_ = 8 * static_cast<std::size_t>(triangles + edges);
  pair_budget_ = kPairsPerElement * static_cast<std::size_t>(triangles + edges);
  pairs_.reserve(reserved_pairs_);
  previous_.reserve(reserved_pairs_);
  vertex_found_.reserve(reserved_pairs_);
  edge_found_.reserve(reserved_pairs_);
  vertex_slot_.assign(particles.cloth_count + 1, 0);
}

std::size_t SelfCollision::releaseExcessCapacity() {
  // The search's vertex list is scratch, empty between searches: it keeps at most the reserve.
  return shrinkToReserve(vertex_found_, reserved_pairs_) +
         shrinkToReserve(edge_found_, reserved_pairs_) + shrinkToReserve(pairs_, reserved_pairs_) +
         shrinkToReserve(previous_, reserved_pairs_);
}

void SelfCollision::findPairs(const Particles& p, const ClothTopology& topology,
                              const MotionBounds& bounds, double thickness, bool edge_pairs,
                              bool keep_states) {
  const Vec3Array& lo = bounds.lo;
  const Vec3Array& hi = bounds.hi;
  // Edge-edge pairs first, vertex-triangle pairs after them: a search that renews only the latter
  // keeps the edge pairs. The pairs it replaces go aside to hand their states on.
  previous_edge_count_ = 0;
  previous_.clear();
  if (keep_states) {
    previous_.assign(pairs_.begin() + (edge_pairs ? 0 : edge_pair_count_), pairs_.end());
    if (edge_pairs) previous_edge_count_ = edge_pair_count_;
  }
  pairs_.resize(edge_pairs ? 0 : edge_pair_count_);
  if (edge_pairs) edge_pair_count_ = 0;
  vertex_found_.clear();
  edge_found_.clear();
  truncated_ = false;
  const int triangles = topology.triangleCount();
  if (triangles == 0) return;
  // Vertex boxes grown by h / 2: two boxes built from them overlap when within h of each other.
  const double half = 0.5 * thickness;
  const int vertices = p.cloth_count;
  grown_lo_.resize(vertices);
  grown_hi_.resize(vertices);
  for (int v = 0; v < vertices; ++v) {
    grown_lo_[v] = lo[v].array() - half;
    grown_hi_[v] = hi[v].array() + half;
  }
  const auto& tri = topology.triangles;
  triangle_lo_.resize(triangles);
  triangle_hi_.resize(triangles);
  for (int t = 0; t < triangles; ++t) boxTriangle(t, tri);
  if (edge_pairs) {
    const int edges = static_cast<int>(edges_.size());
    edge_lo_.resize(edges);
    edge_hi_.resize(edges);
    for (int e = 0; e < edges; ++e) {
      const int a = edges_[e][0], b = edges_[e][1];
      edge_lo_[e] = grown_lo_[a].cwiseMin(grown_lo_[b]);
      edge_hi_[e] = grown_hi_[a].cwiseMax(grown_hi_[b]);
    }
  }
  tree_.refit(tri, triangle_lo_, triangle_hi_, bounds.path_start, bounds.path_move);
  // The budget is checked between leaf pairs: a search keeps at most one leaf pair's candidates
  // beyond it.
  truncated_ = !tree_.forEachLeafPair(tree_.cosFlat(thickness), [&](int a, int b) {
    findLeafPairs(a, b, p, topology, bounds, thickness, edge_pairs);
    return vertex_found_.size() + edge_found_.size() < pair_budget_;
  });
  // Each kind by its first particle (counting sort; a particle's pairs in the order the traversal
  // found them): the order carryStates bisects.
  if (edge_pairs) {
    appendByFirstParticle(edge_found_, vertices);
    edge_pair_count_ = static_cast<int>(pairs_.size());
  }
  appendByFirstParticle(vertex_found_, vertices);
  if (keep_states) {
    const auto previous_vertex = previous_.begin() + previous_edge_count_;
    if (edge_pairs) {
      carryStates(pairs_.begin(), pairs_.begin() + edge_pair_count_, previous_.begin(),
                  previous_vertex);
    }
    carryStates(pairs_.begin() + edge_pair_count_, pairs_.end(), previous_vertex, previous_.end());
  }
}

void SelfCollision::markLeavesOf(int v) {
  for (int k = vertex_triangle_offsets_[v]; k < vertex_triangle_offsets_[v + 1]; ++k) {
    const int leaf = tree_.leafOf(vertex_triangles_[k]);
    if (!leaf_changed_[leaf]) {
      leaf_changed_[leaf] = 1;
      changed_leaves_.push_back(leaf);
    }
  }
}

void SelfCollision::boxTriangle(int t, const std::vector<unsigned>& tri) {
  const unsigned a = tri[3 * t], b = tri[3 * t + 1], c = tri[3 * t + 2];
  triangle_lo_[t] = grown_lo_[a].cwiseMin(grown_lo_[b]).cwiseMin(grown_lo_[c]);
  triangle_hi_[t] = grown_hi_[a].cwiseMax(grown_hi_[b]).cwiseMax(grown_hi_[c]);
}

const std::vector<int>& SelfCollision::renewedAround(const std::vector<int>& leavers,
                                                     const ClothTopology& topology, int particles) {
  // The leaves that hold a leaver are searched again anyway; so are their particles renewed,
  // which on paths of before the leaver's change of velocity would leave theirs a substep later
  // one by one, each with a search of its own: every corner of those leaves whose triangles all
  // lie in them (a corner with a triangle elsewhere would add that leaf to the search).
  changed_leaves_.clear();
  for (int v : leavers) {
    if (v >= particles) continue;
    markLeavesOf(v);
  }
  renewed_.clear();
  for (int v : leavers) {
    if (v < particles && !particle_renewed_[v]) {  // (a particle of no triangle too)
      particle_renewed_[v] = 1;
      renewed_.push_back(v);
    }
  }
  for (int leaf : changed_leaves_) {
    const TriangleTree::Node& n = tree_.node(leaf);
    for (int s = n.first; s < n.first + n.count; ++s) {
      for (int e = 0; e < 3; ++e) {
        const int v = static_cast<int>(topology.triangles[3 * tree_.triangle(s) + e]);
        if (v >= particles || particle_renewed_[v]) continue;
        bool inside = true;
        for (int k = vertex_triangle_offsets_[v]; inside && k < vertex_triangle_offsets_[v + 1];
             ++k) {
          inside = leaf_changed_[tree_.leafOf(vertex_triangles_[k])] != 0;
        }
        if (!inside) continue;
        particle_renewed_[v] = 1;
        renewed_.push_back(v);
      }
    }
  }
  for (int leaf : changed_leaves_) leaf_changed_[leaf] = 0;
  for (int v : renewed_) particle_renewed_[v] = 0;
  return renewed_;
}

void SelfCollision::findPairsNear(const Particles& p, const ClothTopology& topology,
                                  const MotionBounds& bounds, double thickness,
                                  const std::vector<int>& renewed) {
  truncated_ = false;
  const int triangles = topology.triangleCount();
  if (triangles == 0) return;
  const double half = 0.5 * thickness;
  changed_leaves_.clear();
  for (int v : renewed) {
    if (v >= p.cloth_count) continue;
    grown_lo_[v] = bounds.lo[v].array() - half;
    grown_hi_[v] = bounds.hi[v].array() + half;
    markLeavesOf(v);
  }
  std::sort(changed_leaves_.begin(), changed_leaves_.end());
  const auto& tri = topology.triangles;
  for (int leaf : changed_leaves_) {
    const TriangleTree::Node& n = tree_.node(leaf);
    for (int s = n.first; s < n.first + n.count; ++s) boxTriangle(tree_.triangle(s), tri);
  }
  tree_.mark(changed_leaves_);
  tree_.refitMarked(tri, triangle_lo_, triangle_hi_, bounds.path_start, bounds.path_move);
  // The vertex-triangle pairs of changed leaf pairs go aside (in order) to hand their states on.
  previous_.clear();
  previous_edge_count_ = 0;
  std::size_t kept = static_cast<std::size_t>(edge_pair_count_);
  for (std::size_t k = kept; k < pairs_.size(); ++k) {
    const SelfContactPair& pair = pairs_[k];
    if (leaf_changed_[owner_leaf_[pair.index[0]]] || leaf_changed_[tree_.leafOf(pair.triangle)]) {
      previous_.push_back(pair);
    } else {
      pairs_[kept++] = pair;
    }
  }
  pairs_.resize(kept);
  vertex_found_.clear();
  const std::size_t kept_vertex_pairs = kept - static_cast<std::size_t>(edge_pair_count_);
  truncated_ = !tree_.forEachMarkedLeafPair(tree_.cosFlat(thickness), [&](int a, int b) {
    findLeafPairs(a, b, p, topology, bounds, thickness, false);
    return kept_vertex_pairs + vertex_found_.size() < pair_budget_;
  });
  for (int leaf : changed_leaves_) leaf_changed_[leaf] = 0;
  // The new pairs in a total order (no two share all four indices), their states carried, then
  // merged with the kept ones by first particle.
  std::sort(vertex_found_.begin(), vertex_found_.end(),
            [](const SelfContactPair& a, const SelfContactPair& b) {
              return std::lexicographical_compare(a.index, a.index + 4, b.index, b.index + 4);
            });
  for (SelfContactPair& pair : vertex_found_) pair.local = true;
  carryStates(vertex_found_.begin(), vertex_found_.end(), previous_.begin(), previous_.end());
  edge_found_.assign(pairs_.begin() + edge_pair_count_, pairs_.end());  // scratch: the kept
  pairs_.resize(edge_pair_count_);
  std::merge(edge_found_.begin(), edge_found_.end(), vertex_found_.begin(), vertex_found_.end(),
             std::back_inserter(pairs_), [](const SelfContactPair& a, const SelfContactPair& b) {
               return a.index[0] < b.index[0];
             });
  edge_found_.clear();
  vertex_found_.clear();
}

void SelfCollision::appendByFirstParticle(std::vector<SelfContactPair>& found, int particles) {
  std::fill(vertex_slot_.begin(), vertex_slot_.end(), 0);
  for (const SelfContactPair& pair : found) ++vertex_slot_[pair.index[0] + 1];
  for (int v = 0; v < particles; ++v) vertex_slot_[v + 1] += vertex_slot_[v];
  const std::size_t start = pairs_.size();
  pairs_.resize(start + found.size());
  for (const SelfContactPair& pair : found) {
    pairs_[start + static_cast<std::size_t>(vertex_slot_[pair.index[0]]++)] = pair;
  }
  found.clear();
}

// A contact found again within the step keeps its side (frozen while the vertex is over the
// triangle, or the edges face each other within the band, where the step-start side a new pair
// gets may no longer be the one it is held to) and its contact state. Both ranges are of one kind
// and ordered by first particle: the old pairs of each new pair's particle are a short range
// found by bisection.
void SelfCollision::carryStates(PairIterator begin, PairIterator end, PairIterator old_begin,
                                PairIterator old_end) {
  const auto by_first = [](const SelfContactPair& pair, int v) { return pair.index[0] < v; };
  for (auto pair = begin; pair != end; ++pair) {
    auto old = std::lower_bound(old_begin, old_end, pair->index[0], by_first);
    for (; old != old_end && old->index[0] == pair->index[0]; ++old) {
      if (std::equal(old->index + 1, old->index + 4, pair->index + 1)) {
        pair->side = old->side;
        pair->state = old->state;
        break;
      }
    }
  }
}

void SelfCollision::findLeafPairs(int a, int b, const Particles& p, const ClothTopology& topology,
                                  const MotionBounds& bounds, double thickness, bool edge_pairs) {
  const TriangleTree::Node& first = tree_.node(a);
  const TriangleTree::Node& second = tree_.node(b);
  const int first_end = first.first + first.count, second_end = second.first + second.count;
  for (int s = first.first; s < first_end; ++s) {
    const int t = tree_.triangle(s);
    // A leaf with itself: each pair of its triangles once (a triangle with itself has none: its
    // vertices and edges all touch it).
    for (int r = a == b ? s + 1 : second.first; r < second_end; ++r) {
      const int u = tree_.triangle(r);
      if (!boxesOverlap(triangle_lo_[t], triangle_hi_[t], triangle_lo_[u], triangle_hi_[u]))
        continue;
      for (int v : owned_vertices_[t]) {
        if (v >= 0) addVertexTriangle(v, u, p, topology, bounds, thickness);
      }
      for (int v : owned_vertices_[u]) {
        if (v >= 0) addVertexTriangle(v, t, p, topology, bounds, thickness);
      }
      if (!edge_pairs) continue;
      for (int e : owned_edges_[t]) {
        if (e < 0) continue;
        for (int f : owned_edges_[u]) {
          if (f >= 0) addEdgeEdge(std::min(e, f), std::max(e, f), p, topology, bounds, thickness);
        }
      }
    }
  }
}

void SelfCollision::addVertexTriangle(int v, int t, const Particles& p,
                                      const ClothTopology& topology, const MotionBounds& bounds,
                                      double thickness) {
  if (!boxesOverlap(grown_lo_[v], grown_hi_[v], triangle_lo_[t], triangle_hi_[t])) return;
  const auto& tri = topology.triangles;
  const int a = static_cast<int>(tri[3 * t]), b = static_cast<int>(tri[3 * t + 1]),
            c = static_cast<int>(tri[3 * t + 2]);
  if (v == a || v == b || v == c || allKinematic(p, v, a, b, c)) return;
  const Vec3Array& x = bounds.path_start;
  const Vec3Array& move = bounds.path_move;
  // How far each particle may leave its path.
  auto deviation = [&](int i) { return bounds.path_slack * p.radius[i]; };
  // The paths' cull (findPairs), where it can drop the pair at all: the distance is at most the
  // diagonal of the two boxes together (a thickness as large as the cloth would otherwise add its
  // cost to every pair of a search that lists them all).
  const double reach =
      thickness + deviation(v) + std::max({deviation(a), deviation(b), deviation(c)}) +
      std::sqrt(std::max({(move[v] - move[a]).squaredNorm(), (move[v] - move[b]).squaredNorm(),
                          (move[v] - move[c]).squaredNorm()}));
  const Vec3 span = grown_hi_[v].cwiseMax(triangle_hi_[t]) - grown_lo_[v].cwiseMin(triangle_lo_[t]);
  if (reach * reach < span.squaredNorm() && pointTriangleDistance(x[v], x[a], x[b], x[c]) > reach) {
    return;
  }
  ContactGeometry start;
  if (!vertexTriangle(p.step_start[v], p.step_start[a], p.step_start[b], p.step_start[c], start)) {
    return;
  }
  SelfContactPair pair;
  pair.index[0] = v;
  pair.index[1] = a;
  pair.index[2] = b;
  pair.index[3] = c;
  pair.triangle = t;
  pair.side = start.distance >= 0.0 ? 1.0 : -1.0;
  vertex_found_.push_back(pair);
}

// Edges of one grid cell or of neighbouring cells (some end points within one row and column)
// are left out: nearly coplanar while the cloth is smooth, they would get a side by chance, and
// folding them onto each other is already stopped by the vertex-triangle contacts.
// A mesh cloth: the particles sharing a triangle or a hinge, which on a grid are exactly these.
bool SelfCollision::neighbours(int u, int v, const ClothTopology& topology) const {
  if (topology.from_mesh) return topology.meshNear(u, v);
  const int cols = topology.cols;
  const int dr = u / cols - v / cols, dc = u % cols - v % cols;
  return dr >= -1 && dr <= 1 && dc >= -1 && dc <= 1;
}

void SelfCollision::addEdgeEdge(int e, int f, const Particles& p, const ClothTopology& topology,
                                const MotionBounds& bounds, double thickness) {
  if (!boxesOverlap(edge_lo_[e], edge_hi_[e], edge_lo_[f], edge_hi_[f])) return;
  const int a = edges_[e][0], b = edges_[e][1], c = edges_[f][0], d = edges_[f][1];
  if (neighbours(a, c, topology) || neighbours(a, d, topology) || neighbours(b, c, topology) ||
      neighbours(b, d, topology) || allKinematic(p, a, b, c, d)) {
    return;
  }
  const Vec3Array& x = bounds.path_start;
  const Vec3Array& move = bounds.path_move;
  auto deviation = [&](int i) { return bounds.path_slack * p.radius[i]; };
  // The paths' cull (findPairs), for points of the two edges: convex combinations of a, b and
  // of c, d.
  const double reach =
      thickness + std::max(deviation(a), deviation(b)) + std::max(deviation(c), deviation(d)) +
      std::sqrt(std::max({(move[a] - move[c]).squaredNorm(), (move[a] - move[d]).squaredNorm(),
                          (move[b] - move[c]).squaredNorm(), (move[b] - move[d]).squaredNorm()}));
  const Vec3 span = edge_hi_[e].cwiseMax(edge_hi_[f]) - edge_lo_[e].cwiseMin(edge_lo_[f]);
  if (reach * reach < span.squaredNorm() &&
      segmentSegmentDistance(x[a], x[b], x[c], x[d]) > reach) {
    return;
  }
  SelfContactPair pair;
  pair.index[0] = a;
  pair.index[1] = b;
  pair.index[2] = c;
  pair.index[3] = d;
  pair.edge_edge = true;
  ContactGeometry start;
  if (geometry(pair, p.step_start, start) && start.distance != 0.0) {
    pair.side = start.distance > 0.0 ? 1.0 : -1.0;
  }
  edge_found_.push_back(pair);
}

void SelfCollision::preStabilize(Particles& p, double thickness, double max_shift,
                                 double slop) const {
  for (const SelfContactPair& pair : pairs_) {
    ContactGeometry g;
    if (pair.side == 0.0 || !geometry(pair, p.position, g) || !g.inside) continue;
    const double violation = pair.side * g.distance - thickness;
    if (violation >= -slop * thickness) continue;
    const double w = inverseMass(pair, g, p);
    if (w == 0.0) continue;
    distribute(pair, g, w, (std::min(-violation, max_shift) * pair.side) * g.normal, p);
  }
}

void SelfCollision::measureAllowances(const Vec3Array& x, double thickness, double slop) {
  for (SelfContactPair& pair : pairs_) {
    if (pair.side != 0.0 && pair.allowance_side == pair.side) continue;  // measured (header)
    pair.allowance = 0.0;
    pair.allowance_side = pair.side;
    ContactGeometry g;
    if (pair.side != 0.0 && geometry(pair, x, g) && g.inside) {
      pair.allowance = allowanceFor(thickness - pair.side * g.distance, thickness, slop);
    }
  }
}

double SelfCollision::project(Particles& p, double thickness, int substep, const Friction& friction,
                              Vec3Array& reaction) {
  double max_change = 0.0;
  for (SelfContactPair& pair : pairs_) {
    ContactState& state = pair.state;
    // A window of one substep: the relative displacement is measured from substep_start, since
    // the point under the vertex (or the edges' closest points) changes as the layers slide.
    if (state.beginSubstep(substep, substep, false, false)) {
      // Beside the triangle (edges not facing each other) the vertex may go round the border to
      // the other side (a hinge neighbour rotating about the shared edge, a layer sliding past a
      // fold): the side only freezes while the contact is active, where changing it means
      // passing through.
      // Nearly parallel edges have no stable common normal (n = p21 x q21 comes out reversed on
      // the other side of parallel): their side is unknown until they diverge again, and it is
      // only frozen while they are within kEdgeBand thicknesses, where a change of sign can only
      // mean that they passed through each other.
      // Edges more than kEdgeBand h apart at the substep start are either not facing each other
      // or farther than the band: either way the side follows the start (below), which needs
      // only the sign, not the closest points.
      double side = 0.0;
      const double band = kEdgeBand * thickness;
      const bool apart = pair.edge_edge ? edgesApart(pair, p.substep_start, band)
                                        : vertexApart(pair, p.substep_start, band);
      far_pair_substeps_ += apart && !pair.local;
      if (pair.edge_edge && apart) {
        if (!edgeSide(pair, p.substep_start, side)) {
          pair.side = 0.0;
        } else if (side != 0.0) {
          pair.side = side;
        }
      } else {
        // Where the start's distance has the sign of the side, every branch below keeps the side
        // (or sets it to the same): that sign alone, without the closest points, settles most
        // pairs (the layers of a fold, of a garment, resting on each other).
        double start_side = 0.0;
        const bool signed_start = pair.edge_edge ? edgeSide(pair, p.substep_start, start_side)
                                                 : vertexSide(pair, p.substep_start, start_side);
        if (!signed_start || start_side == 0.0 || start_side != pair.side) {
          ContactGeometry start;
          if (!geometry(pair, p.substep_start, start)) {
            if (pair.edge_edge) pair.side = 0.0;
          } else if ((!start.inside || pair.side == 0.0 ||
                      (pair.edge_edge && std::abs(start.distance) > kEdgeBand * thickness)) &&
                     start.distance != 0.0) {
            pair.side = start.distance > 0.0 ? 1.0 : -1.0;
          }
        }
      }
    }
    if (pair.side == 0.0) continue;
    // Edges more than h apart now, on their side (the sign agrees with the distance's: facing
    // each other, the distance is their distance, more than h), with nothing pushed this substep
    // (a window of one substep: no friction either): no correction.
    if (pair.edge_edge && state.depth == 0.0 && edgesApart(pair, p.position, thickness)) {
      double side = 0.0;
      if (!edgeSide(pair, p.position, side) || side * pair.side >= 0.0) continue;
    }
    ContactGeometry g;
    if (!geometry(pair, p.position, g) || !g.inside) continue;
    const double w = inverseMass(pair, g, p);
    if (w == 0.0) continue;
    const double c = pair.side * g.distance - (thickness - pair.allowance);
    if (c < 0.0 || state.depth > 0.0) {
      // At most h / 2 per pass: a contact found deep (a fast approach, or a tangle the solver did
      // not prevent) is undone over several passes and substeps, the side frozen meanwhile,
      // instead of flinging the cloth (full pushes fed the whipping of stiff cloth into tangles
      // that grew without bound in the drape scene). h per pass was tried: fewer intersections
      // on the drape at 64 x 64 and 91 x 91 (24 to 17 and 58 to 22 at most over 1 s), but at
      // 128 x 128 the cloth blew up (1.4 million intersections, strain 2.7, 12 s a step
      // against 244, 0.88 and 0.97 s: `cloth_bench --duration 0.5` at the scaling benchmark's
      // 128 x 128 settings).
      const double push = contactIncrement(std::max(c, -kMaxPush * thickness), state);
      state.normal = pair.side * g.normal;
      distribute(pair, g, w, push * state.normal, p, &reaction);
      max_change = std::max(max_change, std::abs(push));
    }
    if (state.frictionDepth() > 0.0) {
      Vec3 relative = Vec3::Zero();
      for (int k = 0; k < 4; ++k) {
        const int i = pair.index[k];
        relative += g.coefficient[k] * (p.position[i] - p.substep_start[i]);
      }
      distribute(pair, g, w, frictionCorrection(relative, state, friction), p, &reaction);
    }
  }
  return max_change;
}

double SelfCollision::maxPenetration(const Particles& p, double thickness) const {
  double depth = 0.0;
  for (const SelfContactPair& pair : pairs_) {
    ContactGeometry g;
    if (pair.side == 0.0 || !geometry(pair, p.position, g) || !g.inside) continue;
    if (pair.edge_edge && std::abs(g.distance) > kEdgeBand * thickness) continue;  // not in touch
    depth = std::max(depth, thickness - pair.side * g.distance);
  }
  return depth;
}

}  // namespace pbd_cloth
