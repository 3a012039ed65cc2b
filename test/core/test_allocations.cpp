// The step allocates nothing once warm (issue 3: hot loops over flat arrays, free of allocation).
// Global operator new/delete are replaced for the whole test_core binary; they only count while
// `g_counting` is set, around sim.step() below, and otherwise behave like the default ones.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <new>
#include <string>
#include <utility>
#include <vector>

#include "collision_scenes.h"
#include "mesh_builders.h"
#include "obj_text.h"
#include "pbd_cloth/scene/scene_assets.h"
#include "pbd_cloth/sensors/depth_camera.h"
#include "pbd_cloth/sim/simulation.h"
#include "pbd_cloth/solver/rod_stepper.h"
#include "test_scenes.h"

namespace {
std::atomic<bool> g_counting{false};
std::atomic<long> g_allocations{0};

void* allocate(std::size_t size) {
  if (g_counting.load(std::memory_order_relaxed)) {
    g_allocations.fetch_add(1, std::memory_order_relaxed);
  }
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
}  // namespace

void* operator new(std::size_t size) { return allocate(size); }
void* operator new[](std::size_t size) { return allocate(size); }
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  if (g_counting.load(std::memory_order_relaxed)) {
    g_allocations.fetch_add(1, std::memory_order_relaxed);
  }
  return std::malloc(size == 0 ? 1 : size);
}
void* operator new[](std::size_t size, const std::nothrow_t& tag) noexcept {
  return operator new(size, tag);
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }

namespace pbd_cloth {
namespace {

// Allocations during `steps` steps after 3 warm-up steps.
long allocationsPerRun(const SceneConfig& scene, int steps) {
  Simulation sim(scene);
  for (int k = 0; k < 3; ++k) sim.step();
  g_allocations = 0;
  g_counting = true;
  for (int k = 0; k < steps; ++k) sim.step();
  g_counting = false;
  return g_allocations.load();
}

// The counter itself works (otherwise a 0 below would prove nothing).
TEST(Allocations, CounterSeesAllocations) {
  static std::vector<double>* volatile sink = nullptr;  // volatile: the pair cannot be elided
  g_allocations = 0;
  g_counting = true;
  sink = new std::vector<double>(100);
  g_counting = false;
  delete sink;
  EXPECT_GE(g_allocations.load(), 2);  // the vector object and its buffer
}

// A 20 x 20 cloth pinned at two corners, with bending and tethers, every method and ordering.
TEST(Allocations, SolverStepAllocatesNothingAfterWarmUp) {
  for (Method method : {Method::kVerlet, Method::kPbd, Method::kXpbd, Method::kMassSpring}) {
    for (Ordering ordering : {Ordering::kGaussSeidel, Ordering::kJacobi}) {
      SceneConfig scene = test::clothScene(20, 20, 0.03, method);
      scene.cloth.pinned = {0, 19};
      scene.cloth.bend_compliance = 1e-3;
      scene.cloth.tethers = true;
      scene.solver.substeps = 4;
      scene.solver.iterations = 2;
      scene.solver.ordering = ordering;
      const long count = allocationsPerRun(scene, 10);
      EXPECT_EQ(count, 0) << toString(method) << " " << toString(ordering);
    }
  }
}

// The whole step as the node runs it: self-collision, an obstacle and a bounds box too.
TEST(Allocations, StepWithCollisionsAllocatesNothingAfterWarmUp) {
  for (Method method : {Method::kXpbd, Method::kVerlet}) {
    SceneConfig scene = test::clothScene(20, 20, 0.03, method);
    scene.cloth.origin = Eigen::Vector3d(-0.3, 0.3, 0.2);
    scene.cloth.bend_compliance = 1e-3;
    scene.cloth.self_collision = true;
    scene.solver.substeps = 4;
    ObstacleConfig ball;
    ball.name = "ball";
    ball.shape = ShapeType::kSphere;
    ball.radius = 0.15;
    scene.obstacles = {ball};
    scene.bounds.enabled = true;
    scene.bounds.min = Eigen::Vector3d(-1.0, -1.0, -0.2);
    scene.bounds.max = Eigen::Vector3d(1.0, 1.0, 1.0);
    // 20 steps after warm-up: the cloth reaches the ball and drapes over it.
    const long count = allocationsPerRun(scene, 20);
    EXPECT_EQ(count, 0) << toString(method);
  }
}

// Scripted grasps and releases fire inside the step (followTrajectories): a gripper takes hold of
// the loose corner of a cloth pinned at one corner, lifts it, lets go, and takes hold again, all
// within the counted steps (after 3 warm-up steps at t = 0.05 s), with and without tethers (each
// grasp and release rebuilds them in the room build() left), on the grid and on the same grid
// read as a mesh (its tethers come from searches along the edges).
TEST(Allocations, ScriptedGraspAndReleaseAllocateNothing) {
  struct Case {
    Method method;
    bool tethers, mesh;
  };
  for (const Case& c : {Case{Method::kXpbd, false, false}, Case{Method::kXpbd, true, false},
                        Case{Method::kXpbd, true, true}, Case{Method::kVerlet, false, false}}) {
    const Method method = c.method;
    const bool tethers = c.tethers;
    SceneConfig scene = test::clothScene(20, 20, 0.03, method);
    if (c.mesh) {
      // The grid's particles, numbered as the grid's (no jitter), as a mesh.
      const std::string path =
          test::writeObj("pbd_cloth_allocations_grid.obj", test::squareObj(20, 0.03, 0.0, 1));
      scene.cloth.mesh = path;
      loadClothMesh(scene);
    }
    scene.cloth.tethers = tethers;
    scene.cloth.pinned = {0};
    scene.cloth.bend_compliance = 1e-3;
    scene.solver.gravity.setZero();
    scene.solver.substeps = 4;
    const Eigen::Vector3d corner(19 * 0.03, 0.0, 0.0);  // particle 19, the loose top corner
    GripperConfig gripper;
    gripper.name = "hand";
    gripper.radius = 0.05;  // particles 18, 19, 38 and 39; the next ones are 6 cm away
    const auto waypoint = [&corner](double t, double lift, int grasp) {
      Waypoint w;
      w.t = t;
      w.pose.position = corner + Eigen::Vector3d(0.0, 0.0, lift);
      w.grasp = grasp;
      return w;
    };
    // Each lift ends 0.05 s before the release, so the corner is at rest when it is let go and
    // still within reach for the second grasp.
    gripper.trajectory = {waypoint(0.0, 0.0, -1), waypoint(0.1, 0.0, 1),  waypoint(0.25, 0.02, -1),
                          waypoint(0.3, 0.02, 0), waypoint(0.4, 0.02, 1), waypoint(0.55, 0.04, -1),
                          waypoint(0.6, 0.04, 0)};
    scene.grippers = {gripper};
    Simulation sim(scene);
    for (int k = 0; k < 3; ++k) sim.step();
    ASSERT_FALSE(sim.grippers().grasping(0));
    int grasps = 0, releases = 0;
    std::size_t most_tethers = 0;
    bool holding = false;
    g_allocations = 0;
    for (int k = 0; k < 42; ++k) {  // to t = 0.75 s
      g_counting = true;
      sim.step();
      g_counting = false;
      if (sim.grippers().grasping(0) != holding) {
        holding = !holding;
        ++(holding ? grasps : releases);
      }
      most_tethers = std::max(most_tethers, sim.topology().tethers.size());
    }
    EXPECT_EQ(grasps, 2) << toString(method) << ": the script's grasps did not happen";
    EXPECT_EQ(releases, 2) << toString(method);
    EXPECT_EQ(g_allocations.load(), 0)
        << toString(method) << " tethers " << tethers << " mesh " << c.mesh;
    // While held: the 395 free particles tethered to the pin and to the hand's 4 particles.
    if (tethers) EXPECT_EQ(most_tethers, 395u * 2u);
  }
}

// A rope's step (a Cosserat rod's direct solve) allocates nothing once its solver is prepared.
TEST(Allocations, RodStepAllocatesNothing) {
  Rod rod = makeStraightRod(Vec3(0.0, 0.0, 1.0), Vec3(1.0, 0.0, 1.0), 50, RodMaterial());
  rod.fixParticle(0);
  rod.fixSegment(0);
  RodSolver solver;
  solver.prepare(rod.segments());
  RodStepSettings settings;
  stepRod(rod, 1.0 / 60.0, settings, solver);
  g_allocations = 0;
  g_counting = true;
  for (int k = 0; k < 10; ++k) stepRod(rod, 1.0 / 60.0, settings, solver);
  g_counting = false;
  EXPECT_EQ(g_allocations.load(), 0);
  EXPECT_LT(rod.position.back().z(), 1.0);  // it moved: the steps ran
}

// Fault recovery checks every step and undoes a failed one from buffers sized at build: a NaN
// and a blow-up injected in the counted steps are caught and undone without allocating.
TEST(Allocations, FaultRecoveryAllocatesNothing) {
  SceneConfig scene = test::clothScene(20, 20, 0.03, Method::kXpbd);
  scene.cloth.pinned = {0, 19};
  scene.solver.substeps = 4;
  Simulation sim(scene);
  sim.setFaultRecovery(true);
  for (int k = 0; k < 3; ++k) sim.step();
  g_allocations = 0;
  g_counting = true;
  for (int k = 0; k < 10; ++k) {
    if (k == 3) sim.injectFaultForTesting(InjectedFault::kNaN);
    if (k == 6) sim.injectFaultForTesting(InjectedFault::kBlowUp);
    sim.step();
  }
  g_counting = false;
  EXPECT_EQ(sim.faultGuard().restoredSteps(), 2u);
  EXPECT_EQ(g_allocations.load(), 0);
}

// Accuracy on demand (solver.target_max_strain): choosing the substeps, and running a step again
// from its start (the particles and the collisions' step state restored, an obstacle among them),
// allocate nothing: a cloth swinging down from two pins past a ball, with a target two substeps
// cannot meet.
TEST(Allocations, AccuracyTargetAndRedoneStepsAllocateNothing) {
  SceneConfig scene = test::clothScene(20, 20, 0.03, Method::kXpbd);
  scene.cloth.pinned = {0, 19};
  scene.solver.substeps = 2;
  scene.solver.target_max_strain = 0.002;
  scene.solver.max_substeps = 1000;
  scene.obstacles = {test::sphere("ball", 0.1, test::makePose(Vec3(0.3, -0.3, -0.3)))};
  Simulation sim(scene);
  for (int k = 0; k < 3; ++k) sim.step();
  SolverConfig tighter = scene.solver;  // the substeps chosen so far are no longer enough
  tighter.target_max_strain = 0.0002;
  sim.setSolverConfig(tighter);
  g_allocations = 0;
  g_counting = true;
  int redone = 0;
  for (int k = 0; k < 20; ++k) {
    sim.step();
    redone += sim.accuracy().redos;
  }
  g_counting = false;
  EXPECT_GT(redone, 0);  // the path that restores a step ran
  EXPECT_EQ(g_allocations.load(), 0);
}

// Forward kinematics runs every step: with `out` at its size it allocates nothing (a revolute,
// prismatic, fixed and mimic joint on the way).
TEST(Allocations, RobotLinkPosesAllocateNothing) {
  SceneConfig scene;
  scene.robot.urdf_file = std::string(PBD_CLOTH_SOURCE_DIR) + "/test/data/planar_arm.urdf";
  loadRobotFile(scene);
  const RobotModel& model = scene.robot.model;
  std::vector<double> positions(model.joints.size(), 0.2);
  std::vector<Pose> poses(model.links.size());
  g_allocations = 0;
  g_counting = true;
  for (int k = 0; k < 100; ++k) {
    positions[0] = 0.01 * k;
    model.linkPoses(Pose(), positions, poses);
  }
  g_counting = false;
  EXPECT_EQ(g_allocations.load(), 0);
  EXPECT_EQ(poses.size(), model.links.size());
}

// A depth camera runs beside the step (the node's render thread): once its buffers have their
// sizes, capturing the state and rendering it (cloth, a mesh, analytic shapes) allocate nothing.
TEST(Allocations, DepthCaptureAndRenderAllocateNothingOnceWarm) {
  SceneConfig scene = test::clothScene(20, 20, 0.025, Method::kXpbd);
  scene.cloth.origin = Eigen::Vector3d(-0.25, 0.25, 0.5);
  ObstacleConfig ball;
  ball.name = "ball";
  ball.radius = 0.1;
  Pose at;
  at.position = Eigen::Vector3d(0.3, 0.0, 0.2);
  ObstacleConfig mesh = test::meshObstacle("mesh", test::icosphere(0.1, 2), at);
  ObstacleConfig floor;
  floor.name = "floor";
  floor.shape = ShapeType::kPlane;
  scene.obstacles = {ball, mesh, floor};
  Simulation sim(scene);
  DepthSnapshot snapshot;
  DepthRenderer renderer;
  PinholeCamera camera;
  Frame pose;
  pose.rotation = Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()).toRotationMatrix();
  pose.translation = Eigen::Vector3d(0.0, 0.0, 1.5);
  std::vector<float> depth(camera.pixelCount());
  snapshot.capture(sim);
  renderer.render(snapshot, camera, pose, depth.data());
  sim.step();
  g_allocations = 0;
  g_counting = true;
  for (int k = 0; k < 5; ++k) {
    snapshot.capture(sim);
    renderer.render(snapshot, camera, pose, depth.data());
  }
  g_counting = false;
  EXPECT_EQ(g_allocations.load(), 0);
  int seen = 0;
  for (float z : depth) seen += std::isfinite(z);
  EXPECT_GT(seen, 1000);  // it did draw something
}

// A 10 x 10 cloth with self-collision whose particles all move at 52 m/s, alternately one way and
// the other along a diagonal (what a gripper jump across the cloth does in the soak): every swept
// box crosses the whole cloth, so that step's self-collision candidates outgrow their reserve.
// Once the extreme is over, releaseExcessCapacity gives the excess back between steps (the node
// calls it every 5 s), and the run goes on bit for bit as one that never released anything. The
// search runs on one thread whatever solver.threads says: two threads release the same bytes.
std::size_t releasedAfterExtremeStep(int threads);

TEST(Allocations, ExtremeStepGrowthIsReleasedBetweenStepsWithoutChangingTheResult) {
  const std::size_t one_thread = releasedAfterExtremeStep(1);
  ASSERT_FALSE(HasFatalFailure());
  const std::size_t two_threads = releasedAfterExtremeStep(2);
  EXPECT_EQ(two_threads, one_thread);
}

std::size_t releasedAfterExtremeStep(int threads) {
  SceneConfig scene = test::clothScene(10, 10, 0.05, Method::kXpbd);
  scene.cloth.self_collision = true;
  scene.solver.substeps = 4;
  scene.solver.threads = threads;
  Simulation kept(scene), released(scene);
  // Both simulations continue from their own state with every velocity replaced.
  const auto set_velocities = [&](auto velocity_of) {
    for (Simulation* sim : {&kept, &released}) {
      SimulationState state;
      sim->getState(state);
      for (std::size_t i = 0; i < state.velocity.size(); ++i) state.velocity[i] = velocity_of(i);
      std::string reason;
      ASSERT_TRUE(sim->setState(state, reason)) << reason;
    }
  };
  set_velocities([](std::size_t i) {
    const double v = i % 2 == 0 ? 30.0 : -30.0;
    return Vec3(v, v, v);
  });
  if (::testing::Test::HasFatalFailure()) return 0;
  EXPECT_EQ(released.releaseExcessCapacity(), 0u) << "nothing has grown before the first step";
  g_allocations = 0;
  g_counting = true;
  released.step();
  g_counting = false;
  EXPECT_GT(g_allocations.load(), 0) << "the extreme step did not outgrow the reserve: the test "
                                        "no longer exercises the release";
  kept.step();
  // The candidate lists still hold that step's pairs: kept. The search's list of vertex-triangle
  // pairs (sorted before they join the candidates) is scratch, emptied after each search: given
  // back at once.
  std::size_t bytes = released.releaseExcessCapacity();
  EXPECT_GT(bytes, 0u) << "the search's scratch list grew in that step";
  // The extreme is over: both come to rest where they are, and step on.
  set_velocities([](std::size_t) { return Vec3(0.0, 0.0, 0.0); });
  if (::testing::Test::HasFatalFailure()) return 0;
  for (int k = 0; k < 30; ++k) {
    kept.step();
    released.step();
    bytes += released.releaseExcessCapacity();
  }
  EXPECT_GT(bytes, 0u);
  for (int i = 0; i < kept.particles().size(); ++i) {
    EXPECT_EQ(kept.particles().position[i], released.particles().position[i]) << "particle " << i;
    EXPECT_EQ(kept.particles().velocity[i], released.particles().velocity[i]) << "particle " << i;
  }
  return bytes;
}

}  // namespace
}  // namespace pbd_cloth
