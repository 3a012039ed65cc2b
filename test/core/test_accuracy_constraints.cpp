// Accuracy of the constraint solve against answers that do not come from this code
// (../shared/REFERENCE_CASES.md, cases 4 to 7).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "accuracy_helpers.h"
#include "pbd_cloth/collision/collisions.h"
#include "pbd_cloth/sim/simulation.h"
#include "pbd_cloth/solver/solver.h"

namespace pbd_cloth {
namespace {

using test::kG;
using test::kPi;

// ---------------------------------------------------------------------------------------------
// Case 4: the hanging chain is a discrete catenary. N equal masses, N - 1 links of l = L/(N-1),
// ends pinned at the same height S apart. Each free node turns the tension by its weight, so the
// link slopes are tan(phi_i) = q (i - (N-2)/2), q = m g / H, and q solves
// sum_i l / sqrt(1 + tan^2 phi_i) = S (monotone in q: bisection).
struct Node {
  double x = 0.0;
  double z = 0.0;
};

std::vector<Node> discreteCatenary(int n, double span, double length, double* q_out = nullptr) {
  const double l = length / (n - 1), middle = (n - 2) / 2.0;
  auto width = [&](double q) {
    double w = 0.0;
    for (int i = 0; i < n - 1; ++i) {
      const double slope = q * (i - middle);
      w += l / std::sqrt(1.0 + slope * slope);
    }
    return w;
  };
  double lo = 0.0, hi = 1e6;  // width(0) = L > S, width(1e6) ~ 0 < S
  for (int k = 0; k < 200; ++k) {
    const double mid = 0.5 * (lo + hi);
    (width(mid) > span ? lo : hi) = mid;
  }
  const double q = 0.5 * (lo + hi);
  if (q_out != nullptr) *q_out = q;
  std::vector<Node> nodes{{0.0, 0.0}};
  for (int i = 0; i < n - 1; ++i) {
    const double slope = q * (i - middle), c = 1.0 / std::sqrt(1.0 + slope * slope);
    nodes.push_back({nodes.back().x + l * c, nodes.back().z + l * slope * c});
  }
  return nodes;
}

double sag(const std::vector<Node>& nodes) {
  double lowest = 0.0;
  for (const Node& node : nodes) lowest = std::min(lowest, node.z);
  return -lowest;
}

// The discrete solver itself, against the continuous check values (S = 1, L = 2: a = 0.2296402,
// sag 0.7963884): the discrete chain tends to the cosh curve as N grows, with a = H / (rho g)
// = l / q. At N = 20 it differs by O(N^-2), which is why case 4 compares with the discrete answer.
TEST(AccuracyCatenary, DiscreteAnswerTendsToContinuousCatenary) {
  const int n = 4001;
  double q = 0.0;
  const std::vector<Node> fine = discreteCatenary(n, 1.0, 2.0, &q);
  EXPECT_NEAR(sag(fine), 0.7963884, 1e-6);
  EXPECT_NEAR((2.0 / (n - 1)) / q, 0.2296402, 1e-6);
  EXPECT_NEAR(fine.back().x, 1.0, 1e-12);
  EXPECT_NEAR(fine.back().z, 0.0, 1e-12);
  const double coarse = sag(discreteCatenary(20, 1.0, 2.0));
  std::printf(
      "discrete sag N = 20: %.7f, N = %d: %.7f (continuous 0.7963884); N = 20 is %.3f %% "
      "below the cosh curve\n",
      coarse, n, sag(fine), 100.0 * (1.0 - coarse / 0.7963884));
}

// The simulated chain settles on the discrete answer. XPBD (alpha = 0) at 60 Hz x 20 substeps x
// 20 passes, damping 5 1/s, 10 s from a V-shaped start of the right link lengths.
TEST(AccuracyCatenary, HangingChainMatchesDiscreteCatenary) {
  const int n = 20;
  const double span = 1.0, length = 2.0, l = length / (n - 1);
  const std::vector<Node> exact = discreteCatenary(n, span, length);
  const double h = sag(exact);

  SceneConfig scene = test::clothScene(1, n, l, Method::kXpbd);
  scene.cloth.pinned = {0, n - 1};
  scene.solver.substeps = 20;
  scene.solver.iterations = 20;
  scene.solver.damping = 5.0;
  Simulation sim(scene);
  // Start as a V: 9 links down at angle acos(c), one level link, 9 links up; ends 1 m apart.
  Particles& p = sim.mutableParticles();
  const double c = (span - l) / (18.0 * l), s = std::sqrt(1.0 - c * c);
  Vec3 x = p.position[0];
  for (int i = 0; i < n; ++i) {
    p.position[i] = x;
    x += l * (i < 9 ? Vec3(c, 0.0, -s) : i == 9 ? Vec3(1.0, 0.0, 0.0) : Vec3(c, 0.0, s));
  }
  ASSERT_NEAR(p.position[n - 1].x() - p.position[0].x(), span, 1e-12);
  for (int k = 0; k < 600; ++k) sim.step();

  double deviation = 0.0;
  for (int i = 0; i < n; ++i) {
    const Vec3 r = p.position[i] - p.position[0];
    deviation = std::max(deviation, std::hypot(r.x() - exact[i].x, r.z() - exact[i].z));
  }
  const Metrics metrics = sim.computeMetrics();
  std::printf(
      "catenary N = 20: sag %.7f, max node deviation %.2e h (limit 1e-4), max strain %.2e "
      "(limit 1e-4)\n",
      h, deviation / h, metrics.max_strain);
  EXPECT_LT(deviation, 1e-4 * h);
  EXPECT_LT(metrics.max_strain, 1e-4);
}

// ---------------------------------------------------------------------------------------------
// Case 5: a heavy mass at the end of a light inextensible chain (Macklin et al. 2019, "Small
// Steps in Physics Simulation"): 20 particles of 1 kg, 0.01 m links, top pinned, the bottom
// particle 1 to 1e5 kg (cloth.point_masses). The exact drop of the bottom particle below its rest
// position is 0; the error is the mean drop over a 5 s run at 60 Hz. Equal cost: N substeps x 1
// pass against 1 substep x N passes. Gauss-Seidel corrects the error of one pass only by a factor
// that tends to 1 as the mass ratio grows, while a substep cuts the error at its source (g h^2),
// so substeps must win at every ratio and by a large factor at 1e3 and beyond.
double heavyEndDrop(double ratio, int substeps, int iterations) {
  SceneConfig scene = test::hangingRope(20, 0.01, Method::kXpbd);
  scene.cloth.point_masses = {{19, ratio}};
  scene.solver.substeps = substeps;
  scene.solver.iterations = iterations;
  Simulation sim(scene);
  EXPECT_DOUBLE_EQ(sim.particles().mass[19], ratio);
  const double rest = sim.particles().position[19].z();
  const int steps = 300;
  double mean = 0.0;
  for (int k = 0; k < steps; ++k) {
    sim.step();
    mean += (rest - sim.particles().position[19].z()) / steps;
  }
  return mean;
}

TEST(AccuracyHeavyEnd, SubstepsBeatIterationsAtEqualCost) {
  for (int passes : {20, 100}) {
    for (double ratio : {1.0, 10.0, 1e2, 1e3, 1e5}) {
      const double substeps = heavyEndDrop(ratio, passes, 1);
      const double iterations = heavyEndDrop(ratio, 1, passes);
      std::printf(
          "heavy end 1:%-6g %3d passes: drop %.3e m with substeps, %.3e m with "
          "iterations, ratio %.1f\n",
          ratio, passes, substeps, iterations, iterations / substeps);
      EXPECT_LT(substeps, iterations) << ratio << " " << passes;
      if (passes == 100) {
        // The paper's 100/100 figure is ~100x at 1e5 (322 m vs 3.2 m over a longer run).
        EXPECT_GT(iterations / substeps, ratio >= 1e3 ? 50.0 : 10.0) << ratio;
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Case 6: XPBD stiffness independence (Macklin, Mueller, Chentanez 2016). A hanging chain of 5
// particles of 1 kg, 0.1 m links, compliance alpha = 1e-4 m/N: link j carries the weight of the
// 4 - j particles below it, T_j = (4 - j) m g, and must stretch by alpha T_j whatever dt and the
// pass count, once the passes converge. Damping (5 1/s over 4 s) removes the bounce and, acting
// only on the carried velocity, does not change the static stretch.
std::vector<double> chainStretch(double step_rate, int substeps, int iterations, Ordering ordering,
                                 Method method, double pbd_stiffness = 1.0) {
  SceneConfig scene = test::hangingRope(5, 0.1, method);
  scene.step_rate = step_rate;
  scene.publish_rate = step_rate;
  scene.solver.substeps = substeps;
  scene.solver.iterations = iterations;
  scene.solver.ordering = ordering;
  scene.solver.damping = 5.0;
  scene.solver.stretch_stiffness = pbd_stiffness;
  scene.cloth.stretch_compliance = 1e-4;
  Simulation sim(scene);
  const int steps = static_cast<int>(4.0 * step_rate);
  for (int k = 0; k < steps; ++k) sim.step();
  std::vector<double> stretch;
  for (int j = 0; j < 4; ++j) {
    stretch.push_back((sim.particles().position[j] - sim.particles().position[j + 1]).norm() - 0.1);
  }
  return stretch;
}

TEST(AccuracyXpbd, ConvergedStretchIsComplianceTimesTension) {
  const double alpha = 1e-4;
  const struct {
    double rate;
    int substeps, iterations;
    Ordering ordering;
  } settings[] = {
      {30.0, 1, 50, Ordering::kGaussSeidel},  {60.0, 1, 20, Ordering::kGaussSeidel},
      {60.0, 1, 200, Ordering::kGaussSeidel}, {240.0, 1, 20, Ordering::kGaussSeidel},
      {60.0, 100, 1, Ordering::kGaussSeidel}, {30.0, 1, 1000, Ordering::kJacobi},
      {60.0, 1, 200, Ordering::kJacobi},      {240.0, 1, 50, Ordering::kJacobi},
  };
  for (const auto& s : settings) {
    const std::vector<double> stretch =
        chainStretch(s.rate, s.substeps, s.iterations, s.ordering, Method::kXpbd);
    std::printf("xpbd %-12s %5.0f Hz x %3d substeps x %4d passes: stretch / (alpha T) =",
                toString(s.ordering), s.rate, s.substeps, s.iterations);
    for (int j = 0; j < 4; ++j) {
      const double expected = alpha * (4 - j) * kG;
      std::printf(" %.5f", stretch[j] / expected);
      EXPECT_NEAR(stretch[j], expected, 0.01 * expected)
          << toString(s.ordering) << " " << s.rate << " Hz " << s.substeps << "x" << s.iterations
          << " link " << j;
    }
    std::printf("\n");
  }
}

// Plain PBD (stiffness k = 0.5, corrected to k' = 1 - (1 - k)^(1/n), Mueller et al. 2007 sec. 3.3)
// has no such limit: at rest every substep pulls each particle down by g h^2 and the projection
// takes back only part of it, so the stretch scales with h^2 (x4 from 60 to 30 Hz) and, in a
// chain, changes with the pass count.
TEST(AccuracyXpbd, PbdStretchDependsOnTimeStepAndIterations) {
  const auto slow = chainStretch(30.0, 1, 1, Ordering::kGaussSeidel, Method::kPbd, 0.5);
  const auto fast = chainStretch(60.0, 1, 1, Ordering::kGaussSeidel, Method::kPbd, 0.5);
  const auto more = chainStretch(60.0, 1, 10, Ordering::kGaussSeidel, Method::kPbd, 0.5);
  std::printf(
      "pbd k = 0.5, top link stretch: 30 Hz %.3e m, 60 Hz %.3e m, 60 Hz x 10 passes %.3e "
      "m; bottom link %.3e, %.3e, %.3e m\n",
      slow[0], fast[0], more[0], slow[3], fast[3], more[3]);
  double largest_change = 0.0;
  for (int j = 0; j < 4; ++j) {
    EXPECT_NEAR(slow[j] / fast[j], 4.0, 0.1) << "link " << j;  // ~ h^2
    // XPBD converged changes by < 1 % (above); PBD by 6 to 40 % per link from 1 to 10 passes.
    const double change = std::abs(more[j] / fast[j] - 1.0);
    EXPECT_GT(change, 0.05) << "link " << j;
    largest_change = std::max(largest_change, change);
  }
  EXPECT_GT(largest_change, 0.2);
}

// The spring test of the XPBD paper, sec. 6.1: rest length 1, start at 1.5, alpha = 0.001 m/N,
// m = 1 kg, one end fixed, no gravity. For one linear constraint a converged XPBD step is implicit
// Euler, whose step map has eigenvalues 1 / (1 -+ i w h), w = sqrt(1 / (m alpha)): amplitude
// factor 1 / sqrt(1 + (w h)^2) = 0.88465 per 60 Hz step and period 2 pi h / atan(w h) = 0.215895 s
// (exact: 2 pi / w = 0.198692 s). The sampled stretch obeys a two-term recurrence whose fitted
// roots give both figures without interpolation error.
std::pair<double, double> springPeriodAndDecay(int substeps, int iterations) {
  SceneConfig scene = test::clothScene(1, 2, 1.0, Method::kXpbd);
  scene.cloth.pinned = {0};
  scene.cloth.stretch_compliance = 0.001;
  scene.solver.gravity.setZero();
  scene.solver.substeps = substeps;
  scene.solver.iterations = iterations;
  Simulation sim(scene);
  sim.mutableParticles().position[1].x() = 1.5;
  std::vector<double> stretch{0.5};
  for (int k = 0; k < 40; ++k) {
    sim.step();
    stretch.push_back(sim.particles().position[1].x() - 1.0);
  }
  const auto [r, phi] = test::fitRecurrence(stretch);
  return {2.0 * kPi / (60.0 * phi), r};
}

TEST(AccuracyXpbd, SpringPeriodIsImplicitEulerAndConvergesWithSubsteps) {
  const double w = std::sqrt(1000.0), h = 1.0 / 60.0;
  ASSERT_NEAR(2.0 * kPi * h / std::atan(w * h), 0.215895, 1e-6);  // the reference figures
  ASSERT_NEAR(1.0 / std::sqrt(1.0 + w * w * h * h), 0.88465, 1e-5);
  for (int iterations : {1, 5}) {
    const auto [period, decay] = springPeriodAndDecay(1, iterations);
    std::printf(
        "xpbd spring 60 Hz, %d pass(es): period %.6f s (reference 0.215895), amplitude "
        "x%.5f per step (reference 0.88465)\n",
        iterations, period, decay);
    EXPECT_NEAR(period, 0.215895, 1e-6);
    EXPECT_NEAR(decay, 0.88465, 1e-5);
  }
  double previous_error = 1.0;
  for (int substeps : {1, 10, 100}) {
    const auto [period, decay] = springPeriodAndDecay(substeps, 1);
    const double error = period / 0.198692 - 1.0;
    std::printf(
        "xpbd spring 60 Hz x %3d substeps: period %.6f s (exact 0.198692, error %.4f %%), "
        "amplitude x%.5f per step\n",
        substeps, period, 100.0 * error, decay);
    EXPECT_LT(error, previous_error);  // implicit Euler lengthens the period: error > 0, shrinking
    EXPECT_GT(error, 0.0);
    previous_error = error;
  }
  EXPECT_LT(previous_error, 1e-4);  // 100 substeps: within 0.01 % of 2 pi / w
}

// ---------------------------------------------------------------------------------------------
// Case 7: Jacobi needs averaging. One free particle between anchors at -l and +l with K identical
// distance constraints of rest length l (alternately to either anchor; each asks for the same
// correction -d), displaced by d. Built directly from Particles, ClothTopology and Solver: a scene
// file cannot duplicate constraints.
struct JacobiRig {
  Particles particles;
  ClothTopology topology;
  Collisions collisions;
  Solver solver;
};

void buildJacobiRig(JacobiRig& rig, int k, double d, Ordering ordering, bool averaging,
                    double relaxation, int passes) {
  const double l = 1.0;
  Particles& p = rig.particles;
  p.resize(3);
  p.cloth_count = 3;
  p.position = {Vec3(-l, 0.0, 0.0), Vec3(d, 0.0, 0.0), Vec3(l, 0.0, 0.0)};
  p.mass = {1.0, 1.0, 1.0};
  p.inverse_mass = {0.0, 1.0, 0.0};
  p.radius = {0.01, 0.01, 0.01};
  p.kinematic_from = p.kinematic_to = p.substep_start = p.step_start = p.position;
  rig.topology = ClothTopology();
  rig.topology.rows = 1;
  rig.topology.cols = 3;
  for (int c = 0; c < k; ++c) rig.topology.stretch.push_back({1, c % 2 == 0 ? 0 : 2, l});
  rig.topology.structural_count = k;

  SceneConfig scene;
  scene.cloth.bend_compliance = -1.0;
  scene.cloth.stretch_compliance = 0.0;
  scene.cloth.self_collision = false;
  scene.solver.method = Method::kXpbd;
  scene.solver.substeps = 1;
  scene.solver.iterations = passes;
  scene.solver.gravity.setZero();
  scene.solver.ordering = ordering;
  scene.solver.jacobi_averaging = averaging;
  scene.solver.relaxation = relaxation;
  rig.collisions.configure(collisionSettings(scene));
  rig.solver.configure(scene.solver, clothMaterial(scene.cloth));
  rig.solver.prepare(p, rig.topology);
  rig.collisions.prepare(p, rig.topology);
}

// Position of the free particle after `passes` passes of one step (the velocity update comes
// after the passes, so it does not enter).
double jacobiAfter(int k, double d, Ordering ordering, bool averaging, double relaxation,
                   int passes) {
  JacobiRig rig;
  buildJacobiRig(rig, k, d, ordering, averaging, relaxation, passes);
  rig.solver.step(1.0 / 60.0, rig.particles, rig.topology, rig.collisions);
  EXPECT_EQ(rig.particles.position[1].y(), 0.0);
  return rig.particles.position[1].x();
}

TEST(AccuracyJacobi, PlainJacobiOvershootsByConstraintCount) {
  const double d = 1e-3;
  // x <- (1 - K) d per pass. K = 2: +-d forever.
  for (int passes = 1; passes <= 40; ++passes) {
    const double expected = (passes % 2 == 1 ? -d : d);
    EXPECT_NEAR(jacobiAfter(2, d, Ordering::kJacobi, false, 1.0, passes), expected, 1e-12 * d)
        << passes;
  }
  // K >= 3 diverges: (1 - K)^n d, while |x| stays below l (the anchors' geometry holds).
  for (int k = 3; k <= 5; ++k) {
    for (int passes = 1; std::pow(k - 1.0, passes) * d < 0.5; ++passes) {
      const double expected = std::pow(1.0 - k, passes) * d;
      EXPECT_NEAR(jacobiAfter(k, d, Ordering::kJacobi, false, 1.0, passes), expected,
                  1e-9 * std::abs(expected))
          << "K " << k << " passes " << passes;
    }
  }
  std::printf(
      "plain Jacobi: K = 2 after 40 passes %+.3e (d = 1e-3), K = 3 after 8 passes %+.4e "
      "(reference (-2)^8 d = 0.256)\n",
      jacobiAfter(2, d, Ordering::kJacobi, false, 1.0, 40),
      jacobiAfter(3, d, Ordering::kJacobi, false, 1.0, 8));
}

TEST(AccuracyJacobi, AveragingWithRelaxationConvergesAsOneMinusWToTheN) {
  const double d = 1e-3;
  for (int k = 2; k <= 5; ++k) {
    for (double w : {0.5, 1.0, 1.5, 1.9}) {
      for (int passes : {1, 2, 5, 10, 20}) {
        const double expected = std::pow(1.0 - w, passes) * d;
        EXPECT_NEAR(jacobiAfter(k, d, Ordering::kJacobi, true, w, passes), expected,
                    1e-12 * d + 1e-9 * std::abs(expected))
            << "K " << k << " w " << w << " passes " << passes;
      }
    }
  }
  std::printf(
      "averaged Jacobi K = 3: w = 0.5 after 20 passes %.3e (reference 0.5^20 d = %.3e), "
      "w = 1.9 %.3e (reference %.3e)\n",
      jacobiAfter(3, d, Ordering::kJacobi, true, 0.5, 20), std::pow(0.5, 20) * d,
      jacobiAfter(3, d, Ordering::kJacobi, true, 1.9, 20), std::pow(-0.9, 20) * d);
}

TEST(AccuracyJacobi, GaussSeidelConvergesInOnePass) {
  for (int k = 2; k <= 5; ++k) {
    EXPECT_NEAR(jacobiAfter(k, 1e-3, Ordering::kGaussSeidel, false, 1.0, 1), 0.0, 1e-15) << k;
  }
}

}  // namespace
}  // namespace pbd_cloth
