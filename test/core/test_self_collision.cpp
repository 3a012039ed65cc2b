// Vertex-triangle self-collision (collision seed, eq. vertex_triangle_constraint) with the side the
// vertex was on respected: REFERENCE_CASES.md case 14, a cloth folded onto itself by two grippers
// and a cloth dropped onto a thin rod, with the edge-triangle intersections counted every frame.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <set>
#include <string>

#include "collision_scenes.h"
#include "pbd_cloth/scene/scene_yaml.h"
#include "pbd_cloth/sim/mesh_cloth.h"
#include "pbd_cloth/sim/metrics.h"
#include "pbd_cloth/sim/simulation.h"

namespace pbd_cloth {
namespace {

const std::string kSourceDirectory = PBD_CLOTH_SOURCE_DIR;

Waypoint waypoint(double t, const Vec3& position, int grasp = -1) {
  Waypoint w;
  w.t = t;
  w.pose = test::makePose(position);
  w.grasp = grasp;
  return w;
}

// A 16 x 16 cloth (0.3 m square) held at its two top corners by grippers; the right gripper
// carries its corner along a half circle (radius half the side, about the middle of the top edge)
// to 1 cm in front of the left one: the cloth folds in half onto itself, the two halves hanging
// face to face while they swing.
SceneConfig foldScene(bool self_collision) {
  const int n = 16;
  const double spacing = 0.02, h = 0.004, side = (n - 1) * spacing, top = 0.5;
  SceneConfig scene = test::clothScene(n, n, spacing, Method::kXpbd);
  scene.solver.substeps = 20;
  scene.cloth.mass = 0.05;
  scene.cloth.thickness = h;
  scene.cloth.bend_compliance = 10.0;
  scene.cloth.self_collision = self_collision;
  scene.cloth.rpy = Vec3(test::kPiValue / 2.0, 0.0, 0.0);  // hangs in the x-z plane
  scene.cloth.origin = Vec3(0.0, 0.0, top);
  GripperConfig left, right;
  left.name = "left";
  right.name = "right";
  left.radius = right.radius = 0.5 * spacing;
  left.trajectory = {waypoint(0.0, Vec3(0.0, 0.0, top), 1)};
  right.trajectory = {waypoint(0.0, Vec3(side, 0.0, top), 1)};
  for (int k = 1; k <= 8; ++k) {
    const double angle = test::kPiValue * k / 8.0;
    const double y = k < 8 ? 0.5 * side * std::sin(angle) : 0.01;
    right.trajectory.push_back(
        waypoint(0.3 * k, Vec3(0.5 * side * (1.0 + std::cos(angle)), y, top)));
  }
  scene.grippers = {left, right};
  return scene;
}

// Case 14a: zero edge-triangle intersections in every frame of the fold and of the swinging
// after it, and the fold happened: the right top corner hangs 1 cm in front of the left one.
// With the adaptive search window (the default) and with a search every substep and every 4.
class FoldWithSearchWindow : public ::testing::TestWithParam<int> {};

TEST_P(FoldWithSearchWindow, NeverIntersects) {
  SceneConfig scene = foldScene(true);
  scene.solver.search_window = GetParam();
  Simulation sim(scene);
  ASSERT_EQ(sim.grippers().count(), 2);
  int worst = 0, worst_step = -1, truncated = 0;
  double deepest = 0.0;
  for (int k = 0; k < 240; ++k) {
    sim.step();
    truncated += sim.collisions().stats().truncated_searches;
    const int count = countSelfIntersections(sim.particles(), sim.topology());
    if (count > worst) {
      worst = count;
      worst_step = k;
    }
    deepest = std::max(deepest, sim.stats().max_penetration);
  }
  const Particles& p = sim.particles();
  const double h = 0.004;
  std::printf("fold: max self-intersections %d (step %d), max penetration %.2e m\n", worst,
              worst_step, deepest);
  EXPECT_EQ(worst, 0);
  EXPECT_EQ(truncated, 0);  // a fold is far from the search's budget (CrushedCloth... below)
  EXPECT_TRUE(sim.computeMetrics().finite);
  EXPECT_LT((p.position[15] - Vec3(0.0, 0.01, 0.5)).norm(), 1e-9);  // held by the right gripper
  EXPECT_LT((p.position[0] - Vec3(0.0, 0.0, 0.5)).norm(), 1e-9);
  // Layers that swing into each other at up to ~3 m/s are stopped within a few substeps (at most
  // h / 2 per pass, self_collision.cpp), never through: the deepest approach stays below h.
  EXPECT_LT(deepest, h);
}

INSTANTIATE_TEST_SUITE_P(SelfCollision, FoldWithSearchWindow, ::testing::Values(0, 1, 4));

// solver.threads splits the stretch links, hinges and obstacle contacts around the self-contacts
// (whose searches, whole and local, run on the calling thread): the fold ends in the same
// positions, bit for bit, with 1, 2 and 3 threads. The runs start from the fold's state at
// 2.5 s (step 150), just before its layers meet (the paths' cull lists no pair before that), and
// run through the contact. (A race shows here only now and then; scripts/run_thread_sanitizer
// runs this test under ThreadSanitizer, which sees it every time.)
TEST(SelfCollision, EveryThreadCountFindsTheSamePairs) {
  SimulationState before_contact;
  {
    Simulation sim(foldScene(true));
    for (int k = 0; k < 150; ++k) sim.step();
    sim.getState(before_contact);
  }
  std::vector<Vec3Array> ends;
  for (int threads : {1, 2, 3}) {
    SceneConfig scene = foldScene(true);
    scene.solver.threads = threads;
    Simulation sim(scene);
    std::string reason;
    ASSERT_TRUE(sim.setState(before_contact, reason)) << reason;
    int most_pairs = 0, most_runs = 0;
    for (int k = 0; k < 60; ++k) {
      sim.step();
      most_pairs = std::max(most_pairs, sim.collisions().stats().vertex_triangle_pairs);
      most_runs = std::max(most_runs, sim.collisions().stats().broad_phase_runs +
                                          sim.collisions().stats().local_searches);
    }
    EXPECT_GT(most_pairs, 0);  // the fold brings the layers together
    EXPECT_GT(most_runs, 1);   // and the search runs again within a step (locally, here)
    ends.push_back(sim.particles().position);
    EXPECT_EQ(ends.back(), ends.front()) << threads << " threads";
  }
}

// Without self-collision the same fold lets the halves pass through each other: the count can
// fail.
TEST(SelfCollision, FoldWithoutSelfCollisionIntersects) {
  Simulation sim(foldScene(false));
  int worst = 0;
  for (int k = 0; k < 240; ++k) {
    sim.step();
    worst = std::max(worst, countSelfIntersections(sim.particles(), sim.topology()));
  }
  std::printf("fold without self-collision: max self-intersections %d\n", worst);
  EXPECT_GT(worst, 0);
}

// Case 14b: a cloth dropped onto a thin rod (capsule of 1 cm radius, a thirtieth of the cloth)
// folds over it; the two halves hang against each other. Zero intersections every frame, no
// particle inside the rod. (Contact with obstacles is per particle: a rod thinner than the gap
// between two particles, spacing - 2 (radius + h) here, lets the cloth through between them.)
SceneConfig rodScene() {
  const int n = 16;
  const double spacing = 0.02, h = 0.004;
  SceneConfig scene = test::clothScene(n, n, spacing, Method::kXpbd);
  scene.solver.substeps = 20;
  scene.cloth.mass = 0.05;
  scene.cloth.thickness = h;
  scene.cloth.bend_compliance = 100.0;
  scene.cloth.self_collision = true;
  // Centred over the rod, which runs along y at z = 0.
  scene.cloth.origin = Vec3(-0.5 * (n - 1) * spacing, 0.5 * (n - 1) * spacing, 0.1);
  const Eigen::Quaterniond along_y(Eigen::AngleAxisd(test::kPiValue / 2.0, Vec3::UnitX()));
  scene.obstacles = {test::capsule("rod", 0.01, 0.6, test::makePose(Vec3::Zero(), along_y))};
  return scene;
}

TEST(SelfCollision, DropOntoThinRodNeverIntersects) {
  const int n = 16;
  const double h = 0.004;
  const SceneConfig scene = rodScene();
  Simulation sim(scene);
  int worst = 0;
  double deepest = 0.0;
  for (int k = 0; k < 180; ++k) {
    sim.step();
    worst = std::max(worst, countSelfIntersections(sim.particles(), sim.topology()));
    deepest = std::max(deepest, test::obstaclePenetration(sim));
  }
  const Particles& p = sim.particles();
  double lowest = 1.0;
  for (const Vec3& x : p.position) lowest = std::min(lowest, x.z());
  std::printf(
      "rod: max self-intersections %d, deepest in rod %.2e m, lowest point %.3f m, max "
      "penetration %.2e m\n",
      worst, deepest, lowest, sim.stats().max_penetration);
  EXPECT_EQ(worst, 0);
  EXPECT_LT(deepest, 0.01 * h);
  // It folds over the rod (its halves, 0.15 m, bend down on both sides) and stays on it.
  EXPECT_LT(lowest, -0.04);
  EXPECT_GT(lowest, -0.16);
  EXPECT_TRUE(sim.computeMetrics().finite);
}

// A cloth crushed into itself, as a gripper squeezing it into its fist would: every particle
// within 0.1 mm of one point, the two pinned corners held there (set with setState, so their
// targets are there too). Every vertex is within the thickness of every triangle, about 50,000
// candidates for this 10 x 10 cloth (a 32 x 32 cloth crushed so took 50 s a step). The search
// stops at its budget (SelfCollision::kPairsPerElement per triangle and edge) and says so in the
// stats; the budget is what it lists at most (one search's edge-edge pairs and one's
// vertex-triangle pairs, each over by at most a leaf pair's candidates: 16 triangle pairs, 96
// vertex-triangle and 144 edge-edge candidates). With the pinned corners crushed together, a
// pinned vertex touches triangles at the other pin, whose free corners have barycentric
// coefficients near 0: moved by the correction over the coefficient, they were thrown at 800 to
// 14,000 m/s (and fault recovery then undid every step, for good), until no particle of a pair
// moved by more than kMaxLeverage times its correction (self_collision.cpp). What is left is the
// stretch links pulling the cloth out of the crush, as fast without self-collision (24 m/s at
// most over these steps): the test allows 50 m/s. Before the crush the same cloth is far from
// the budget.
TEST(SelfCollision, CrushedClothStopsEachSearchAtItsBudget) {
  SceneConfig scene = test::clothScene(10, 10, 0.05, Method::kXpbd);
  scene.cloth.self_collision = true;
  scene.cloth.thickness = 0.005;
  scene.cloth.pinned = {0, 9};
  scene.solver.substeps = 10;
  Simulation sim(scene);
  for (int k = 0; k < 12; ++k) {
    sim.step();
    ASSERT_EQ(sim.collisions().stats().truncated_searches, 0) << "the swinging cloth, step " << k;
  }
  const int triangles = sim.topology().triangleCount();
  const int edges = 3 * 9 * 9 + 2 * 9;  // rows, columns and one diagonal per cell
  const int budget = SelfCollision::kPairsPerElement * (triangles + edges);
  SimulationState crushed;
  sim.getState(crushed);
  for (std::size_t i = 0; i < crushed.position.size(); ++i) {
    const double k = static_cast<double>(i);
    crushed.position[i] =
        Vec3(0.2, -0.2, 0.8) +
        1e-4 * Vec3(std::fmod(k, 7.0) / 7.0, std::fmod(k, 5.0) / 5.0, std::fmod(k, 3.0) / 3.0);
    crushed.velocity[i].setZero();
  }
  crushed.substep_start.clear();
  std::string reason;
  ASSERT_TRUE(sim.setState(crushed, reason)) << reason;
  int truncated = 0;
  double fastest = 0.0;
  for (int k = 0; k < 4; ++k) {
    sim.step();
    const CollisionStats& stats = sim.collisions().stats();
    truncated += stats.truncated_searches;
    EXPECT_LE(stats.edge_edge_pairs, budget + 144) << "step " << k;
    EXPECT_LE(stats.vertex_triangle_pairs, budget + 96) << "step " << k;
    EXPECT_FALSE(sim.faultGuard().lastStepRestored())
        << "step " << k << ": " << describe(sim.faultGuard().lastFault(), scene.solver.max_speed);
    for (const Vec3& v : sim.particles().velocity) fastest = std::max(fastest, v.norm());
  }
  std::printf("crushed 10 x 10: %d truncated searches, fastest particle %.1f m/s\n", truncated,
              fastest);
  EXPECT_GT(truncated, 0);
  EXPECT_LT(fastest, 50.0);
  EXPECT_TRUE(sim.computeMetrics().finite);
}

// A free cloth made of `mesh` at 1 m, thickness h, with self-collision.
SceneConfig meshClothScene(const std::shared_ptr<ClothMesh>& mesh, double h) {
  SceneConfig scene = test::clothScene(2, 2, 0.1, Method::kXpbd);
  scene.cloth.mesh = mesh->source;
  scene.cloth.mesh_data = mesh;
  scene.cloth.origin = Vec3(0.0, 0.0, 1.0);
  scene.cloth.rpy = Vec3::Zero();
  scene.cloth.thickness = h;
  scene.cloth.self_collision = true;
  scene.cloth.pinned.clear();
  return scene;
}

// CollisionStats counts the two kinds of self-collision candidates apart. Two triangles that share
// no vertex, one above the other in the same outline, 0.6 h apart (within the thickness, so every
// box reaches the other layer): each of the 3 + 3 vertices is a candidate against the other
// layer's triangle (6 vertex-triangle pairs), and each of the 3 edges against each of the other's
// 3 (9 edge-edge pairs: the edges of one triangle meet at its corners, so in the outline every
// edge touches every edge of the other).
TEST(SelfCollision, StatsCountVertexTriangleAndEdgeEdgePairsApart) {
  const double h = 0.005;
  auto mesh = std::make_shared<ClothMesh>();
  mesh->source = "two parallel triangles";
  for (const double z : {0.0, 0.6 * h}) {
    mesh->vertices.emplace_back(0.0, 0.0, z);
    mesh->vertices.emplace_back(0.1, 0.0, z);
    mesh->vertices.emplace_back(0.0, 0.1, z);
  }
  mesh->triangles = {0, 1, 2, 3, 4, 5};
  mesh->triangle_face = {1, 2};
  SceneConfig scene = meshClothScene(mesh, h);
  scene.solver.gravity = Vec3::Zero();
  Simulation sim(scene);
  sim.step();
  const CollisionStats& stats = sim.collisions().stats();
  EXPECT_EQ(stats.vertex_triangle_pairs, 6);
  EXPECT_EQ(stats.edge_edge_pairs, 9);
}

// The paths' cull (SelfCollision::findPairs): a flat cloth falling freely moves every particle
// along its reference path, so no vertex is listed with a triangle of its own cloth, though its
// swept box overlaps those of the triangles next to it (a right triangle's box holds the opposite
// corner of its cell: about two per vertex, 722 here, which the boxes alone listed), and no search
// is repeated within a step.
TEST(SelfCollision, FlatClothFallingAsAWholeListsNoNeighbours) {
  SceneConfig scene = test::clothScene(20, 20, 0.02, Method::kXpbd);
  scene.cloth.rpy = Vec3::Zero();
  scene.cloth.origin = Vec3(0.0, 0.0, 2.0);
  scene.cloth.thickness = 0.005;
  scene.cloth.self_collision = true;
  scene.cloth.pinned.clear();
  scene.solver.substeps = 12;
  Simulation sim(scene);
  for (int k = 0; k < 30; ++k) {
    sim.step();
    const CollisionStats& stats = sim.collisions().stats();
    ASSERT_EQ(stats.vertex_triangle_pairs, 0) << "step " << k;
    ASSERT_EQ(stats.broad_phase_runs, 1) << "step " << k;
    ASSERT_EQ(stats.search_window, 12) << "step " << k << ": the adaptive window spans the step";
  }
  EXPECT_LT(sim.particles().position[0].z(), 1.5);  // it fell (1.8 m/s after 0.5 s)
}

// The adaptive search window (collisions.h): where neighbours move apart fast, a search over the
// whole step lists pairs that the step's motion could bring together but that never come near.
// The drape at 64 x 64 (the scaling benchmark's settings: 60 Hz, 20 substeps, h = spacing / 6),
// its corners whipping round the ball: with the window fixed at the whole step the step-start
// searches list thousands of edge-edge pairs; the adaptive window shortens after the first touch
// and lists far fewer (here 308,812 against 21,608 over 30 steps; its shortest window 2
// substeps).
TEST(SelfCollision, SearchWindowShortensWhereNeighboursMoveApart) {
  const int n = 64;
  const double spacing = 0.93 / (n - 1), h = spacing / 6.0;
  long edge_pairs[2] = {0, 0};
  int shortest[2] = {1000, 1000};
  for (int adaptive = 0; adaptive < 2; ++adaptive) {
    SceneConfig scene = loadScene(kSourceDirectory + "/config/drape.yaml");
    scene.cloth.rows = scene.cloth.cols = n;
    scene.cloth.spacing = spacing;
    scene.cloth.thickness = h;
    scene.solver.search_window = adaptive ? 0 : scene.solver.substeps;
    Simulation sim(scene);
    double deepest = 0.0;
    for (int k = 0; k < 30; ++k) {
      sim.step();
      edge_pairs[adaptive] += sim.collisions().stats().edge_edge_pairs;
      shortest[adaptive] = std::min(shortest[adaptive], sim.collisions().stats().search_window);
      deepest = std::max(deepest, sim.stats().max_penetration);
    }
    std::printf(
        "%s window: %ld edge-edge candidates over 30 steps, shortest window %d substeps, "
        "deepest %.2e m\n",
        adaptive ? "adaptive" : "whole-step", edge_pairs[adaptive], shortest[adaptive], deepest);
    EXPECT_TRUE(sim.computeMetrics().finite);
  }
  EXPECT_EQ(shortest[0], 20);
  EXPECT_LE(shortest[1], 5);
  EXPECT_LT(4 * edge_pairs[1], edge_pairs[0]);
}

// The triangle tree's flat patches (triangle_tree.h) leave out only pairs that cannot touch: on
// states of the fold (layers meeting and swinging apart) and of the T-shirt (a mesh, its front and
// back lying flat on each other: parallel layers that no patch may hold), every vertex-triangle and
// edge-edge pair within 2 h (the thickness plus the two particles' path slack, what any search
// must list) is among the tree's candidates, compared with every pair of the cloth. The tree
// is built at the cloth's rest shape, as the simulation does, and searched with each state's
// motion over the next step. (The drape, 32 x 32 or 45 x 45, brings no pair within 2 h.)
struct CandidateCheck {
  long close = 0;   // pairs within 2 h, all of which must be listed
  long missed = 0;  // of those, not listed
  long listed = 0;  // the tree's candidates
};

CandidateCheck checkCandidates(SelfCollision& search, const Particles& p,
                               const ClothTopology& topology, double h, double dt) {
  const int n = p.cloth_count;
  Vec3Array lo(p.size()), hi(p.size()), move(p.size());
  for (int i = 0; i < p.size(); ++i) {
    move[i] = dt * p.velocity[i];
    const Vec3 end = p.position[i] + move[i];
    lo[i] = p.position[i].cwiseMin(end).array() - 0.5 * p.radius[i];
    hi[i] = p.position[i].cwiseMax(end).array() + 0.5 * p.radius[i];
  }
  Particles at = p;
  at.step_start = p.position;
  search.findPairs(at, topology, MotionBounds{lo, hi, p.position, move, 0.5}, h, true, false);
  std::set<std::array<int, 4>> listed;
  for (const SelfContactPair& pair : search.pairs()) {
    listed.insert({pair.index[0], pair.index[1], pair.index[2], pair.index[3]});
  }
  CandidateCheck check;
  check.listed = static_cast<long>(listed.size());
  const Vec3Array& x = p.position;
  const auto& tri = topology.triangles;
  for (int t = 0; t < topology.triangleCount(); ++t) {
    const int a = static_cast<int>(tri[3 * t]), b = static_cast<int>(tri[3 * t + 1]),
              c = static_cast<int>(tri[3 * t + 2]);
    for (int v = 0; v < n; ++v) {
      if (v == a || v == b || v == c) continue;
      if (pointTriangleDistance(x[v], x[a], x[b], x[c]) > 2.0 * h) continue;
      ++check.close;
      if (!listed.count({v, a, b, c})) ++check.missed;
    }
  }
  std::set<std::array<int, 2>> edge_set;
  for (int t = 0; t < topology.triangleCount(); ++t) {
    for (int e = 0; e < 3; ++e) {
      const int a = static_cast<int>(tri[3 * t + e]),
                b = static_cast<int>(tri[3 * t + (e + 1) % 3]);
      edge_set.insert({std::min(a, b), std::max(a, b)});
    }
  }
  const std::vector<std::array<int, 2>> edges(edge_set.begin(), edge_set.end());
  auto near = [&](int u, int v) {
    if (topology.from_mesh) return topology.meshNear(u, v);
    return std::abs(u / topology.cols - v / topology.cols) <= 1 &&
           std::abs(u % topology.cols - v % topology.cols) <= 1;
  };
  for (std::size_t e = 0; e < edges.size(); ++e) {
    for (std::size_t f = e + 1; f < edges.size(); ++f) {
      const auto [a, b] = edges[e];
      const auto [c, d] = edges[f];
      if (near(a, c) || near(a, d) || near(b, c) || near(b, d)) continue;
      if (segmentSegmentDistance(x[a], x[b], x[c], x[d]) > 2.0 * h) continue;
      ++check.close;
      if (!listed.count({a, b, c, d}) && !listed.count({c, d, a, b})) ++check.missed;
    }
  }
  return check;
}

void expectTreeListsEveryClosePair(const SceneConfig& scene, const std::vector<int>& at_steps,
                                   const char* what) {
  Simulation sim(scene);
  SelfCollision search;
  search.reserve(sim.particles(), sim.topology());  // the tree at the rest shape
  const double dt = 1.0 / scene.step_rate;
  long close = 0, missed = 0, listed = 0;
  int step = 0;
  for (int target : at_steps) {
    for (; step < target; ++step) sim.step();
    const CandidateCheck check =
        checkCandidates(search, sim.particles(), sim.topology(), scene.cloth.thickness, dt);
    close += check.close;
    missed += check.missed;
    listed += check.listed;
    EXPECT_EQ(check.missed, 0) << what << ", step " << target << ": " << check.close
                               << " pairs within 2 h";
  }
  std::printf("%s: %ld pairs within 2 h, %ld missed, %ld candidates listed\n", what, close, missed,
              listed);
  EXPECT_GT(close, 0) << what << ": no state brought the cloth near itself";
}

TEST(SelfCollision, TreeListsEveryPairWithinTwiceTheThickness) {
  std::vector<int> fold_steps;
  for (int k = 150; k < 240; k += 3) fold_steps.push_back(k);
  expectTreeListsEveryClosePair(foldScene(true), fold_steps, "fold");
  // Two separate squares, one 0.6 h above the other and facing the same way, falling together:
  // parallel layers that nodes holding both would find flat, were they not two patches.
  const double h = 0.005;
  auto mesh = std::make_shared<ClothMesh>();
  mesh->source = "two stacked squares";
  const int side = 6;
  for (const double z : {0.0, 0.6 * h}) {
    const unsigned base = static_cast<unsigned>(mesh->vertices.size());
    for (int r = 0; r < side; ++r) {
      for (int c = 0; c < side; ++c) mesh->vertices.emplace_back(0.02 * c, 0.02 * r, z);
    }
    for (int r = 0; r + 1 < side; ++r) {
      for (int c = 0; c + 1 < side; ++c) {
        const unsigned k = base + static_cast<unsigned>(r * side + c);
        const unsigned s = static_cast<unsigned>(side);
        mesh->triangles.insert(mesh->triangles.end(), {k, k + 1, k + s + 1, k, k + s + 1, k + s});
        mesh->triangle_face.insert(mesh->triangle_face.end(), {1, 1});
      }
    }
  }
  expectTreeListsEveryClosePair(meshClothScene(mesh, h), {0, 5}, "two stacked squares");
  SceneConfig shirt = loadScene(kSourceDirectory + "/config/tshirt.yaml");
  expectTreeListsEveryClosePair(shirt, {0, 30, 60}, "tshirt");
}

// A local search (SelfCollision::findPairsNear, Collisions' search for a few particles that left
// their bounds) lists every vertex-triangle pair within 2 h, as the whole search does: on the same
// states, after a whole search, every 7th particle leaves (moved by 1.5 h across the cloth and
// given another velocity), the particles renewedAround them get bounds of their new state, the
// others keep theirs, and the local search's list is compared with every pair of the cloth at the
// new positions. It also lists fewer candidates than there are pairs within the changed leaves'
// reach of a whole search would cost: the kept pairs come from the search before.
void expectLocalSearchListsEveryClosePair(const SceneConfig& scene,
                                          const std::vector<int>& at_steps, const char* what) {
  Simulation sim(scene);
  SelfCollision search;
  search.reserve(sim.particles(), sim.topology());
  const ClothTopology& topology = sim.topology();
  const double dt = 1.0 / scene.step_rate, h = scene.cloth.thickness;
  long close = 0, missed = 0, renewed_total = 0;
  int step = 0;
  for (int target : at_steps) {
    for (; step < target; ++step) sim.step();
    Particles at = sim.particles();
    at.step_start = at.position;
    const int n = at.size();
    Vec3Array lo(n), hi(n), start(n), move(n);
    auto bound = [&](int i) {
      move[i] = dt * at.velocity[i];
      start[i] = at.position[i];
      const Vec3 end = at.position[i] + move[i];
      lo[i] = at.position[i].cwiseMin(end).array() - 0.5 * at.radius[i];
      hi[i] = at.position[i].cwiseMax(end).array() + 0.5 * at.radius[i];
    };
    for (int i = 0; i < n; ++i) bound(i);
    const MotionBounds bounds{lo, hi, start, move, 0.5};
    search.findPairs(at, topology, bounds, h, true, false);
    std::vector<int> leavers;
    for (int i = 3; i < at.cloth_count; i += 7) {
      if (at.inverse_mass[i] == 0.0) continue;
      leavers.push_back(i);
      // Across the cloth (along its local normal, roughly) and sideways: out of its box.
      at.position[i] += Vec3(0.9 * h, -0.9 * h, 0.9 * h);
      at.velocity[i] = -at.velocity[i] + Vec3(0.1, 0.0, -0.2);
    }
    const std::vector<int> renewed = search.renewedAround(leavers, topology, at.cloth_count);
    renewed_total += static_cast<long>(renewed.size());
    for (int i : renewed) bound(i);
    search.findPairsNear(at, topology, bounds, h, renewed);
    std::set<std::array<int, 4>> listed;
    for (const SelfContactPair& pair : search.pairs()) {
      if (!pair.edge_edge)
        listed.insert({pair.index[0], pair.index[1], pair.index[2], pair.index[3]});
    }
    const Vec3Array& x = at.position;
    const auto& tri = topology.triangles;
    long state_close = 0, state_missed = 0;
    for (int t = 0; t < topology.triangleCount(); ++t) {
      const int a = static_cast<int>(tri[3 * t]), b = static_cast<int>(tri[3 * t + 1]),
                c = static_cast<int>(tri[3 * t + 2]);
      for (int v = 0; v < at.cloth_count; ++v) {
        if (v == a || v == b || v == c) continue;
        if (pointTriangleDistance(x[v], x[a], x[b], x[c]) > 2.0 * h) continue;
        ++state_close;
        if (!listed.count({v, a, b, c})) ++state_missed;
      }
    }
    EXPECT_EQ(state_missed, 0) << what << ", step " << target << ": " << state_close
                               << " vertex-triangle pairs within 2 h";
    close += state_close;
    missed += state_missed;
  }
  std::printf(
      "%s: %ld vertex-triangle pairs within 2 h after the local searches, %ld missed, "
      "%ld particles renewed\n",
      what, close, missed, renewed_total);
  EXPECT_GT(close, 0) << what << ": no state brought the cloth near itself";
}

TEST(SelfCollision, LocalSearchListsEveryPairWithinTwiceTheThickness) {
  std::vector<int> fold_steps;
  for (int k = 150; k < 240; k += 6) fold_steps.push_back(k);
  expectLocalSearchListsEveryClosePair(foldScene(true), fold_steps, "fold");
  SceneConfig shirt = loadScene(kSourceDirectory + "/config/tshirt.yaml");
  expectLocalSearchListsEveryClosePair(shirt, {0, 30, 60}, "tshirt");
}

// measureAllowances runs after every search of a step, a local one included, and keeps the
// allowance of a pair measured earlier in the step while its side stands (the same positions,
// the step's start, and the same side: the same value). A side that changes is measured anew. A
// 5 x 5 grid lies flat; its corner, particle 0, starts 0.3 h above a triangle of the cell (2, 2):
// h - 0.3 h of overlap is allowed on the side it starts on. A substep that starts with the corner
// beside the triangle and below its plane turns the pair's side over, and the same step-start
// positions then allow h + 0.3 h.
TEST(SelfCollision, AllowanceKeptWhileThePairsSideStands) {
  SceneConfig scene = test::clothScene(5, 5, 0.1, Method::kXpbd);
  scene.cloth.self_collision = true;
  Simulation sim(scene);
  Particles p = sim.particles();
  const ClothTopology& topology = sim.topology();
  const double h = 0.01, slop = 0.1, s = 0.1;
  for (int i = 0; i < p.size(); ++i) p.position[i] = Vec3((i % 5) * s, (i / 5) * s, 0.0);
  SelfCollision search;
  search.reserve(p, topology);  // the tree at the flat rest shape
  // A triangle with corners in the cell (2, 2)-(3, 3) only: 12, 13, 17, 18.
  int t = -1;
  for (int k = 0; k < topology.triangleCount() && t < 0; ++k) {
    bool in_cell = true;
    for (int e = 0; e < 3; ++e) {
      const int v = static_cast<int>(topology.triangles[3 * k + e]);
      in_cell = in_cell && (v == 12 || v == 13 || v == 17 || v == 18);
    }
    if (in_cell) t = k;
  }
  ASSERT_GE(t, 0);
  const unsigned* corner = &topology.triangles[3 * t];
  const Vec3 centroid =
      (p.position[corner[0]] + p.position[corner[1]] + p.position[corner[2]]) / 3.0;
  p.position[0] = centroid + Vec3(0.0, 0.0, 0.3 * h);
  p.step_start = p.substep_start = p.position;
  const Vec3Array move(p.size(), Vec3::Zero());
  Vec3Array lo(p.position), hi(p.position), reaction(p.size(), Vec3::Zero());
  search.findPairs(p, topology, MotionBounds{lo, hi, p.position, move, 0.5}, h, true, false);
  auto pairOf = [&]() -> const SelfContactPair* {
    for (const SelfContactPair& pair : search.pairs()) {
      if (!pair.edge_edge && pair.index[0] == 0 && pair.triangle == t) return &pair;
    }
    return nullptr;
  };
  ASSERT_NE(pairOf(), nullptr) << "the corner over the triangle is a candidate";
  search.measureAllowances(p.step_start, h, slop);
  const double start_side = pairOf()->side;  // the triangle's normal decides which
  ASSERT_NE(start_side, 0.0);
  EXPECT_NEAR(pairOf()->allowance, allowanceFor(0.7 * h, h, slop), 1e-15);
  // A substep starting with the corner 2 spacings aside and 0.5 h below the triangle's plane:
  // outside it, so the side follows the start.
  p.substep_start[0] = centroid + Vec3(2.0 * s, 0.0, -0.5 * h);
  p.position = p.substep_start;
  search.project(p, h, 1, Friction{0.0, 0.0}, reaction);
  EXPECT_EQ(pairOf()->side, -start_side);
  search.measureAllowances(p.step_start, h, slop);
  EXPECT_NEAR(pairOf()->allowance, allowanceFor(1.3 * h, h, slop), 1e-15)
      << "measured again with the side it has now";
}

}  // namespace
}  // namespace pbd_cloth
