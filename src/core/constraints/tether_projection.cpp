#include "pbd_cloth/constraints/tether_projection.h"

#include <algorithm>
#include <cmath>

namespace pbd_cloth {
namespace {

// Below this length a tether has no direction: left alone (a particle on its anchor).
constexpr double kMinLength = 1e-12;

// A squared length decides a tether only this far from its bound; nearer, the square root is
// taken and the rounds' own test |d| - r > r * kTetherSlack decides, so a pass ends bit for bit
// where the general rounds would. 1e-9 is far above the rounding of either test (1e-16).
constexpr double kSquaredMargin = 1e-9;

// |d| (as Eigen's norm() computes it) when d may reach past r (1 + kTetherSlack): only a tether
// near or past its bound pays for the square root. False when it is clearly inside.
bool nearOrPast(const Vec3& d, double r, double& length) {
  const double bound = r * (1.0 + kTetherSlack);
  const double squared = d.squaredNorm();
  if (squared < bound * bound * (1.0 - kSquaredMargin)) return false;
  length = std::sqrt(squared);
  return true;
}

// The general rounds' test of a violated tether, |d| - r > r * kTetherSlack, with |d| from
// nearOrPast in `length`.
bool exceeds(const Vec3& d, double r, double& length) {
  return nearOrPast(d, r, length) && length - r > r * kTetherSlack;
}

// Whether |d| <= r * (1 + kTetherSlack), the lens's test that a projection lies in a ball, with
// the square root only next to the bound.
bool inside(const Vec3& d, double r) {
  const double bound = r * (1.0 + kTetherSlack);
  const double squared = d.squaredNorm();
  if (squared < bound * bound * (1.0 - kSquaredMargin)) return true;
  if (squared > bound * bound * (1.0 + kSquaredMargin)) return false;
  return std::sqrt(squared) <= bound;
}

// projectIntoBall's move for a particle already known to be at `length` from the anchor.
Vec3 ballPoint(const Vec3& x, const Vec3& d, double length, double r) {
  if (length <= r * (1.0 + kTetherSlack) || length < kMinLength) return x;
  return x - ((length - r) / length) * d;
}

// The reactions of addLensReactions with the anchor distances la and lb of x given.
void lensReactions(const Vec3& move, double mass, const Vec3& to_a, double la, const Vec3& to_b,
                   double lb, Vec3& reaction_a, Vec3& reaction_b) {
  if (la > kMinLength && lb > kMinLength) {
    const Vec3 na = to_a / la, nb = to_b / lb;
    const double c = na.dot(nb), det = 1.0 - c * c;
    if (det > 1e-6) {
      const double ra = -move.dot(na), rb = -move.dot(nb);
      reaction_a += (mass * (ra - c * rb) / det) * na;
      reaction_b += (mass * (rb - c * ra) / det) * nb;
      return;
    }
  }
  reaction_a -= 0.5 * mass * move;
  reaction_b -= 0.5 * mass * move;
}

// The nearest point of the lens for an x that neither ball's own point serves, from the anchors'
// axis (unit u from `first`, length `distance` >= kMinLength): on the circle where the spheres
// meet, or, for balls that do not meet, the point of the axis that splits the excess in
// proportion to the radii. Returns whether the point is on the circle (on both spheres).
bool lensPoint(Vec3& x, const Vec3& first, double r_first, double r_second, const Vec3& u,
               double distance) {
  if (distance >= r_first + r_second) {
    x = first + (r_first / (r_first + r_second) * distance) * u;
    return false;
  }
  const double t =
      (distance * distance + r_first * r_first - r_second * r_second) / (2.0 * distance);
  const double rho = std::sqrt(std::max(0.0, r_first * r_first - t * t));
  Vec3 radial = (x - first) - (x - first).dot(u) * u;
  const double radial_length = radial.norm();
  radial = radial_length > kMinLength ? Vec3(radial / radial_length) : u.unitOrthogonal();
  x = first + t * u + rho * radial;
  return true;
}

}  // namespace

double projectIntoBall(Vec3& x, const Vec3& a, double r) {
  const Vec3 delta = x - a;
  const double length = delta.norm();
  if (length <= r * (1.0 + kTetherSlack) || length < kMinLength) return 0.0;
  x -= ((length - r) / length) * delta;
  return length - r;
}

// When neither single-ball projection lies in the other ball, the nearest point is on the circle
// where the spheres meet: centre a + t u, radius sqrt(ra^2 - t^2), t = (D^2 + ra^2 - rb^2) / (2D).
// Balls that only touch (a particle of the top row between two pins at their rest distance) make
// that circle a point, where alternating projections would only creep towards it. Balls that do
// not meet (anchors pulled apart beyond the rest distance) have no feasible point: the particle
// then goes to the point of the axis that splits the excess in proportion to the radii.
double projectIntoLens(Vec3& x, const Vec3& a, double ra, const Vec3& b, double rb) {
  const Vec3 start = x;
  Vec3 pa = x, pb = x;
  projectIntoBall(pa, a, ra);
  projectIntoBall(pb, b, rb);
  const bool pa_in_b = (pa - b).norm() <= rb * (1.0 + kTetherSlack);
  const bool pb_in_a = (pb - a).norm() <= ra * (1.0 + kTetherSlack);
  if (pa_in_b || pb_in_a) {
    // Both candidates feasible: the nearer one (only possible when x is already inside both).
    x = (pa_in_b && (!pb_in_a || (pa - start).squaredNorm() <= (pb - start).squaredNorm())) ? pa
                                                                                            : pb;
    return (x - start).norm();
  }
  const Vec3 axis = b - a;
  const double distance = axis.norm();
  if (distance < kMinLength) return 0.0;  // coincident anchors of different radii: nothing to do
  lensPoint(x, a, ra, rb, axis / distance, distance);
  return (x - start).norm();
}

// At the nearest point of the lens the move is -(mu_a n_a + mu_b n_b), n the unit vectors from
// each anchor to x and mu >= 0 the two tethers' multipliers (the KKT condition), so solving that
// 2 x 2 system splits the momentum m (start - x) between the anchors. When n_a and n_b are
// (nearly) parallel the split is not determined by the geometry (anchors pulled apart beyond the
// rest distance): halves.
void addLensReactions(const Vec3& start, const Vec3& x, double mass, const Vec3& a, const Vec3& b,
                      Vec3& reaction_a, Vec3& reaction_b) {
  const Vec3 to_a = x - a, to_b = x - b;
  lensReactions(x - start, mass, to_a, to_a.norm(), to_b, to_b.norm(), reaction_a, reaction_b);
}

// One round of the general active set, step for step, reusing what it would compute twice: the
// distances to both anchors (for the most violated tether, then for that ball's projection and
// the other's), and the test of the first ball's point against the second ball (the round's check
// and the lens's are the same norm). Squared lengths decide the tests that are far from their
// bound. In the lens's circle, the common case of a cloth hanging from two pins, the particle ends
// on both spheres, so the reactions take the radii as its distances.
bool projectTetherPair(Vec3& x, double mass, const Vec3& a, double ra, const Vec3& b, double rb,
                       Vec3& reaction_a, Vec3& reaction_b, AnchorAxis& axis,
                       double& moved_squared) {
  moved_squared = 0.0;
  const Vec3 da = x - a, db = x - b;
  double la = 0.0, lb = 0.0;
  const bool near_a = nearOrPast(da, ra, la), near_b = nearOrPast(db, rb, lb);
  const bool out_a = near_a && la - ra > ra * kTetherSlack;
  const bool out_b = near_b && lb - rb > rb * kTetherSlack;
  if (!out_a && !out_b) return true;
  // The most violated first; a tie goes to the first listed, as in the rounds.
  const bool a_first = out_a && (!out_b || !(lb - rb > la - ra));
  const Vec3& first = a_first ? a : b;
  const Vec3& second = a_first ? b : a;
  const Vec3& d_first = a_first ? da : db;
  const Vec3& d_second = a_first ? db : da;
  const double r_first = a_first ? ra : rb, r_second = a_first ? rb : ra;
  const double l_first = a_first ? la : lb, l_second = a_first ? lb : la;
  const bool near_second = a_first ? near_b : near_a;
  Vec3& reaction_first = a_first ? reaction_a : reaction_b;
  Vec3& reaction_second = a_first ? reaction_b : reaction_a;

  const Vec3 start = x;
  const Vec3 p_first = ballPoint(x, d_first, l_first, r_first);
  double l_cross = 0.0;
  if (!exceeds(p_first - second, r_second, l_cross)) {
    // The first ball's point satisfies the second tether: only the first anchor pulls, and the
    // rounds stop here.
    reaction_first -= mass * (p_first - x);
    x = p_first;
    moved_squared = (x - start).squaredNorm();
    return true;
  }
  // projectIntoLens(x, first, r_first, second, r_second), with its two ball points and their
  // tests from the distances above.
  const bool first_in_second = l_cross <= r_second * (1.0 + kTetherSlack);
  const Vec3 p_second = near_second ? ballPoint(x, d_second, l_second, r_second) : x;
  const bool second_in_first = inside(p_second - first, r_first);
  if (first_in_second || second_in_first) {
    x = (first_in_second &&
         (!second_in_first || (p_first - start).squaredNorm() <= (p_second - start).squaredNorm()))
            ? p_first
            : p_second;
    addLensReactions(start, x, mass, first, second, reaction_first, reaction_second);
  } else {
    if (axis.from != &first || axis.to != &second) {
      // A run of particles tethered to the same two anchors in the same order shares this.
      axis.from = &first;
      axis.to = &second;
      axis.distance = (second - first).norm();
      axis.u = (second - first) / axis.distance;
    }
    if (axis.distance < kMinLength) return true;  // coincident anchors: every round leaves x
    if (lensPoint(x, first, r_first, r_second, axis.u, axis.distance)) {
      lensReactions(x - start, mass, x - first, r_first, x - second, r_second, reaction_first,
                    reaction_second);
    } else {
      addLensReactions(start, x, mass, first, second, reaction_first, reaction_second);
    }
  }
  moved_squared = (x - start).squaredNorm();
  // After a lens the rounds look once more; the lens's point is on or inside both spheres, so
  // that look finds nothing unless rounding of coordinates far larger than the radii put it past
  // the slack: then the caller goes on with the rounds.
  double unused = 0.0;
  return !exceeds(x - a, ra, unused) && !exceeds(x - b, rb, unused);
}

double projectTetherRounds(Vec3& x, double mass, const Tether* first, const Tether* last,
                           const Vec3Array& position, const std::vector<double>& inverse_mass,
                           Vec3Array& reaction, int first_round) {
  constexpr int kMaxRounds = 16;
  // The most violated tether at y, other than `skip`; nullptr when none is violated. Anchors no
  // longer kinematic (a released gripper, until the list is rebuilt) are ignored.
  auto worst = [&](const Vec3& y, const Tether* skip) {
    const Tether* found = nullptr;
    double largest = 0.0;
    for (const Tether* t = first; t != last; ++t) {
      if (t == skip || inverse_mass[t->anchor] != 0.0) continue;
      const double excess = (y - position[t->anchor]).norm() - t->max_length;
      if (excess > t->max_length * kTetherSlack && excess > largest) {
        largest = excess;
        found = t;
      }
    }
    return found;
  };
  double max_change = 0.0;
  for (int round = first_round; round < kMaxRounds; ++round) {
    const Tether* ta = worst(x, nullptr);
    if (ta == nullptr) break;
    Vec3 projected = x;
    const double moved = projectIntoBall(projected, position[ta->anchor], ta->max_length);
    const Tether* tb = worst(projected, ta);
    if (tb == nullptr) {
      // Only the particle moves: the anchor's reaction is the momentum it was given, reversed.
      reaction[ta->anchor] -= mass * (projected - x);
      x = projected;
      max_change = std::max(max_change, moved);
      break;
    }
    const Vec3 start = x;
    max_change = std::max(max_change, projectIntoLens(x, position[ta->anchor], ta->max_length,
                                                      position[tb->anchor], tb->max_length));
    addLensReactions(start, x, mass, position[ta->anchor], position[tb->anchor],
                     reaction[ta->anchor], reaction[tb->anchor]);
  }
  return max_change;
}

double projectTetherSingle(Vec3& x, double mass, const Vec3& a, double r, Vec3& reaction) {
  const Vec3 d = x - a;
  double length = 0.0;
  if (!exceeds(d, r, length)) return 0.0;
  const Vec3 projected = ballPoint(x, d, length, r);
  reaction -= mass * (projected - x);
  const double moved = (projected - x).squaredNorm();
  x = projected;
  return moved;
}

}  // namespace pbd_cloth
