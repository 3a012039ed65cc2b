// Microbenchmarks of the hot loops (Google Benchmark): nanoseconds per stretch and per bending
// constraint projection, per collision test (sphere obstacle, particle pairs, cloth self-contact)
// on a 50 x 50 cloth, and a whole step of config/hanging.yaml per method; and, as issue 12's
// reference, what a direct solve of the swinging cloth's links costs (BM_Direct*).
//
//   cloth_microbench [--scene=<hanging.yaml>] [Google Benchmark flags, e.g.
//                    --benchmark_format=csv --benchmark_min_time=0.2]
//
// Every figure times the public entry points the simulation itself calls (Solver::step,
// Collisions::beginStep / project), so it measures the real code, not a copy of it. The per-
// projection counters divide the time of a step of one substep and N passes by N x constraint
// count: prediction and velocity update are then amortized over N passes (the /50 rows are closest
// to the pure projection cost). Bending is the difference between a step with and one without
// bending hinges, divided by the hinge count.
#include <benchmark/benchmark.h>

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "../core/mesh_builders.h"
#include "pbd_cloth/collision/collisions.h"
#include "pbd_cloth/constraints/flat_hinges.h"
#include "pbd_cloth/constraints/stretch_links.h"
#include "pbd_cloth/scene/scene_assets.h"
#include "pbd_cloth/scene/scene_yaml.h"
#include "pbd_cloth/sensors/depth_camera.h"
#include "pbd_cloth/sim/cloth_builder.h"
#include "pbd_cloth/sim/simulation.h"
#include "pbd_cloth/solver/rod_stepper.h"
#include "pbd_cloth/solver/solver.h"

namespace pbd_cloth {
namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// The scene file: --scene=<path>, else config/hanging.yaml of the source tree this was built from.
std::string& scenePath() {
  static std::string path = [] {
    const std::string file = __FILE__;  // <package>/test/bench/microbench.cpp
    const std::size_t test = file.rfind("/test/bench/");
    return (test == std::string::npos ? std::string(".") : file.substr(0, test)) +
           "/config/hanging.yaml";
  }();
  return path;
}

// The 50 x 50, 1 m hanging cloth of config/hanging.yaml, built in code so the projection benchmarks
// do not depend on the file: 0.2 g particles, pinned at the two top corners.
SceneConfig clothScene(Method method, int iterations, bool bending) {
  SceneConfig scene;
  scene.step_rate = 60.0;
  scene.solver.method = method;
  scene.solver.substeps = 1;
  scene.solver.iterations = iterations;
  scene.solver.damping = 0.1;
  scene.cloth.rows = 50;
  scene.cloth.cols = 50;
  scene.cloth.spacing = 1.0 / 49.0;
  scene.cloth.mass = 0.5;
  scene.cloth.origin = Eigen::Vector3d(0.0, 0.0, 1.5);
  scene.cloth.rpy = Eigen::Vector3d(1.5707963267948966, 0.0, 0.0);  // hangs in x-z
  scene.cloth.bend_compliance = bending ? 1.0 : -1.0;
  scene.cloth.self_collision = false;
  scene.cloth.pinned = {0, 49};
  return scene;
}

// A solver with its particles, constraints and (empty) contacts, stepped directly.
struct SolverRig {
  explicit SolverRig(const SceneConfig& scene) : dt(1.0 / scene.step_rate) {
    buildScene(scene, particles, topology);
    collisions.configure(collisionSettings(scene));
    solver.configure(scene.solver, clothMaterial(scene.cloth));
    solver.prepare(particles, topology);
    collisions.prepare(particles, topology);
    initial = particles;
  }
  // One step, timed; every 60 steps the cloth starts again so the state stays the hanging one.
  double timedStep() {
    if (++steps % 60 == 0) particles = initial;
    const Clock::time_point start = Clock::now();
    solver.step(dt, particles, topology, collisions);
    return secondsSince(start);
  }
  double dt;
  long steps = 0;
  Particles particles;
  Particles initial;
  ClothTopology topology;
  Solver solver;
  Collisions collisions;
};

// The two counters every benchmark reports (Google Benchmark's CSV needs the same set in every
// row): `count` (constraints, hinges, tests or particles per pass) and `ns_per_item`, the measured
// seconds spread over `items` per iteration.
void setCounters(benchmark::State& state, double count, double seconds, double items) {
  state.counters["count"] = count;
  state.counters["ns_per_item"] =
      benchmark::Counter(1e9 * seconds / items, benchmark::Counter::kAvgIterations);
}

// ns per stretch projection: args = {method, ordering, passes}.
void BM_StretchProjection(benchmark::State& state) {
  SceneConfig scene =
      clothScene(static_cast<Method>(state.range(0)), static_cast<int>(state.range(2)), false);
  scene.solver.ordering = static_cast<Ordering>(state.range(1));
  SolverRig rig(scene);
  const double projections =
      static_cast<double>(rig.topology.stretch.size()) * scene.solver.iterations;
  double total = 0.0;
  for (auto _ : state) {
    const double seconds = rig.timedStep();
    state.SetIterationTime(seconds);
    total += seconds;
  }
  setCounters(state, static_cast<double>(rig.topology.stretch.size()), total, projections);
  state.SetLabel(std::string(toString(scene.solver.method)) + " " +
                 toString(scene.solver.ordering) + ": per stretch projection");
}

// The stretch pair of issue 12 (target 5): one Gauss-Seidel pass over the links of the swinging
// cloth (config/swinging.yaml built in code: 50 x 50, both diagonals, 9702 links) through the
// solver's own projection (projectStretchLinks, arg simd = 1: AVX2 where there, 0: the portable
// loop), against BM_StretchBareLoop: a bare loop doing the same XPBD arithmetic on the same flat
// arrays, with none of the checks (kinematic ends, coincident particles, largest correction).
struct StretchRig {
  explicit StretchRig(int rows = 50) {
    SceneConfig scene = clothScene(Method::kXpbd, 1, false);
    scene.cloth.rows = scene.cloth.cols = rows;  // the swinging cloth at rows x rows, 1 m
    scene.cloth.spacing = 1.0 / (rows - 1);
    scene.cloth.pinned = {0, rows - 1};
    scene.cloth.shear_diagonals = 2;
    scene.cloth.rpy = Eigen::Vector3d::Zero();  // flat, swinging down as config/swinging.yaml
    scene.solver.substeps = 20;
    SolverRig rig(scene);
    for (int step = 0; step < 30; ++step) rig.timedStep();  // a swinging, stretched state
    links.assign(rig.topology.stretch, rig.particles.size());
    position.resize(rig.particles.size());
    positionsToColumns(rig.particles.position.front().data(), 0, rig.particles.size(),
                       position.columns(), false);
    inverse_mass = rig.particles.inverse_mass;
    lambda.assign(links.size(), 0.0);
  }
  PositionColumns x() { return position.columns(); }
  StretchLinks links;
  ColumnPositions position;  // in columns, as the solver's sweep has them
  std::vector<double> inverse_mass;
  std::vector<double> lambda;
};

// The path a projection takes on this processor.
const char* stretchPath(const StretchProjection& how) {
  if (how.simd && how.avx512 && stretchLinksUseAvx512()) return "projectStretchLinks, AVX-512";
  if (how.simd && stretchLinksUseAvx2()) return "projectStretchLinks, AVX2";
  return "projectStretchLinks, portable";
}

// simd 1: the widest path this processor has (AVX-512, else AVX2), 0: the portable loop, 2: AVX2
// at most (solver.avx512: false), to compare the two register widths on an AVX-512 processor.
void BM_StretchLinks(benchmark::State& state) {
  StretchRig rig;
  StretchProjection how;
  how.alpha = 1e-9;  // a compliance, so the multiplier term is computed as in XPBD
  how.simd = state.range(0) != 0;
  how.avx512 = state.range(0) != 2;
  rig.links.prepareStep(rig.inverse_mass.data(), how.alpha);
  double total = 0.0;
  for (auto _ : state) {
    const Clock::time_point start = Clock::now();
    benchmark::DoNotOptimize(
        projectStretchLinks(rig.links, 0, rig.links.batchCount(), how, rig.x(), rig.lambda.data()));
    benchmark::ClobberMemory();
    total += secondsSince(start);
  }
  setCounters(state, rig.links.size(), total, rig.links.size());
  state.SetLabel(stretchPath(how));
}

// The same arithmetic, in the same order, on the same arrays (the link list, the per-step inverse
// masses and denominators, the positions and multipliers), with nothing else.
void BM_StretchBareLoop(benchmark::State& state) {
  StretchRig rig;
  const double alpha = 1e-9;
  rig.links.prepareStep(rig.inverse_mass.data(), alpha);
  const int count = rig.links.size();
  const int* link_i = rig.links.i.data();
  const int* link_j = rig.links.j.data();
  const double* rest = rig.links.rest_length.data();
  const double* wi = rig.links.inverse_mass_i.data();
  const double* wj = rig.links.inverse_mass_j.data();
  const double* inverse_denominator = rig.links.inverse_denominator.data();
  double* lambda = rig.lambda.data();
  double* x = rig.x().x;
  double* y = rig.x().y;
  double* z = rig.x().z;
  double total = 0.0;
  for (auto _ : state) {
    const Clock::time_point start = Clock::now();
    for (int c = 0; c < count; ++c) {
      const int a = link_i[c], b = link_j[c];
      const double dx = x[a] - x[b], dy = y[a] - y[b], dz = z[a] - z[b];
      const double length = std::sqrt((dx * dx + dy * dy) + dz * dz);
      const double dlambda = (-(length - rest[c]) - alpha * lambda[c]) * inverse_denominator[c];
      lambda[c] += dlambda;
      const double s = dlambda / length;
      const double fa = wi[c] * s, fb = wj[c] * s;
      x[a] += fa * dx;
      y[a] += fa * dy;
      z[a] += fa * dz;
      x[b] -= fb * dx;
      y[b] -= fb * dy;
      z[b] -= fb * dz;
    }
    benchmark::ClobberMemory();
    total += secondsSince(start);
  }
  setCounters(state, count, total, count);
  state.SetLabel("bare loop, same arithmetic");
}

// A direct solve as the reference issue 12 names (fast projection, Goldenthal et al. 2007; Eigen's
// SimplicialLDLT): one Newton step of the swinging cloth's inextensible links solves
// (J W J^T + alpha~) dlambda = -C exactly, where one Gauss-Seidel pass of the solver takes each
// link alone. The matrix of every stretch link (rows, columns, both diagonals) of StretchRig's
// swinging state at rows x rows (arg): A_kl = sum over the particles p the links k and l share of
// w_p s_kp s_lp (n_k . n_l), s = +-1 the particle's end of the link, n the link's direction.
// alpha~ is 1e-9 of each link's own diagonal: 9702 links hold 7494 free coordinates at 50 x 50,
// so J W J^T alone is singular. The ordering (AMD) is found once, outside the timing.
struct DirectRig {
  explicit DirectRig(int rows) : stretch(rows) {
    const StretchLinks& links = stretch.links;
    const int count = links.size();
    direction.resize(count);
    at.resize(stretch.position.size());
    const PositionColumns x = stretch.x();
    auto at_particle = [&x](int q) { return Vec3(x.x[q], x.y[q], x.z[q]); };
    for (int k = 0; k < count; ++k) {
      direction[k] = (at_particle(links.i[k]) - at_particle(links.j[k])).normalized();
      at[links.i[k]].push_back({k, 1.0});
      at[links.j[k]].push_back({k, -1.0});
    }
    matrix.resize(count, count);
    assemble();
    ldlt.analyzePattern(matrix);
  }
  // A from the state's link directions, as a Newton step would at each iteration.
  void assemble() {
    triplets.clear();
    // alpha~ on the diagonal, whose J W J^T entry is w_i + w_j (n_k . n_k = 1).
    const StretchLinks& links = stretch.links;
    for (int k = 0; k < links.size(); ++k) {
      triplets.emplace_back(
          k, k, 1e-9 * (stretch.inverse_mass[links.i[k]] + stretch.inverse_mass[links.j[k]]));
    }
    for (std::size_t p = 0; p < at.size(); ++p) {
      const double w = stretch.inverse_mass[p];
      if (w == 0.0) continue;
      for (const auto& [k, sk] : at[p]) {
        for (const auto& [l, sl] : at[p]) {
          triplets.emplace_back(k, l, w * sk * sl * direction[k].dot(direction[l]));
        }
      }
    }
    matrix.setFromTriplets(triplets.begin(), triplets.end());  // sums duplicates
  }
  StretchRig stretch;
  std::vector<Vec3> direction;
  std::vector<std::vector<std::pair<int, double>>> at;  // each particle's links, with its sign
  std::vector<Eigen::Triplet<double>> triplets;
  Eigen::SparseMatrix<double> matrix;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt;
};

// Assembling and factorizing A: what each Newton iteration pays. ns_per_item: per link.
void BM_DirectFactorize(benchmark::State& state) {
  DirectRig rig(static_cast<int>(state.range(0)));
  double total = 0.0;
  for (auto _ : state) {
    const Clock::time_point start = Clock::now();
    rig.assemble();
    rig.ldlt.factorize(rig.matrix);
    benchmark::DoNotOptimize(rig.ldlt.info());
    total += secondsSince(start);
  }
  if (rig.ldlt.info() != Eigen::Success) state.SkipWithError("factorization failed");
  setCounters(state, rig.stretch.links.size(), total, rig.stretch.links.size());
  state.SetLabel(
      "SimplicialLDLT of J W J^T, nnz(L) " +
      std::to_string(static_cast<long>(rig.ldlt.matrixL().nestedExpression().nonZeros())));
}

// One solve with the factors (forward and back substitution): the least a step of a frozen-matrix
// Newton method would pay per iteration. ns_per_item: per link.
void BM_DirectSolve(benchmark::State& state) {
  DirectRig rig(static_cast<int>(state.range(0)));
  rig.ldlt.factorize(rig.matrix);
  const Eigen::VectorXd violation = Eigen::VectorXd::Ones(rig.matrix.rows());
  Eigen::VectorXd dlambda;
  double total = 0.0;
  for (auto _ : state) {
    const Clock::time_point start = Clock::now();
    dlambda = rig.ldlt.solve(violation);
    benchmark::DoNotOptimize(dlambda.data());
    total += secondsSince(start);
  }
  // A solve that does not solve would time nothing worth knowing.
  const double residual = (rig.matrix * dlambda - violation).norm() / violation.norm();
  if (!(residual < 1e-6)) state.SkipWithError("the solve's relative residual is over 1e-6");
  setCounters(state, rig.stretch.links.size(), total, rig.stretch.links.size());
  state.SetLabel("forward and back substitution");
}

// ns per bending projection: a step with hinges minus the same step without, per hinge and pass.
void BM_BendProjection(benchmark::State& state) {
  const Method method = static_cast<Method>(state.range(0));
  const int passes = static_cast<int>(state.range(1));
  SolverRig with(clothScene(method, passes, true));
  SolverRig without(clothScene(method, passes, false));
  const double projections = static_cast<double>(with.topology.bend.size()) * passes;
  double difference = 0.0;
  for (auto _ : state) {
    const double seconds = with.timedStep();
    difference += seconds - without.timedStep();
    state.SetIterationTime(seconds);
  }
  setCounters(state, static_cast<double>(with.topology.bend.size()), difference, projections);
  state.SetLabel(std::string(toString(method)) + ": per bending projection");
}

// ns per flat hinge projection (flat_hinges.h) on each path, the pass alone: a 50 x 50 cloth at
// config/fabric_table.yaml's spacing (bending on, zero compliance here), its hinges in the solver's
// sweep order with what Solver::prepareBendStep fixes for them, positions bent by a swinging start.
// path 0: portable loop, 1: AVX-512VL where the processor has it (else AVX2), 2: AVX2; first 1:
// each pass a substep's first (its multipliers written, not read), 0: a later iteration's; keep
// 1: the multipliers written for a later pass, 0: the substep's last pass (solver.iterations 1:
// first and last), which writes only those of hinges with a kinematic corner (none here).
void BM_FlatHinges(benchmark::State& state) {
  SceneConfig scene = clothScene(Method::kXpbd, 1, true);
  scene.cloth.rows = scene.cloth.cols = 50;
  scene.cloth.spacing = 0.02;
  scene.cloth.pinned = {0, 49};
  scene.cloth.bend_compliance = 0.0;
  scene.cloth.rpy = Eigen::Vector3d::Zero();  // flat at the start, so it bends as it swings
  SolverRig rig(scene);
  for (int step = 0; step < 30; ++step) rig.timedStep();  // a bent, swinging state
  const auto& bend = rig.topology.bend;
  std::vector<FlatHinge> hinge(bend.size());
  for (std::size_t c = 0; c < bend.size(); ++c) {  // at zero compliance (alpha~ 0, k 1)
    hinge[c] = makeFlatHinge(bend[c], rig.particles.inverse_mass.data(), 0.0, 1.0, 1e-300);
  }
  const bool simd = state.range(0) != 0, avx512 = state.range(0) != 2, first = state.range(1) != 0;
  const bool keep = state.range(2) != 0;
  std::vector<double> lambda(3 * bend.size(), 0.0);
  double* x = rig.particles.position.front().data();
  double total = 0.0;
  for (auto _ : state) {
    const Clock::time_point start = Clock::now();
    benchmark::DoNotOptimize(projectFlatHinges(hinge.data(), static_cast<int>(hinge.size()), first,
                                               keep, false, simd, avx512, x, lambda.data()));
    benchmark::ClobberMemory();
    total += secondsSince(start);
  }
  setCounters(state, static_cast<double>(hinge.size()), total, static_cast<double>(hinge.size()));
  state.SetLabel(!simd || !stretchLinksUseAvx2()     ? "projectFlatHinges, portable"
                 : avx512 && flatHingesUseAvx512Vl() ? "projectFlatHinges, AVX-512VL"
                                                     : "projectFlatHinges, AVX2");
}

// Contacts of one scene: the broad phase once, then timed passes of Collisions::project from the
// same positions each time.
struct ContactRig {
  explicit ContactRig(const SceneConfig& scene) {
    buildScene(scene, particles, topology);
    collisions.configure(collisionSettings(scene));
    collisions.prepare(particles, topology);
  }
  void begin() {
    initial = particles;
    collisions.beginStep(particles, topology, 1.0 / 60.0);
    collisions.setSubstepFraction(0.0, 1.0);
  }
  double timedPass() {
    particles.position = initial.position;
    const Clock::time_point start = Clock::now();
    collisions.project(particles, topology);
    return secondsSince(start);
  }
  Particles particles;
  Particles initial;
  ClothTopology topology;
  Collisions collisions;
};

void runContactPasses(benchmark::State& state, ContactRig& rig, int tests_per_pass,
                      const char* label) {
  rig.begin();
  double total = 0.0;
  for (auto _ : state) {
    const double seconds = rig.timedPass();
    state.SetIterationTime(seconds);
    total += seconds;
  }
  setCounters(state, tests_per_pass, total, tests_per_pass);
  state.SetLabel(label);
}

// Particle against a sphere: a flat 50 x 50 cloth pressed 5 cm into a 0.3 m ball (about a third
// of the particles inside). ns per particle per pass.
void BM_SphereCollision(benchmark::State& state) {
  SceneConfig scene = clothScene(Method::kXpbd, 1, false);
  scene.cloth.rpy = Eigen::Vector3d::Zero();
  scene.cloth.origin = Eigen::Vector3d(-0.5, 0.5, 0.55);
  scene.cloth.pinned.clear();
  ObstacleConfig ball;
  ball.name = "ball";
  ball.shape = ShapeType::kSphere;
  ball.radius = 0.3;
  ball.pose.position = Eigen::Vector3d(0.0, 0.0, 0.3);
  scene.obstacles.push_back(ball);
  ContactRig rig(scene);
  runContactPasses(state, rig, rig.particles.cloth_count, "per particle-sphere test");
}

// The same contact against the same ball as a closed triangle mesh (an icosphere of 20 * 4^level
// triangles): ns per particle-mesh test, exact closest-triangle search over the tree included.
void BM_MeshSphereCollision(benchmark::State& state) {
  SceneConfig scene = clothScene(Method::kXpbd, 1, false);
  scene.cloth.rpy = Eigen::Vector3d::Zero();
  scene.cloth.origin = Eigen::Vector3d(-0.5, 0.5, 0.55);
  scene.cloth.pinned.clear();
  Pose pose;
  pose.position = Eigen::Vector3d(0.0, 0.0, 0.3);
  const test::MeshGeometry ball = test::icosphere(0.3, static_cast<int>(state.range(0)));
  scene.obstacles.push_back(test::meshObstacle("ball", ball, pose));
  ContactRig rig(scene);
  runContactPasses(state, rig, rig.particles.cloth_count, "per particle-mesh test");
}

// One signed-distance query of a mesh alone, at points within 5 cm of an icosphere's surface.
void BM_MeshSignedDistance(benchmark::State& state) {
  const auto mesh = test::icosphere(0.3, static_cast<int>(state.range(0))).build();
  std::vector<Vec3> points;
  for (int k = 0; k < 1024; ++k) {
    const double phi = 2.399963 * k, z = 1.0 - 2.0 * (k + 0.5) / 1024.0;  // a Fibonacci sphere
    const double rho = std::sqrt(1.0 - z * z), r = 0.25 + 0.1 * ((k * 37) % 100) / 100.0;
    points.emplace_back(r * rho * std::cos(phi), r * rho * std::sin(phi), r * z);
  }
  double sum = 0.0;
  std::size_t k = 0;
  for (auto _ : state) {
    Vec3 normal;
    sum += mesh->signedDistance(points[k++ & 1023], normal);
  }
  benchmark::DoNotOptimize(sum);
  state.SetLabel(std::to_string(mesh->triangleCount()) + " triangles");
}

// Building a mesh shape at load (welding, pseudo-normals, tree): time and the bytes it holds.
void BM_MeshBuild(benchmark::State& state) {
  const test::MeshGeometry ball = test::icosphere(0.3, static_cast<int>(state.range(0)));
  std::size_t bytes = 0;
  double total = 0.0;
  for (auto _ : state) {
    const Clock::time_point start = Clock::now();
    const TriangleMesh mesh(ball.vertices, ball.triangles);
    bytes = mesh.memoryBytes();
    benchmark::DoNotOptimize(bytes);
    total += secondsSince(start);
  }
  // Every benchmark reports the same counters (Google Benchmark's CSV needs one set); the rest
  // goes into the label.
  const double triangles = static_cast<double>(ball.triangles.size());
  setCounters(state, triangles, total, triangles);
  state.SetLabel(std::to_string(ball.triangles.size()) + " triangles, " + std::to_string(bytes) +
                 " bytes held; ns per triangle");
}

// Particle pairs: 1000 granular particles of 1 cm on a lattice squeezed to 90 % of its pitch, so
// neighbours overlap by 0.2 r. ns per particle per pass (all its pair tests).
// cloth.mesh at load: reading a 142 x 142 = 20,164-vertex OBJ (tinyobjloader, with the line scan
// and the checks of makeClothMesh) and building the simulation from it (masses, edges, hinges,
// neighbour lists, solver and collision buffers, self-collision on). The file is written once.
void BM_ClothMeshLoadAndBuild(benchmark::State& state) {
  const int n = 142;
  const std::string path =
      (std::filesystem::temp_directory_path() / "pbd_cloth_bench_20k.obj").string();
  {
    std::ofstream obj(path);
    for (int r = 0; r < n; ++r) {
      for (int c = 0; c < n; ++c) obj << "v " << c * 0.01 << " " << -r * 0.01 << " 0\n";
    }
    for (int r = 0; r + 1 < n; ++r) {
      for (int c = 0; c + 1 < n; ++c) {
        const int a = r * n + c + 1, b = a + 1, d = a + n, e = d + 1;
        obj << "f " << a << " " << d << " " << e << "\nf " << a << " " << e << " " << b << "\n";
      }
    }
  }
  double load_seconds = 0.0, build_seconds = 0.0, grid_seconds = 0.0;
  for (auto _ : state) {
    // For comparison: the grid of the same size built from rows and cols.
    SceneConfig grid;
    grid.cloth.rows = grid.cloth.cols = n;
    grid.cloth.pinned.clear();
    const auto g0 = std::chrono::steady_clock::now();
    Simulation grid_sim(grid);
    grid_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - g0).count();
    SceneConfig scene;
    scene.cloth.mesh = path;
    const auto t0 = std::chrono::steady_clock::now();
    loadClothMesh(scene);
    const auto t1 = std::chrono::steady_clock::now();
    Simulation sim(scene);
    const auto t2 = std::chrono::steady_clock::now();
    benchmark::DoNotOptimize(sim.particles().position.data());
    load_seconds += std::chrono::duration<double>(t1 - t0).count();
    build_seconds += std::chrono::duration<double>(t2 - t1).count();
  }
  const double iterations = static_cast<double>(state.iterations());
  setCounters(state, n * n, load_seconds + build_seconds, static_cast<double>(n) * n);
  char label[160];
  std::snprintf(label, sizeof(label),
                "load %.3g ms, build %.3g ms (the %dx%d grid: %.3g ms); ns per vertex",
                1e3 * load_seconds / iterations, 1e3 * build_seconds / iterations, n, n,
                1e3 * grid_seconds / iterations);
  state.SetLabel(label);
}

void BM_ParticlePairs(benchmark::State& state) {
  SceneConfig scene = clothScene(Method::kXpbd, 1, false);
  scene.cloth.rows = 1;
  scene.cloth.cols = 2;
  scene.cloth.origin = Eigen::Vector3d(5.0, 5.0, 5.0);  // out of the way
  scene.cloth.pinned.clear();
  scene.granular.count = 1000;
  scene.granular.radius = 0.01;
  scene.granular.region_min = Eigen::Vector3d(0.0, 0.0, 0.0);
  scene.granular.region_max = Eigen::Vector3d(0.22, 0.22, 0.5);
  ContactRig rig(scene);
  const Vec3 centre = scene.granular.region_min;
  for (int i = rig.particles.cloth_count; i < rig.particles.size(); ++i) {
    rig.particles.position[i] = centre + 0.9 * (rig.particles.position[i] - centre);
  }
  runContactPasses(state, rig, scene.granular.count, "per particle, all its pairs");
}

// Cloth self-contact (vertex-triangle with thickness): a 50 x 50 cloth folded in half, the two
// layers half a thickness apart. ns per cloth particle per pass.
void BM_SelfCollision(benchmark::State& state) {
  SceneConfig scene = clothScene(Method::kXpbd, 1, false);
  scene.cloth.rpy = Eigen::Vector3d::Zero();
  scene.cloth.origin = Eigen::Vector3d::Zero();
  scene.cloth.pinned.clear();
  scene.cloth.self_collision = true;
  ContactRig rig(scene);
  const int rows = scene.cloth.rows, cols = scene.cloth.cols;
  for (int r = rows / 2; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      // Row r lies over row rows-1-r, on the other layer.
      rig.particles.position[r * cols + c] = rig.particles.position[(rows - 1 - r) * cols + c] +
                                             Vec3(0.0, 0.0, 0.5 * scene.cloth.thickness);
    }
  }
  runContactPasses(state, rig, rig.particles.cloth_count, "per cloth particle");
}

// The broad phase of a step (once per step, before the substeps) on the folded cloth.
void BM_SelfCollisionBroadPhase(benchmark::State& state) {
  SceneConfig scene = clothScene(Method::kXpbd, 1, false);
  scene.cloth.rpy = Eigen::Vector3d::Zero();
  scene.cloth.pinned.clear();
  scene.cloth.self_collision = true;
  ContactRig rig(scene);
  double total = 0.0;
  for (auto _ : state) {
    const Clock::time_point start = Clock::now();
    rig.collisions.beginStep(rig.particles, rig.topology, 1.0 / 60.0);
    const double seconds = secondsSince(start);
    state.SetIterationTime(seconds);
    total += seconds;
  }
  setCounters(state, rig.particles.cloth_count, total, rig.particles.cloth_count);
  state.SetLabel("per step, ns per cloth particle");
}

// A whole step of config/hanging.yaml's cloth per method, without tethers at 10 substeps (the
// scene's settings before it took tethers and 4 substeps on 2026-11-27, kept so the figures stay
// comparable: the methods differ in the links' projection, which tethers would mostly hide).
// mass_spring runs its cheapest stable setting on that scene instead (80 substeps, k = 1e3 N/m,
// bending springs 0.01): at 10 substeps it diverges.
void BM_HangingStep(benchmark::State& state) {
  SceneConfig scene;
  try {
    scene = loadScene(scenePath());
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  scene.solver.method = static_cast<Method>(state.range(0));
  scene.solver.substeps = 10;
  scene.cloth.tethers = false;
  if (scene.solver.method == Method::kMassSpring) {
    scene.solver.substeps = 80;
    scene.solver.spring_stiffness = 1e3;
    scene.solver.bend_spring_stiffness = 0.01;
  }
  Simulation sim(scene);
  long steps = 0;
  double total = 0.0;
  for (auto _ : state) {
    if (++steps % 180 == 0) sim.reset();  // stay within the 3 s of the sweeps
    const Clock::time_point start = Clock::now();
    sim.step();
    const double seconds = secondsSince(start);
    state.SetIterationTime(seconds);
    total += seconds;
  }
  const double particles = sim.particles().size();
  setCounters(state, particles, total, particles);
  state.SetLabel(std::string(toString(scene.solver.method)) + " " +
                 std::to_string(scene.solver.substeps) + "x" +
                 std::to_string(scene.solver.iterations) + ": whole step, per particle");
}

// A scene file next to config/hanging.yaml (the --scene flag moves them together).
std::string siblingScene(const std::string& name) {
  const std::string& hanging = scenePath();
  return hanging.substr(0, hanging.rfind('/') + 1) + name;
}

// One depth image (depth_camera.h) of a shipped scene, at the camera's size times range(1) / 2
// (2: as configured, 320 x 240; 4: 640 x 480, the focal lengths scaled alike so the view is
// the same). range(0) = 0: config/demo.yaml with its head camera after 1 s (a 20 x 20 towel on a
// table, a floor plane); 1: config/hanging.yaml (50 x 50, 4802 triangles) after 1 s, seen by the
// same camera 2 m in front of the cloth. The render thread's cost per image.
void BM_DepthRender(benchmark::State& state) {
  SceneConfig scene;
  try {
    scene = loadScene(siblingScene("demo.yaml"));
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  CameraConfig config = scene.cameras.at(0);
  if (state.range(0) == 1) {
    scene = loadScene(scenePath());
    // Optical z along world +y, x along world -x... looking at the cloth's centre from y = -2 m.
    config.pose.position = Eigen::Vector3d(0.5, -2.0, 1.0);
    config.pose.orientation = Eigen::Quaterniond(
        Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitX()).toRotationMatrix());
  }
  const double scale = state.range(1) / 2.0;
  config.width = static_cast<int>(config.width * scale);
  config.height = static_cast<int>(config.height * scale);
  config.fx *= scale;
  config.fy *= scale;
  config.cx = (config.width - 1) / 2.0;
  config.cy = (config.height - 1) / 2.0;
  Simulation sim(scene);
  for (int k = 0; k < scene.step_rate; ++k) sim.step();
  DepthSnapshot snapshot;
  snapshot.capture(sim);
  DepthRenderer renderer;
  const PinholeCamera camera = PinholeCamera::fromConfig(config);
  const Frame pose = frameFromPose(config.pose);
  std::vector<float> depth(camera.pixelCount());
  for (auto _ : state) {
    renderer.render(snapshot, camera, pose, depth.data());
    benchmark::DoNotOptimize(depth.data());
  }
  long seen = 0;
  for (float z : depth) seen += std::isfinite(z);
  state.counters["count"] = static_cast<double>(camera.pixelCount());
  state.counters["ns_per_item"] = 0.0;  // the image's time is the benchmark's own
  state.SetLabel(std::string(state.range(0) == 0 ? "demo.yaml " : "hanging.yaml ") +
                 std::to_string(camera.width) + "x" + std::to_string(camera.height) +
                 ": one image, " + std::to_string(seen) + " pixels see the scene");
}

// What a camera costs the step thread: copying the state out (DepthSnapshot::capture) of
// config/hanging.yaml (2500 particles).
void BM_DepthCapture(benchmark::State& state) {
  SceneConfig scene;
  try {
    scene = loadScene(scenePath());
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  Simulation sim(scene);
  sim.step();
  DepthSnapshot snapshot;
  snapshot.capture(sim);
  for (auto _ : state) {
    snapshot.capture(sim);
    benchmark::DoNotOptimize(snapshot.positions.data());
  }
  state.SetLabel("hanging.yaml: the step thread's share of one image");
}

// A cable of `segments` Cosserat segments (1 m, 5 mm radius, E = 10 MPa: a soft cable), held at
// one end, swinging under gravity: one step of 1 ms (1 kHz) at `substeps` substeps, each one direct
// solve of the whole rod (constraints/rod_constraints.h). Real time at 1 kHz: under 1 ms.
static void BM_RodStep(benchmark::State& state) {
  const int segments = static_cast<int>(state.range(0));
  RodMaterial material;
  material.radius = 0.005;
  material.young_modulus = 1e7;
  material.shear_modulus = 1e7 / 2.6;
  Rod rod = makeStraightRod(Vec3(0.0, 0.0, 1.0), Vec3(1.0, 0.0, 1.0), segments, material);
  rod.fixParticle(0);
  rod.fixSegment(0);
  RodStepSettings settings;
  settings.substeps = static_cast<int>(state.range(1));
  RodSolver solver;
  solver.prepare(segments);
  for (auto _ : state) {
    stepRod(rod, 1e-3, settings, solver);
    benchmark::DoNotOptimize(rod.position.back().data());
  }
  state.SetLabel("1 ms step, " + std::to_string(settings.substeps) + " substep(s)");
}

constexpr int kGaussSeidel = static_cast<int>(Ordering::kGaussSeidel);
constexpr int kJacobi = static_cast<int>(Ordering::kJacobi);
constexpr int kXpbd = static_cast<int>(Method::kXpbd);
constexpr int kPbd = static_cast<int>(Method::kPbd);
constexpr int kVerlet = static_cast<int>(Method::kVerlet);
constexpr int kMassSpring = static_cast<int>(Method::kMassSpring);

BENCHMARK(BM_StretchProjection)
    ->ArgNames({"method", "ordering", "passes"})
    ->Args({kXpbd, kGaussSeidel, 1})
    ->Args({kXpbd, kGaussSeidel, 10})
    ->Args({kXpbd, kGaussSeidel, 50})
    ->Args({kPbd, kGaussSeidel, 50})
    ->Args({kVerlet, kGaussSeidel, 50})
    ->Args({kXpbd, kJacobi, 50})
    ->UseManualTime()
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_StretchLinks)->ArgName("simd")->Arg(1)->Arg(0)->Arg(2)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_StretchBareLoop)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_RodStep)
    ->ArgNames({"segments", "substeps"})
    ->Args({100, 1})
    ->Args({100, 4})
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_DirectFactorize)->ArgName("rows")->Arg(50)->Arg(100)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_DirectSolve)->ArgName("rows")->Arg(50)->Arg(100)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FlatHinges)
    ->ArgNames({"path", "first", "keep"})
    ->Args({1, 1, 1})
    ->Args({1, 1, 0})
    ->Args({1, 0, 1})
    ->Args({2, 1, 1})
    ->Args({2, 1, 0})
    ->Args({2, 0, 1})
    ->Args({0, 1, 1})
    ->Args({0, 1, 0})
    ->Args({0, 0, 1})
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_BendProjection)
    ->ArgNames({"method", "passes"})
    ->Args({kXpbd, 10})
    ->Args({kPbd, 10})
    ->UseManualTime()
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SphereCollision)->UseManualTime()->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_MeshSphereCollision)
    ->ArgName("level")
    ->Arg(3)
    ->Arg(5)
    ->UseManualTime()
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_MeshSignedDistance)->ArgName("level")->Arg(3)->Arg(5)->Unit(benchmark::kNanosecond);
BENCHMARK(BM_MeshBuild)->ArgName("level")->Arg(3)->Arg(5)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ClothMeshLoadAndBuild)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ParticlePairs)->UseManualTime()->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SelfCollision)->UseManualTime()->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SelfCollisionBroadPhase)->UseManualTime()->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_DepthRender)
    ->ArgNames({"scene", "scale"})
    ->Args({0, 2})
    ->Args({0, 4})
    ->Args({1, 2})
    ->Args({1, 4})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_DepthCapture)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_HangingStep)
    ->ArgName("method")
    ->Arg(kVerlet)
    ->Arg(kPbd)
    ->Arg(kXpbd)
    ->Arg(kMassSpring)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace pbd_cloth

int main(int argc, char** argv) {
  // Our own flag first; Google Benchmark then checks that it knows every remaining one.
  std::vector<char*> args;
  const std::string scene_flag = "--scene=";
  for (int k = 0; k < argc; ++k) {
    const std::string arg = argv[k];
    if (k > 0 && arg.rfind(scene_flag, 0) == 0) {
      pbd_cloth::scenePath() = arg.substr(scene_flag.size());
    } else {
      args.push_back(argv[k]);
    }
  }
  int count = static_cast<int>(args.size());
  benchmark::Initialize(&count, args.data());
  if (benchmark::ReportUnrecognizedArguments(count, args.data())) return 1;
  std::cerr << "cloth_microbench: scene " << pbd_cloth::scenePath() << '\n';
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
