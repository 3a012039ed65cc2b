// The projections of long-range attachments (tethers, Kim et al. 2012): a free particle must stay
// inside the ball of radius max_length around each of its anchors. Only the particle moves; what
// an anchor would feel is returned as a reaction (the momentum it gave the particle, reversed).
#pragma once

#include <vector>

#include "pbd_cloth/model/particles.h"

namespace pbd_cloth {

// A tether counts as satisfied up to this relative excess: the rounding of a projection onto its
// own sphere, so a satisfied tether is not projected again and again.
constexpr double kTetherSlack = 1e-14;

// Projection of x onto the ball |x - a| <= r. Returns the distance moved.
double projectIntoBall(Vec3& x, const Vec3& a, double r);

// Nearest point of the lens |x - a| <= ra, |x - b| <= rb, for an x that a's ball alone does not
// take into b's (the general rounds, projectTetherRounds). Returns the distance moved.
double projectIntoLens(Vec3& x, const Vec3& a, double ra, const Vec3& b, double rb);

// The reactions on the two anchors of a lens projection from `start` to `x` (particle mass
// `mass`), added to reaction_a and reaction_b.
void addLensReactions(const Vec3& start, const Vec3& x, double mass, const Vec3& a, const Vec3& b,
                      Vec3& reaction_a, Vec3& reaction_b);

// The general rounds for one particle's tethers [first, last) (Solver::projectTethers), from round
// `first_round` (of at most 16): a = the most violated tether; if the projection into a's ball
// violates another, b = the worst of those, and the particle goes to the nearest point of the
// lens of a and b. Anchors whose inverse mass is not 0 are ignored. `x` may be the particle's own
// entry of `position` (never an anchor's). Returns the largest distance moved.
double projectTetherRounds(Vec3& x, double mass, const Tether* first, const Tether* last,
                           const Vec3Array& position, const std::vector<double>& inverse_mass,
                           Vec3Array& reaction, int first_round);

// The unit vector and distance from one anchor to another, for the lens's circle: the same for
// every particle tethered to those two (a cloth hung from two pins: all of them), so computed
// once for a run of such particles. Valid while the anchors' positions do not change (one
// Solver::projectTethers call); `from` and `to` are the addresses of the anchor positions it was
// computed for. A default one matches nothing.
struct AnchorAxis {
  const Vec3* from = nullptr;
  const Vec3* to = nullptr;
  Vec3 u = Vec3::Zero();
  double distance = 0.0;
};

// A particle with exactly two tethers, to a (radius ra, listed first) and b (rb), both anchors
// kinematic: the first round of the general active set (the most violated ball, then the lens of
// both) to the bit, with far fewer square roots and divisions in the chain each particle waits on
// (about 16 square roots and 12 divisions a particle before, 4 and 3 now, and the anchors' axis
// once for a run of particles: the whole cost of a tethered cloth's pass). moved_squared: the
// squared distance moved. Returns false when the rounds must go on (a lens's point past a sphere by
// more than the slack).
bool projectTetherPair(Vec3& x, double mass, const Vec3& a, double ra, const Vec3& b, double rb,
                       Vec3& reaction_a, Vec3& reaction_b, AnchorAxis& axis, double& moved_squared);

// A particle with one tether: projectIntoBall without a square root while it is satisfied.
// Returns the squared distance moved.
double projectTetherSingle(Vec3& x, double mass, const Vec3& a, double r, Vec3& reaction);

}  // namespace pbd_cloth
