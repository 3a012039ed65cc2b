// The two-tether shortcut (projectTetherPair) against the general rounds (projectTetherRounds) of
// Solver::projectTethers it replaces for a particle with two kinematic anchors: the same position
// to the bit on every kind of case (inside both balls, one ball violated, both, the lens's circle,
// touching and disjoint balls, coincident anchors, coordinates far larger than the radii), the
// reactions to rounding, and the result inside both balls wherever they meet.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <random>
#include <vector>

#include "pbd_cloth/constraints/tether_projection.h"

namespace pbd_cloth {
namespace {

struct Pair {
  Vec3 a, b;
  double ra = 0.0, rb = 0.0;
};

// The general rounds (projectTetherRounds, what Solver::projectTethers runs for any particle) for
// one particle with tethers to a and b (a listed first), from round `first_round` on.
void rounds(const Pair& pair, double mass, Vec3& x, Vec3& reaction_a, Vec3& reaction_b,
            int first_round) {
  const Vec3Array anchors = {pair.a, pair.b};
  const std::vector<double> inverse_mass = {0.0, 0.0};  // both kinematic
  const Tether tethers[2] = {{2, 0, pair.ra}, {2, 1, pair.rb}};
  Vec3Array reactions = {reaction_a, reaction_b};
  projectTetherRounds(x, mass, tethers, tethers + 2, anchors, inverse_mass, reactions, first_round);
  reaction_a = reactions[0];
  reaction_b = reactions[1];
}

// Anchors 0 to 1.6 (ra + rb) apart (disjoint balls from 1), the particle anywhere within 2.5 radii
// of either, some cases exactly on a sphere or an anchor, all shifted by `offset`.
struct Case {
  Pair pair;
  Vec3 x;
};
Case randomCase(std::mt19937& random, const Vec3& offset) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0), positive(0.05, 1.0);
  std::uniform_int_distribution<int> kind(0, 9);
  Case c;
  c.pair.ra = positive(random);
  c.pair.rb = kind(random) == 0 ? c.pair.ra : positive(random);
  const Vec3 direction = Vec3(unit(random), unit(random), unit(random)).normalized();
  const double distance = 0.8 * (1.0 + unit(random)) * (c.pair.ra + c.pair.rb);
  c.pair.a = offset + Vec3(unit(random), unit(random), unit(random));
  const int k = kind(random);
  // Coincident anchors; anchors exactly touching (a taut row between two pins).
  c.pair.b = k == 0 ? c.pair.a : c.pair.a + (k == 1 ? c.pair.ra + c.pair.rb : distance) * direction;
  const Vec3 around = kind(random) < 5 ? c.pair.a : c.pair.b;
  c.x = around +
        2.5 * std::max(c.pair.ra, c.pair.rb) * Vec3(unit(random), unit(random), unit(random));
  if (kind(random) == 0) c.x = c.pair.a + c.pair.ra * direction;  // on a's sphere
  if (kind(random) == 0) c.x = c.pair.b;                          // on b's anchor
  return c;
}

TEST(TetherProjection, PairShortcutMatchesTheRoundsToTheBit) {
  std::mt19937 random(12);
  const double mass = 0.01;
  int moved = 0, outside = 0;
  // Cases whose balls meet, and those of them that went on with the rounds, near the origin and
  // at 2e4 m. (Disjoint balls, anchors pulled apart, always do: the rounds repeat their axis
  // point, which is inside neither ball.)
  int meeting[2] = {0, 0}, needed_rounds[2] = {0, 0};  // per particle
  for (const Vec3& offset : {Vec3(0.0, 0.0, 0.0), Vec3(1e4, -2e4, 5e3)}) {
    const int far = offset.norm() > 0.0;
    for (int i = 0; i < 200000; ++i) {
      const Case c = randomCase(random, offset);
      const double gap = (c.pair.b - c.pair.a).norm();
      const bool balls_meet = gap > 1e-9 && gap < c.pair.ra + c.pair.rb;
      meeting[far] += 2 * balls_meet;
      // Two particles on the same anchors, the second reusing the axis the first computed (as a
      // run of particles of one cloth does); a new pair of anchors starts a new cache.
      AnchorAxis axis;
      const Vec3 second_start = c.x + 0.5 * (c.pair.b - c.x);
      for (const Vec3& start : {c.x, second_start}) {
        Vec3 expected = start, expected_ra = Vec3::Zero(), expected_rb = Vec3::Zero();
        rounds(c.pair, mass, expected, expected_ra, expected_rb, 0);

        Vec3 x = start, ra = Vec3::Zero(), rb = Vec3::Zero();
        double moved_squared = -1.0;
        const bool settled = projectTetherPair(x, mass, c.pair.a, c.pair.ra, c.pair.b, c.pair.rb,
                                               ra, rb, axis, moved_squared);
        EXPECT_EQ(moved_squared, (x - start).squaredNorm()) << "case " << i;
        if (!settled) {
          needed_rounds[far] += balls_meet;
          rounds(c.pair, mass, x, ra, rb, 1);  // what Solver::projectTethers does then
        }
        moved += x != start;
        ASSERT_TRUE(x.x() == expected.x() && x.y() == expected.y() && x.z() == expected.z())
            << "case " << i << " offset " << offset.transpose() << ": " << x.transpose()
            << " against the rounds' " << expected.transpose();
        // The reactions: the same split of the momentum, up to rounding. The shortcut takes
        // the radii as the distances on the lens's circle; the 2 x 2 split divides by 1 - cos^2
        // of the angle between the tethers, which magnifies that rounding as it does the
        // rounds' own, and coordinates far larger than the radii carry more of it.
        const double relative = 1e-10 * (1.0 + offset.norm() / std::min(c.pair.ra, c.pair.rb));
        const double size = expected_ra.norm() + expected_rb.norm() + mass * (x - start).norm();
        EXPECT_LE((ra - expected_ra).norm(), relative * size)
            << "case " << i << " offset " << offset.transpose();
        EXPECT_LE((rb - expected_rb).norm(), relative * size)
            << "case " << i << " offset " << offset.transpose();
        // Wherever the balls meet, the particle ends inside both (the rounds' promise).
        if (balls_meet) {
          const double tolerance = 1e-12 * (1.0 + offset.norm());
          const bool in = (x - c.pair.a).norm() <= c.pair.ra + tolerance &&
                          (x - c.pair.b).norm() <= c.pair.rb + tolerance;
          outside += !in;
        }
      }
    }
  }
  std::printf(
      "800000 particles: %d moved, %d outside a ball; of those whose balls meet, went on "
      "with the rounds: %d of %d near the origin, %d of %d with coordinates 2e4 times "
      "the radii\n",
      moved, outside, needed_rounds[0], meeting[0], needed_rounds[1], meeting[1]);
  EXPECT_GT(moved, 200000);  // the cases exercise the projection, not only satisfied tethers
  EXPECT_EQ(outside, 0);
  // Near the origin the shortcut's point is within rounding of both spheres, so it almost never
  // falls back on the rounds, which would cost what it saves. The few that do (18 of 208,150 here)
  // are a small ball barely inside a large one's reach, where the circle's centre t loses digits
  // to cancellation and the small sphere is missed by 1.5e-14 of its radius.
  EXPECT_LE(needed_rounds[0], meeting[0] / 10000);
}

TEST(TetherProjection, SingleShortcutMatchesTheBallToTheBit) {
  std::mt19937 random(5);
  std::uniform_real_distribution<double> unit(-1.0, 1.0), positive(0.05, 1.0);
  int moved = 0;
  for (int i = 0; i < 100000; ++i) {
    const Vec3 a(unit(random), unit(random), unit(random));
    const double r = positive(random);
    const Vec3 start = a + 2.0 * r * Vec3(unit(random), unit(random), unit(random));
    Vec3 expected = start;
    const double excess = (start - a).norm() - r;
    if (excess > r * kTetherSlack) projectIntoBall(expected, a, r);
    Vec3 x = start, reaction = Vec3::Zero();
    const double moved_squared = projectTetherSingle(x, 0.02, a, r, reaction);
    moved += x != start;
    ASSERT_TRUE(x.x() == expected.x() && x.y() == expected.y() && x.z() == expected.z())
        << "case " << i;
    EXPECT_EQ(moved_squared, (x - start).squaredNorm());
    EXPECT_TRUE(reaction.isApprox(-0.02 * (x - start)) || x == start) << "case " << i;
    EXPECT_LE((x - a).norm(), r * (1.0 + 1e-12)) << "case " << i;
  }
  EXPECT_GT(moved, 50000);
}

}  // namespace
}  // namespace pbd_cloth
