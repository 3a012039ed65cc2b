// The self-collision broad phase: a bounding volume hierarchy over the cloth's triangles with a
// normal cone per node (Volino & Magnenat-Thalmann 1994, "Efficient self-collision detection on
// smoothly discretized surface animations using geometrical shape regularity"; Provot 1997,
// "Collision and self-collision handling in cloth model dedicated to design garments"), the cones
// bounding the normals over the whole search horizon (continuous normal cones: Tang, Curtis,
// Yoon, Manocha 2009, "ICCD: interactive continuous collision detection between deformable
// models using connectivity-based culling").
//
// Why a tree and not the spatial hash it replaced: a cloth is mostly smooth, and the hash lists
// every neighbour of every vertex (their boxes overlap) for the paths' cull to drop one by one; a
// connected patch whose normals all lie within a cone narrower than the flatness angle (below)
// cannot bring a vertex within h of a triangle of its own that does not touch it, so the tree
// leaves the whole patch out, and with it every pair of neighbouring patches whose union is
// flat. A cloth lying or falling flat costs the refit only.
//
// Flatness (the criterion's bound, for thickness h): the normals of a connected patch lie within
// theta of an axis, so the patch is a graph over the plane normal to it, each triangle shrunk by
// at most cos(theta) in that projection. A triangle that does not touch vertex v lies outside v's
// star, which holds a disc of radius g (the smallest triangle altitude) around v: the two are at
// least cos(theta) g apart, less the two particles' deviations from their paths (h / 2 each,
// Collisions' path slack times the radius h). That is more than h while cos(theta) > 2 h / g
// (with g at the cloth's rest shape: stretch is held to a few percent). Edges that are not
// neighbours (self_collision.cpp) are as far apart. Patches are flat below that angle, and never
// at more than 60 degrees; a cloth with h >= g / 2 has no flat patch at all.
// The one condition of Volino's theorem the tree does not test is the patch's contour (it must
// not overlap itself in the projection): its patches are compact, a few cells across, which a
// cloth cannot roll up without normals leaving the cone.
#pragma once

#include <vector>

#include "pbd_cloth/geometry/vector_types.h"

namespace pbd_cloth {

// Whether the boxes [a_lo, a_hi] and [b_lo, b_hi] share a point.
inline bool boxesOverlap(const Vec3& a_lo, const Vec3& a_hi, const Vec3& b_lo, const Vec3& b_hi) {
  return (a_lo.array() <= b_hi.array()).all() && (b_lo.array() <= a_hi.array()).all();
}

class TriangleTree {
 public:
  struct Node {
    Vec3 lo = Vec3::Zero();  // the box of its triangles' boxes
    Vec3 hi = Vec3::Zero();
    // Normal cone: every normal of its triangles over the horizon is within the angle of `axis`
    // (its cosine and sine; an empty cone, cos -1, when a normal is undefined).
    Vec3 axis = Vec3::UnitZ();
    double cos_angle = -1.0;
    double sin_angle = 0.0;
    int first = 0;  // its triangles: triangle(first) .. triangle(first + count - 1)
    int count = 0;
    int left = -1;  // children (-1 for a leaf)
    int right = -1;
    int boundary_first = 0;  // its vertices that other nodes' triangles share, sorted
    int boundary_count = 0;
    bool connected = false;  // its triangles form one patch (through shared vertices)
  };

  // The hierarchy, once per cloth: triangles split at the median of their centroids along the
  // longest side of their box (in `positions`, the cloth's rest shape), leaves of at most
  // kLeafTriangles; the boundaries and connectedness of every node; the smallest altitude.
  void build(const std::vector<unsigned>& triangles, const Vec3Array& positions);

  // Per search: each node's box from its triangles' boxes (`triangle_lo`, `triangle_hi`, by
  // triangle index), its cone from the triangles' normals along the reference paths start + s
  // move, s in [0, 1]. The normal of a triangle moving so is quadratic in s,
  //   N(s) = B0 (1 - s)^2 + 2 B1 s (1 - s) + B2 s^2,  B0 = e1 x e2,  B2 = (e1 + d1) x (e2 + d2),
  //   B1 = B0 + (e1 x d2 + d1 x e2) / 2  (e the edges from the first corner, d their moves),
  // a combination of B0, B1, B2 with weights >= 0: the cone holding them holds N(s).
  void refit(const std::vector<unsigned>& triangles, const Vec3Array& triangle_lo,
             const Vec3Array& triangle_hi, const Vec3Array& start, const Vec3Array& move);

  // A local search: marks the leaves `leaves` (node indices) and their ancestors, clearing the
  // last marks. refitMarked() then refits the marked nodes only (the boxes or paths of some of
  // the leaves' triangles changed; every other node stays as the last refit left it), and
  // forEachMarkedLeafPair() visits, of the pairs forEachLeafPair() would visit, those that hold a
  // marked leaf, in the same order and by the same rules: a node without a mark holds no such
  // pair, nor does a pair of nodes without one.
  void mark(const std::vector<int>& leaves);
  void refitMarked(const std::vector<unsigned>& triangles, const Vec3Array& triangle_lo,
                   const Vec3Array& triangle_hi, const Vec3Array& start, const Vec3Array& move);
  template <class Visit>
  bool forEachMarkedLeafPair(double cos_flat, Visit&& visit) const {
    return nodes_.empty() || selfPairs<true>(0, cos_flat, visit);
  }
  // The leaf that holds triangle t.
  int leafOf(int t) const { return leaf_of_[t]; }
  int nodeCount() const { return static_cast<int>(nodes_.size()); }

  // Calls visit(a, b) for every pair of leaves (node indices, each pair once; a == b: the leaf
  // with itself) whose boxes overlap and that no flat patch holds: a connected node whose cone's
  // cosine is at least cos_flat is skipped, and so is a pair of connected nodes that share a
  // vertex and whose cones together are that narrow. cos_flat > 1 skips nothing.
  // visit returns false to end the traversal there (a search over its budget); forEachLeafPair
  // then returns false, and true when it visited every such pair.
  template <class Visit>
  bool forEachLeafPair(double cos_flat, Visit&& visit) const {
    return nodes_.empty() || selfPairs<false>(0, cos_flat, visit);
  }

  // cos(theta) of the flatness bound for thickness h (header comment): max(2 h / g, 0.5), or 2
  // (nothing flat) when 2 h / g >= 1.
  double cosFlat(double thickness) const;

  const Node& node(int k) const { return nodes_[k]; }
  int triangle(int slot) const { return order_[slot]; }  // triangles in leaf order

  static constexpr int kLeafTriangles = 4;

 private:
  int buildNode(int first, int count, const std::vector<Vec3>& centroid);
  bool share(const Node& a, const Node& b) const;
  bool flatTogether(const Node& a, const Node& b, double cos_flat) const;

  // Both return false once visit has asked to stop.
  // kMarked: only the pairs that hold a marked leaf (forEachMarkedLeafPair).
  template <bool kMarked, class Visit>
  bool selfPairs(int k, double cos_flat, Visit& visit) const {
    const Node& n = nodes_[k];
    if (kMarked && !marked_[k]) return true;
    if (n.connected && n.cos_angle >= cos_flat) return true;
    if (n.left < 0) return visit(k, k);
    return selfPairs<kMarked>(n.left, cos_flat, visit) &&
           selfPairs<kMarked>(n.right, cos_flat, visit) &&
           crossPairs<kMarked>(n.left, n.right, cos_flat, visit);
  }
  template <bool kMarked, class Visit>
  bool crossPairs(int i, int j, double cos_flat, Visit& visit) const {
    const Node& a = nodes_[i];
    const Node& b = nodes_[j];
    if (kMarked && !marked_[i] && !marked_[j]) return true;
    if (!boxesOverlap(a.lo, a.hi, b.lo, b.hi)) return true;
    if (a.connected && b.connected && flatTogether(a, b, cos_flat) && share(a, b)) return true;
    const bool a_leaf = a.left < 0, b_leaf = b.left < 0;
    if (a_leaf && b_leaf) return visit(i, j);
    if (a_leaf || (!b_leaf && b.count > a.count)) {
      return crossPairs<kMarked>(i, b.left, cos_flat, visit) &&
             crossPairs<kMarked>(i, b.right, cos_flat, visit);
    }
    return crossPairs<kMarked>(a.left, j, cos_flat, visit) &&
           crossPairs<kMarked>(a.right, j, cos_flat, visit);
  }

  void refitNode(int k, const std::vector<unsigned>& triangles, const Vec3Array& triangle_lo,
                 const Vec3Array& triangle_hi, const Vec3Array& start, const Vec3Array& move);
  std::vector<Node> nodes_;
  std::vector<int> parent_;   // -1 for the root
  std::vector<int> leaf_of_;  // by triangle index
  std::vector<char> marked_;  // mark(): the marked nodes, and their list
  std::vector<int> marked_list_;
  std::vector<int> order_;     // triangle indices in leaf order
  std::vector<int> boundary_;  // the nodes' boundary vertices (Node::boundary_first)
  double smallest_altitude_ = 0.0;
};

}  // namespace pbd_cloth
