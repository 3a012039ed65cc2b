#include "pbd_cloth/geometry/triangle_tree.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <numeric>

namespace pbd_cloth {

namespace {

// A normal shorter than this fraction of |e1| |e2| (the sine of the triangle's smallest angle
// below ~1e-8, as self_collision.cpp's kDegenerate) has no direction: the cone is the whole sphere.
constexpr double kDegenerate = 1e-16;
// Flat patches never reach past 60 degrees (cosine 0.5), whatever the thickness allows.
constexpr double kWidestFlat = 0.5;

struct Cone {
  Vec3 axis = Vec3::UnitZ();
  double cos_angle = -1.0;  // -1: every direction
  double sin_angle = 0.0;
};

// The cone about `axis` (unit) holding a cone (a, cos t, sin t): its angle is angle(axis, a) + t,
// added through the sines and cosines (no acos); past pi it is the whole sphere.
void widenToHold(const Vec3& axis, const Vec3& a, double cos_t, double sin_t, double& cos_out,
                 double& sin_out) {
  const double c = std::clamp(axis.dot(a), -1.0, 1.0);
  const double s = std::sqrt(std::max(0.0, 1.0 - c * c));
  double cos_sum = c * cos_t - s * sin_t;
  const double sin_sum = s * cos_t + c * sin_t;
  if (sin_sum < 0.0) cos_sum = -1.0;  // the sum passed pi
  if (cos_sum < cos_out) {
    cos_out = cos_sum;
    sin_out = std::max(0.0, sin_sum);
  }
}

// The cone holding two cones, about the mean of their axes.
Cone merge(const Cone& a, const Cone& b) {
  Cone out;
  if (a.cos_angle <= -1.0 || b.cos_angle <= -1.0) return out;
  const Vec3 sum = a.axis + b.axis;
  const double length = sum.norm();
  if (!(length > 1e-12)) return out;
  out.axis = sum / length;
  out.cos_angle = 1.0;
  out.sin_angle = 0.0;
  widenToHold(out.axis, a.axis, a.cos_angle, a.sin_angle, out.cos_angle, out.sin_angle);
  widenToHold(out.axis, b.axis, b.cos_angle, b.sin_angle, out.cos_angle, out.sin_angle);
  return out;
}

Cone coneOf(const TriangleTree::Node& n) { return Cone{n.axis, n.cos_angle, n.sin_angle}; }

// Adds the unit directions of a triangle's normal along its corners' paths x_k + s u_k
// (TriangleTree::refit: B0, B2 and, unless it vanishes, B1) to `directions`; false when the
// normal has no direction at the start or at the end (the cone is then the whole sphere).
bool addNormalDirections(const Vec3& x0, const Vec3& x1, const Vec3& x2, const Vec3& u0,
                         const Vec3& u1, const Vec3& u2, Vec3* directions, int& count) {
  const Vec3 e1 = x1 - x0, e2 = x2 - x0, d1 = u1 - u0, d2 = u2 - u0;
  const Vec3 b0 = e1.cross(e2);
  const Vec3 b2 = (e1 + d1).cross(e2 + d2);
  const Vec3 b1 = b0 + 0.5 * (e1.cross(d2) + d1.cross(e2));
  const double scale = e1.squaredNorm() * e2.squaredNorm();
  const double n0 = b0.squaredNorm(), n2 = b2.squaredNorm(), n1 = b1.squaredNorm();
  if (!(n0 > kDegenerate * scale) || !(n2 > kDegenerate * scale)) return false;
  directions[count++] = b0 / std::sqrt(n0);
  directions[count++] = b2 / std::sqrt(n2);
  // B1 near zero adds no direction (N(s) is then a combination of B0 and B2 alone).
  if (n1 > kDegenerate * scale) directions[count++] = b1 / std::sqrt(n1);
  return true;
}

// The cone about the mean of `count` unit directions that holds them all.
Cone coneOfDirections(const Vec3* directions, int count) {
  Cone out;
  Vec3 sum = Vec3::Zero();
  for (int k = 0; k < count; ++k) sum += directions[k];
  const double length = sum.norm();
  if (!(length > 1e-12)) return out;
  out.axis = sum / length;
  double cos_angle = 1.0;
  for (int k = 0; k < count; ++k) cos_angle = std::min(cos_angle, out.axis.dot(directions[k]));
  if (cos_angle <= -1.0) return Cone{};
  out.cos_angle = cos_angle;
  out.sin_angle = std::sqrt(std::max(0.0, 1.0 - cos_angle * cos_angle));
  return out;
}

}  // namespace

int TriangleTree::buildNode(int first, int count, const std::vector<Vec3>& centroid) {
  const int k = static_cast<int>(nodes_.size());
  nodes_.emplace_back();
  nodes_[k].first = first;
  nodes_[k].count = count;
  if (count <= kLeafTriangles) return k;
  Vec3 lo = centroid[order_[first]], hi = lo;
  for (int s = first; s < first + count; ++s) {
    lo = lo.cwiseMin(centroid[order_[s]]);
    hi = hi.cwiseMax(centroid[order_[s]]);
  }
  int axis = 0;
  (hi - lo).maxCoeff(&axis);
  const int half = count / 2;
  // Ties broken by index: the same tree on every machine.
  std::nth_element(order_.begin() + first, order_.begin() + first + half,
                   order_.begin() + first + count, [&](int a, int b) {
                     const double ca = centroid[a][axis], cb = centroid[b][axis];
                     return ca < cb || (ca == cb && a < b);
                   });
  const int left = buildNode(first, half, centroid);
  const int right = buildNode(first + half, count - half, centroid);
  nodes_[k].left = left;
  nodes_[k].right = right;
  return k;
}

void TriangleTree::build(const std::vector<unsigned>& tri, const Vec3Array& x) {
  const int triangles = static_cast<int>(tri.size() / 3);
  nodes_.clear();
  boundary_.clear();
  parent_.clear();
  leaf_of_.clear();
  order_.resize(triangles);
  std::iota(order_.begin(), order_.end(), 0);
  smallest_altitude_ = 0.0;
  if (triangles == 0) return;
  int vertices = 0;
  for (unsigned v : tri) vertices = std::max(vertices, static_cast<int>(v) + 1);
  std::vector<Vec3> centroid(triangles);
  std::vector<int> degree(vertices, 0);
  double smallest = INFINITY;
  for (int t = 0; t < triangles; ++t) {
    const Vec3& a = x[tri[3 * t]];
    const Vec3& b = x[tri[3 * t + 1]];
    const Vec3& c = x[tri[3 * t + 2]];
    centroid[t] = (a + b + c) / 3.0;
    for (int e = 0; e < 3; ++e) ++degree[tri[3 * t + e]];
    // Altitude onto the longest side: twice the area over that side.
    const double twice_area = (b - a).cross(c - a).norm();
    const double longest = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
    if (twice_area > 1e-8 * longest * longest) smallest = std::min(smallest, twice_area / longest);
  }
  smallest_altitude_ = std::isfinite(smallest) ? smallest : 0.0;
  nodes_.reserve(4 * (triangles / kLeafTriangles + 1));
  buildNode(0, triangles, centroid);
  parent_.assign(nodes_.size(), -1);
  leaf_of_.assign(triangles, -1);
  for (int k = 0; k < static_cast<int>(nodes_.size()); ++k) {
    const Node& n = nodes_[k];
    if (n.left >= 0) {
      parent_[n.left] = parent_[n.right] = k;
    } else {
      for (int s = n.first; s < n.first + n.count; ++s) leaf_of_[order_[s]] = k;
    }
  }
  marked_.assign(nodes_.size(), 0);
  marked_list_.clear();
  marked_list_.reserve(nodes_.size());

  // Each node's boundary (its vertices used by fewer of its triangles than in all) and whether
  // its triangles form one patch (union-find through the first of its triangles at each vertex).
  std::vector<int> stamp(vertices, -1), uses(vertices, 0), first_slot(vertices, 0);
  std::vector<int> parent(triangles, 0), touched;
  auto root = [&parent](int s) {
    while (parent[s] != s) s = parent[s] = parent[parent[s]];
    return s;
  };
  for (int k = 0; k < static_cast<int>(nodes_.size()); ++k) {
    Node& n = nodes_[k];
    touched.clear();
    for (int s = n.first; s < n.first + n.count; ++s) parent[s] = s;
    for (int s = n.first; s < n.first + n.count; ++s) {
      for (int e = 0; e < 3; ++e) {
        const int v = static_cast<int>(tri[3 * order_[s] + e]);
        if (stamp[v] != k) {
          stamp[v] = k;
          uses[v] = 0;
          first_slot[v] = s;
          touched.push_back(v);
        }
        ++uses[v];
        parent[root(s)] = root(first_slot[v]);
      }
    }
    const int patch = root(n.first);
    n.connected = true;
    for (int s = n.first; s < n.first + n.count; ++s) n.connected = n.connected && root(s) == patch;
    std::sort(touched.begin(), touched.end());
    n.boundary_first = static_cast<int>(boundary_.size());
    for (int v : touched) {
      if (uses[v] < degree[v]) boundary_.push_back(v);
    }
    n.boundary_count = static_cast<int>(boundary_.size()) - n.boundary_first;
  }
}

double TriangleTree::cosFlat(double thickness) const {
  if (!(smallest_altitude_ > 0.0)) return 2.0;
  const double bound = 2.0 * thickness / smallest_altitude_;
  if (!(bound < 1.0)) return 2.0;
  return std::max(bound, kWidestFlat);
}

void TriangleTree::refit(const std::vector<unsigned>& tri, const Vec3Array& triangle_lo,
                         const Vec3Array& triangle_hi, const Vec3Array& x, const Vec3Array& u) {
  // Children come after their parent (built depth first): backwards, children before parents.
  for (int k = static_cast<int>(nodes_.size()) - 1; k >= 0; --k) {
    refitNode(k, tri, triangle_lo, triangle_hi, x, u);
  }
}

void TriangleTree::mark(const std::vector<int>& leaves) {
  for (int k : marked_list_) marked_[k] = 0;
  marked_list_.clear();
  for (int leaf : leaves) {
    for (int k = leaf; k >= 0 && !marked_[k]; k = parent_[k]) {
      marked_[k] = 1;
      marked_list_.push_back(k);
    }
  }
  // Children before parents, as refit goes.
  std::sort(marked_list_.begin(), marked_list_.end(), std::greater<int>());
}

void TriangleTree::refitMarked(const std::vector<unsigned>& tri, const Vec3Array& triangle_lo,
                               const Vec3Array& triangle_hi, const Vec3Array& x,
                               const Vec3Array& u) {
  for (int k : marked_list_) refitNode(k, tri, triangle_lo, triangle_hi, x, u);
}

void TriangleTree::refitNode(int k, const std::vector<unsigned>& tri, const Vec3Array& triangle_lo,
                             const Vec3Array& triangle_hi, const Vec3Array& x, const Vec3Array& u) {
  Node& n = nodes_[k];
  Cone cone;
  if (n.left < 0) {
    // A leaf's cone straight from its triangles' normal directions (no pairwise merging).
    Vec3 directions[3 * kLeafTriangles];
    int count = 0;
    bool defined = true;
    const int first = order_[n.first];
    n.lo = triangle_lo[first];
    n.hi = triangle_hi[first];
    for (int s = n.first; s < n.first + n.count; ++s) {
      const int t = order_[s];
      const unsigned a = tri[3 * t], b = tri[3 * t + 1], c = tri[3 * t + 2];
      n.lo = n.lo.cwiseMin(triangle_lo[t]);
      n.hi = n.hi.cwiseMax(triangle_hi[t]);
      if (defined) {
        defined = addNormalDirections(x[a], x[b], x[c], u[a], u[b], u[c], directions, count);
      }
    }
    if (defined) cone = coneOfDirections(directions, count);
  } else {
    const Node& l = nodes_[n.left];
    const Node& r = nodes_[n.right];
    n.lo = l.lo.cwiseMin(r.lo);
    n.hi = l.hi.cwiseMax(r.hi);
    cone = merge(coneOf(l), coneOf(r));
  }
  n.axis = cone.axis;
  n.cos_angle = cone.cos_angle;
  n.sin_angle = cone.sin_angle;
}

bool TriangleTree::share(const Node& a, const Node& b) const {
  const int* i = boundary_.data() + a.boundary_first;
  const int* i_end = i + a.boundary_count;
  const int* j = boundary_.data() + b.boundary_first;
  const int* j_end = j + b.boundary_count;
  while (i != i_end && j != j_end) {
    if (*i == *j) return true;
    if (*i < *j) {
      ++i;
    } else {
      ++j;
    }
  }
  return false;
}

bool TriangleTree::flatTogether(const Node& a, const Node& b, double cos_flat) const {
  if (a.cos_angle < cos_flat || b.cos_angle < cos_flat) return false;
  return merge(coneOf(a), coneOf(b)).cos_angle >= cos_flat;
}

}  // namespace pbd_cloth
