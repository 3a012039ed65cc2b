// Cloth self-collision with thickness h.
//
// Vertex-triangle, the collision seed's constraint (eq. vertex_triangle_constraint):
//   C(q, p1, p2, p3) = s (q - p1) . n - h >= 0,  n = p21 x p31 / |p21 x p31|,
// applied while q projects inside the triangle (barycentric test), all four particles corrected
// by inverse mass.
//
// Edge-edge, its companion (Bridson, Fedkiw, Anderson 2002, sec. 7): vertex-triangle alone cannot
// see two edges crossing near the triangles' borders (a free edge of the cloth sliding past
// another, the layers of a fold meeting at its rim), which is what countSelfIntersections counts.
// For edges p1p2 and q1q2 whose closest points p(a), q(b) are interior to both,
//   C = s (p1 - q1) . n - h >= 0,  n = p21 x q21 / |p21 x q21|
// ((p(a) - q(b)) is parallel to n there, so (p1 - q1) . n is their signed distance).
//
// The side s: taken from the positions at the step start, then frozen while the vertex is over the
// triangle (the edges' closest points are interior and the edges within a few thicknesses), where
// changing sides means passing through; elsewhere it follows the vertex round the triangle's
// border at every substep start. So a vertex or edge pushed through the other layer within a step
// is pulled back to the side it came from.
//
// Both are written as one four-point contact: C = s n . sum_k c_k x_k - h with coefficients
// (1, -b1, -b2, -b3) (b the barycentric weights) or (1 - a, a, -(1 - b), -b), gradients s c_k n,
// so the corrections w_k c_k lambda s n sum to zero momentum (sum_k c_k = 0).
#pragma once

#include <array>
#include <vector>

#include "pbd_cloth/collision/contact.h"
#include "pbd_cloth/geometry/triangle_queries.h"
#include "pbd_cloth/geometry/triangle_tree.h"
#include "pbd_cloth/model/particles.h"

namespace pbd_cloth {

// How far each particle may move during the rest of the step, while the broad phase's candidates
// stand (Collisions::computeSweptBoxes): within its swept box [lo, hi], and within
// path_slack times its radius of its reference path, the line from path_start (where it is at the
// search) to path_start + path_move (at the step end).
struct MotionBounds {
  const Vec3Array& lo;
  const Vec3Array& hi;
  const Vec3Array& path_start;
  const Vec3Array& path_move;
  double path_slack;
};

struct SelfContactPair {
  // Vertex-triangle: the vertex, then the triangle's corners. Edge-edge: one edge, then the other.
  int index[4] = {0, 0, 0, 0};
  int triangle = -1;  // vertex-triangle: the triangle's index (its leaf, findPairsNear)
  bool edge_edge = false;
  // Found by a local search (findPairsNear): not counted among the far candidates, which measure
  // what the window's length costs (takeFarPairSubsteps), while a local search lists the
  // neighbours of a particle whose new path differs from theirs by its change of velocity.
  bool local = false;
  double side = 0.0;       // s: +1 or -1; 0 until it is known (parallel edges at the step start)
  double allowance = 0.0;  // approach closer than h tolerated this step (allowanceFor)
  double allowance_side = 0.0;  // the side the allowance was measured with (0: not measured)
  ContactState state;
};

class SelfCollision {
 public:
  // Sizes the buffers and lists the mesh's edges.
  void reserve(const Particles& particles, const ClothTopology& topology);

  // Broad phase, once per search window: each cloth vertex whose swept box comes within h of a
  // triangle's swept box (the triangle's own vertices excepted) and that the reference paths do
  // not keep farther than h from it (below) and, with `edge_pairs`, each pair of edges of cells
  // that are not neighbours whose swept boxes come within h. The sides come from the step-start
  // positions. A repeated search within the window (a particle left its box) passes edge_pairs =
  // false: it renews the vertex-triangle pairs, the primary contacts, and keeps the edge-edge
  // pairs of the window's start. With `keep_states` (any search after the step's first) a pair
  // found again keeps its side and contact state.
  // The candidates come from the triangle tree (triangle_tree.h): pairs of leaves whose boxes
  // overlap, flat patches left out. Each vertex and each edge is owned by one of its triangles, so
  // a leaf pair lists the owned vertices of either side's triangles against the other's
  // triangles, and the owned edges of both against each other: every candidate once.
  // The list is the same for every solver.threads (the search runs on one thread).
  // The paths' cull: points of the triangle are convex combinations of its corners, so while each
  // particle i stays within r_i of its path x_i + s u_i (s in [0, 1] the same for all), the
  // distance between the vertex v and the triangle (a, b, c) changes from its value d at the
  // search by at most r_v + max_k r_k + max_k |u_v - u_k| (k = a, b, c). A pair with
  //   d > h + r_v + max_k r_k + max_k |u_v - u_k|
  // cannot come within h before a particle leaves its path, which Collisions checks at every
  // substep (and then searches again): it is left out. It drops the neighbours of a cloth moving
  // as a whole, which the boxes alone list, where the tree's cones do not (a curved cloth).
  // A budget bounds a search: it ends once it has found kPairsPerElement candidates per triangle
  // and edge of the cloth, keeping those (the tree's order: the same for every run) and skipping
  // the rest; lastSearchTruncated() says so. The shipped scenes and the tests need at most 4.3
  // per element, a 10 x 10 cloth flung across itself at 52 m/s (test_allocations.cpp) 98; a
  // 32 x 32 cloth crushed onto a line by a robot 57, onto a point 1279, which took 0.7 to 50 s
  // a step before the budget: every vertex is then within h of hundreds of triangles, contacts
  // no projection can satisfy anyway, and the node would stop keeping time for good.
  static constexpr int kPairsPerElement = 16;
  void findPairs(const Particles& particles, const ClothTopology& topology,
                 const MotionBounds& bounds, double thickness, bool edge_pairs, bool keep_states);
  // The particles a local search renews for `leavers` (the cloth particles, index below
  // `particles`, that left their bounds): the leavers, and every corner of the tree's leaves
  // that hold a leaver whose triangles all lie in those leaves.
  const std::vector<int>& renewedAround(const std::vector<int>& leavers,
                                        const ClothTopology& topology, int particles);
  // A local search within the window, for a few particles that left their bounds
  // (Collisions::searchNear): `renewed` lists the particles whose bounds were set anew, every
  // other particle's still hold (its path only re-expressed from now on). The vertex-triangle
  // candidates of every leaf pair of the tree that holds a triangle with a renewed corner are
  // found again, those of every other leaf pair stay: a pair of particles that kept their bounds
  // is as the last search left it. The changed leaves and their ancestors alone are refitted, and
  // the whole traversal runs restricted to them (TriangleTree::mark, forEachMarkedLeafPair), so a
  // local search costs about its leaves' share of a search, not a pass over the cloth. Edge-edge
  // pairs stay, as in a repeated search. The list stays ordered by first particle (a particle's
  // kept pairs before its new ones, those by their indices), pairs found again keep their side
  // and state, and the same budget applies to the whole list.
  void findPairsNear(const Particles& particles, const ClothTopology& topology,
                     const MotionBounds& bounds, double thickness, const std::vector<int>& renewed);

  // Whether the last findPairs stopped at its budget (candidates skipped).
  bool lastSearchTruncated() const { return truncated_; }

  // Pre-stabilisation: pushes contacts closer than h by more than the slop (a fraction of h) apart
  // by at most max_shift, on the positions before the step's first prediction (no velocity).
  void preStabilize(Particles& particles, double thickness, double max_shift, double slop) const;
  // After pre-stabilisation: how much closer than h each contact may stay this step
  // (allowanceFor, `slop` a fraction of h), measured in `positions` (those of the step start).
  // A pair measured earlier in the step with the side it has now keeps its allowance: the step's
  // first search lists every pair anew, and later ones within the step pass the same positions,
  // so it would measure the same (a local search keeps most pairs: only its new ones are measured).
  void measureAllowances(const Vec3Array& positions, double thickness, double slop);

  // One projection pass, then friction; returns the largest correction. Kinematic particles of a
  // contact get its multiplier times their gradient added to `reaction`
  // (Collisions::kinematicReaction).
  double project(Particles& particles, double thickness, int substep, const Friction& friction,
                 Vec3Array& reaction);

  // Candidates more than a few thicknesses apart at a substep's start (their boxes), summed over
  // the substeps since the last call: listed for the motion of their search window, not for their
  // nearness (Collisions' adaptive search window). Returns the sum and starts a new one.
  long takeFarPairSubsteps() {
    const long sum = far_pair_substeps_;
    far_pair_substeps_ = 0;
    return sum;
  }

  // Deepest violation h - s distance over the contacts that are active (vertex over its
  // triangle; edges' closest points interior, edges within a few thicknesses) (m).
  double maxPenetration(const Particles& particles, double thickness) const;
  int pairCount() const { return static_cast<int>(pairs_.size()); }
  // The candidates: edge-edge pairs first, then vertex-triangle pairs by vertex.
  const std::vector<SelfContactPair>& pairs() const { return pairs_; }
  // Between steps: the candidate lists go back to their reserve once an extreme step that outgrew
  // it is over (a fast fold can need many times the usual candidates, and a node that kept that
  // peak for good would grow with every new extreme).
  // Returns the bytes released.
  std::size_t releaseExcessCapacity();
  int vertexTrianglePairCount() const { return pairCount() - edge_pair_count_; }
  int edgeEdgePairCount() const { return edge_pair_count_; }

 private:
  // The candidates of the leaves a and b of the tree (a == b: of the leaf with itself).
  void findLeafPairs(int a, int b, const Particles& particles, const ClothTopology& topology,
                     const MotionBounds& bounds, double thickness, bool edge_pairs);
  void addVertexTriangle(int v, int t, const Particles& particles, const ClothTopology& topology,
                         const MotionBounds& bounds, double thickness);
  void addEdgeEdge(int e, int f, const Particles& particles, const ClothTopology& topology,
                   const MotionBounds& bounds, double thickness);
  bool neighbours(int u, int v, const ClothTopology& topology) const;
  // renewedAround, findPairsNear: marks the leaves of vertex v's triangles as changed
  // (leaf_changed_, changed_leaves_).
  void markLeavesOf(int v);
  // Triangle t's box from its corners' grown boxes.
  void boxTriangle(int t, const std::vector<unsigned>& triangles);
  using PairIterator = std::vector<SelfContactPair>::iterator;
  // Moves `found` to the end of pairs_, ordered by each pair's first particle.
  void appendByFirstParticle(std::vector<SelfContactPair>& found, int particles);
  void carryStates(PairIterator begin, PairIterator end, PairIterator old_begin,
                   PairIterator old_end);

  std::vector<std::array<int, 2>> edges_;
  TriangleTree tree_;
  std::vector<std::array<int, 3>> owned_vertices_;  // per triangle, -1 where none
  std::vector<std::array<int, 3>> owned_edges_;     // per triangle: indices into edges_, -1
  Vec3Array grown_lo_;                              // vertex boxes grown by h / 2
  Vec3Array grown_hi_;
  Vec3Array triangle_lo_;  // triangle boxes: the union of their vertices' grown boxes
  Vec3Array triangle_hi_;
  Vec3Array edge_lo_;  // edge boxes: the union of their two vertices' grown boxes
  Vec3Array edge_hi_;
  std::size_t reserved_pairs_ = 0;      // capacity reserve() gave pairs_ and previous_
  std::size_t pair_budget_ = 0;         // kPairsPerElement (triangles + edges) per search
  bool truncated_ = false;              // lastSearchTruncated
  std::vector<SelfContactPair> pairs_;  // edge-edge pairs first, then vertex-triangle pairs
  int edge_pair_count_ = 0;
  std::vector<SelfContactPair> previous_;      // the pairs a search within the step replaces
  int previous_edge_count_ = 0;                // edge-edge pairs at the front of previous_
  long far_pair_substeps_ = 0;                 // takeFarPairSubsteps
  std::vector<SelfContactPair> vertex_found_;  // this search's vertex-triangle pairs, then sorted
  std::vector<SelfContactPair> edge_found_;    // this search's edge-edge pairs, then sorted
  std::vector<int> vertex_slot_;               // the counting sort's per-vertex counts, offsets
  // findPairsNear: the triangles of each cloth vertex (CSR), the leaf of the triangle that owns
  // each vertex, and the changed leaves (a mark per tree node, and their list).
  std::vector<int> vertex_triangle_offsets_;
  std::vector<int> vertex_triangles_;
  std::vector<int> owner_leaf_;
  std::vector<char> leaf_changed_;
  std::vector<int> changed_leaves_;
  std::vector<char> particle_renewed_;  // renewedAround's marks, and its list
  std::vector<int> renewed_;
};

}  // namespace pbd_cloth
