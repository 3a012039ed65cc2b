// Saving and restoring the simulation state (saved_state.h): a run of 2 s equals, bit for bit, a
// run of 1 s whose state is saved, written to the state file format, read back, set into a fresh
// Simulation and run 1 s more; on scenes with a grasping gripper, moving obstacles, friction,
// self-collision, granular particles and a robot with mesh links. A state that does not fit the
// scene is refused with the field named, and nothing changes.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <limits>
#include <memory>
#include <sstream>
#include <string>

#include "collision_scenes.h"
#include "pbd_cloth/scene/scene_yaml.h"
#include "pbd_cloth/sim/simulation.h"
#include "pbd_cloth/state/saved_state.h"

namespace pbd_cloth {
namespace {

const std::string kConfig = std::string(PBD_CLOTH_SOURCE_DIR) + "/config/";
// The corner of config/demo.yaml's towel (its particle 0), where the scripted grasps take it.
const Vec3 kDemoCorner(-0.2375, 0.2375, 0.406);

SceneConfig shippedScene(const std::string& file, const std::vector<std::string>& overrides = {}) {
  YAML::Node root = loadSceneYaml(kConfig + file);
  for (const std::string& assignment : overrides) applyOverride(root, assignment);
  return sceneFromYaml(root, sceneFileDirectory(kConfig + file));
}

// Live inputs a node would give before step `k` (0-based); the same on every path.
using Drive = std::function<void(Simulation&, int)>;

void run(Simulation& sim, int from, int to, const Drive& drive) {
  for (int k = from; k < to; ++k) {
    if (drive) drive(sim, k);
    sim.step();
  }
}

bool sameBits(const Vec3Array& a, const Vec3Array& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(Vec3)) == 0;
}

std::string bytesOf(const SimulationState& state) {
  std::ostringstream out;
  writeState(out, state);
  return out.str();
}

// Runs `total` steps straight; saves the state after `split`, round-trips it through the file
// format, sets it into a fresh Simulation (and into one that ran elsewhere meanwhile) and runs the
// rest. Returns the state at the split for further checks.
SimulationState expectContinuesBitForBit(const SceneConfig& scene, int split, int total,
                                         const Drive& drive = Drive()) {
  Simulation straight(scene);
  run(straight, 0, split, drive);
  SimulationState saved;
  straight.getState(saved);
  run(straight, split, total, drive);

  std::stringstream file;
  writeState(file, saved);
  SimulationState loaded;
  std::string reason;
  EXPECT_TRUE(readState(file, loaded, reason)) << reason;
  EXPECT_EQ(bytesOf(loaded), bytesOf(saved));

  Simulation fresh(scene);
  EXPECT_TRUE(fresh.setState(loaded, reason)) << reason;
  EXPECT_EQ(fresh.time(), saved.time);
  run(fresh, split, total, drive);

  // A simulation that has been elsewhere (other steps, another grasp) continues the same way.
  Simulation used(scene);
  run(used, 0, split / 2 + 3, drive);
  EXPECT_TRUE(used.setState(loaded, reason)) << reason;
  run(used, split, total, drive);

  for (const Simulation* resumed : {&fresh, &used}) {
    EXPECT_EQ(resumed->time(), straight.time());
    EXPECT_TRUE(sameBits(resumed->particles().position, straight.particles().position));
    EXPECT_TRUE(sameBits(resumed->particles().velocity, straight.particles().velocity));
    SimulationState a, b;
    resumed->getState(a);
    straight.getState(b);
    EXPECT_EQ(bytesOf(a), bytesOf(b)) << "the whole state, grippers and caches included";
  }
  // Not a trivial agreement: the second half moved the cloth.
  EXPECT_FALSE(sameBits(saved.position, straight.particles().position));
  return saved;
}

// The demo towel on its table, its corner grasped at 0.1 s by a scripted gripper, carried over the
// towel (friction on the table, self-collision of the fold) and released at 1.7 s: the grasp spans
// the save at 1 s, the release (with the gripper's velocity) comes after it.
TEST(SimState, DemoFoldWithScriptedGraspContinuesBitForBit) {
  SceneConfig scene = shippedScene("demo.yaml");
  using test::makePose;
  scene.grippers[0].trajectory = {{0.0, makePose(kDemoCorner), -1},
                                  {0.1, makePose(kDemoCorner), 1},
                                  {0.8, makePose(Vec3(0.0, 0.0, 0.6)), -1},
                                  {1.5, makePose(Vec3(0.2, -0.2, 0.45)), -1},
                                  {1.7, makePose(Vec3(0.2, -0.2, 0.45)), 0}};
  const SimulationState saved = expectContinuesBitForBit(scene, 60, 120);
  ASSERT_EQ(saved.grippers.size(), 1u);
  EXPECT_FALSE(saved.grippers[0].grasped.empty()) << "the grasp spans the save";
  EXPECT_EQ(saved.grippers[0].next_waypoint, 3u);
}

// A repeating script (grippers[i].repeat, period 0.6 s): the corner is grasped at 0.1 s, lifted,
// released at 0.5 s, and grasped again at 0.7 s in the second period; the gripper is where it was
// a period before; the save falls in the second period (next_waypoint counts past the waypoints
// of the first) and the run continues bit for bit.
TEST(SimState, RepeatingTrajectoryGraspsEveryPeriodAndContinuesBitForBit) {
  SceneConfig scene = shippedScene("demo.yaml");
  using test::makePose;
  scene.grippers[0].repeat = true;
  scene.grippers[0].trajectory = {{0.0, makePose(kDemoCorner), -1},
                                  {0.1, makePose(kDemoCorner), 1},
                                  {0.4, makePose(kDemoCorner + Vec3(0.0, 0.0, 0.1)), -1},
                                  {0.5, makePose(kDemoCorner + Vec3(0.0, 0.0, 0.1)), 0},
                                  {0.6, makePose(kDemoCorner), -1}};
  validate(scene);

  Simulation sim(scene);
  std::vector<bool> grasping;  // after each step
  std::vector<Vec3> gripper_at;
  for (int k = 0; k < 72; ++k) {
    sim.step();
    grasping.push_back(sim.grippers().grasping(0));
    gripper_at.push_back(sim.grippers().pose(0).position);
  }
  // Step k ends at (k + 1) / 60 s; events fire at the start of the step they fall in.
  EXPECT_FALSE(grasping[4]) << "0.083 s: not yet";
  EXPECT_TRUE(grasping[10]) << "0.183 s: grasped";
  EXPECT_FALSE(grasping[33]) << "0.567 s: released";
  EXPECT_TRUE(grasping[45]) << "0.767 s: grasped again in the second period";
  for (int k = 0; k + 36 < 72; ++k) {
    EXPECT_LT((gripper_at[k + 36] - gripper_at[k]).norm(), 1e-9) << "step " << k;
  }
  EXPECT_GT((gripper_at[20] - kDemoCorner).norm(), 0.05) << "0.35 s: lifted";

  const SimulationState saved = expectContinuesBitForBit(scene, 48, 96);
  EXPECT_EQ(saved.grippers[0].next_waypoint, 7u)
      << "5 waypoints of the first period, 2 of the second";
  EXPECT_FALSE(saved.grippers[0].grasped.empty()) << "the second grasp spans the save";
}

// The same fold with Verlet (its velocity is the half-step velocity x_n - x_{n-1}).
TEST(SimState, VerletContinuesBitForBit) {
  SceneConfig scene = shippedScene("demo.yaml", {"solver.method=verlet"});
  Pose corner = test::makePose(kDemoCorner);
  Pose up = corner;
  up.position.z() += 0.3;
  scene.grippers[0].trajectory = {{0.0, corner, 1}, {1.5, up, -1}};
  expectContinuesBitForBit(scene, 60, 120);
}

// A state's positions are taken as they are, pinned particles included (doc/scenes.md "Saving and
// restoring state"): a pinned corner moved 10 cm in the state is accepted, stays exactly there
// through the steps after, and the cloth hangs from it (its neighbour follows within a link; with
// tethers, as "Choosing a method" advises for a hanging cloth and hanging.yaml has: without them
// the links at its pins stretch by tens of per cent).
TEST(SimState, PinnedParticlesStayWhereTheStatePutsThem) {
  SceneConfig scene = shippedScene("hanging.yaml", {"cloth.tethers=true"});
  Simulation sim(scene);
  for (int k = 0; k < 30; ++k) sim.step();
  SimulationState state;
  sim.getState(state);
  const int pin = scene.cloth.pinned.front();
  ASSERT_TRUE(sim.particles().isKinematic(pin));
  const Vec3 moved = state.position[pin] + Vec3(0.1, 0.0, 0.05);
  state.position[pin] = moved;
  std::string reason;
  ASSERT_TRUE(sim.setState(state, reason)) << reason;
  for (int k = 0; k < 120; ++k) sim.step();
  EXPECT_EQ(sim.particles().position[pin], moved);
  EXPECT_EQ(sim.particles().velocity[pin], Vec3::Zero());
  const int neighbour = pin + 1;  // the next particle of the top row
  const double link = scene.cloth.spacing;
  EXPECT_LT((sim.particles().position[neighbour] - moved).norm(), 1.01 * link);
  EXPECT_TRUE(sim.computeMetrics().finite);
}

// The drape scene (ball, table, floor; friction; self-collision) with a live gripper that grasps
// an edge and pulls it (released after the save) and the ball moved by live poses, as the node
// drives them.
TEST(SimState, DrapeWithLiveGripperAndMovingObstacleContinuesBitForBit) {
  SceneConfig scene =
      shippedScene("drape.yaml", {"grippers=[{name: pinch, radius: 0.08}]", "cloth.rows=24",
                                  "cloth.cols=24", "cloth.spacing=0.04"});
  const int ball = 0;
  const Drive drive = [ball](Simulation& sim, int k) {
    Pose pose;
    pose.position = Vec3(0.1 * std::sin(0.05 * k), 0.0, 0.5);
    sim.setObstaclePose(ball, pose);
    Pose grip = sim.grippers().pose(0);
    if (k == 19) grip.position = sim.particles().position[0];
    if (k > 20) grip.position.z() += 0.004;
    if (k >= 19) sim.setGripperPose(0, grip);
    if (k == 20) sim.setGrasp(0, true);
    if (k == 90) sim.setGrasp(0, false);
  };
  const SimulationState saved = expectContinuesBitForBit(scene, 60, 120, drive);
  EXPECT_FALSE(saved.grippers[0].grasped.empty());
  EXPECT_TRUE(saved.grippers[0].live);
}

// The drape at 64 x 64 (the scaling benchmark's settings), saved while the adaptive contact
// search window (collisions.h) is shorter than the step: the window is carried with the state.
TEST(SimState, DrapeWithAShortSearchWindowContinuesBitForBit) {
  const int n = 64;
  const double spacing = 0.93 / (n - 1);
  SceneConfig scene = shippedScene(
      "drape.yaml", {"cloth.rows=64", "cloth.cols=64", "cloth.spacing=" + std::to_string(spacing),
                     "cloth.thickness=" + std::to_string(spacing / 6.0)});
  const SimulationState saved = expectContinuesBitForBit(scene, 24, 30);
  EXPECT_GE(saved.search_window, 1);
  EXPECT_LT(saved.search_window, scene.solver.substeps);
}

// Granular particles poured on a hanging cloth: particle-particle contacts with friction.
TEST(SimState, GranularPileContinuesBitForBit) {
  const SceneConfig scene =
      shippedScene("hanging.yaml",
                   {"cloth.rows=12", "cloth.cols=12", "cloth.spacing=0.05", "cloth.pinned=[0,11]",
                    "granular={count: 60, radius: 0.01, mass: 0.001, "
                    "region: {min: [0.1, -0.3, 1.2], max: [0.3, -0.1, 1.4]}}"});
  expectContinuesBitForBit(scene, 60, 120);
}

// The robot demo's arm (mesh links, padding, friction) with its script four times as fast, so
// the forearm sweeps through the hanging cloth (tethers, self-collision) across the save: the
// mesh links' contact caches are part of the state.
TEST(SimState, RobotWithMeshLinksSweepingTheClothContinuesBitForBit) {
  setenv("ROS_PACKAGE_PATH", PBD_CLOTH_SOURCE_DIR, 1);  // the URDF's package:// meshes
  SceneConfig scene = shippedScene("robot_demo.yaml", {"robot.urdf_file=../urdf/demo_arm.urdf"});
  for (JointWaypoint& waypoint : scene.robot.joint_trajectory) waypoint.t *= 0.25;
  const SimulationState saved = expectContinuesBitForBit(scene, 60, 120);
  EXPECT_FALSE(saved.mesh_contacts.empty()) << "the arm's meshes were queried before the save";
  EXPECT_EQ(saved.robot_links.size(), scene.robot.model.links.size());
}

// A mesh cloth (the shipped T-shirt hung from its shoulders: curved rest hinges, mesh-geodesic
// tethers, self-collision between its two layers).
TEST(SimState, MeshClothContinuesBitForBit) {
  setenv("ROS_PACKAGE_PATH", PBD_CLOTH_SOURCE_DIR, 1);  // its package:// OBJ
  expectContinuesBitForBit(shippedScene("tshirt_hanging.yaml"), 15, 30);
}

// --- Refusals ---------------------------------------------------------------------------------

class SimStateRefusal : public ::testing::Test {
 protected:
  void SetUp() override {
    SceneConfig scene = shippedScene("demo.yaml");
    const Pose corner = test::makePose(kDemoCorner);
    scene.grippers[0].trajectory = {{0.0, corner, 1}};
    sim_ = std::make_unique<Simulation>(scene);
    run(*sim_, 0, 10, Drive());
    sim_->getState(good_);
    ASSERT_FALSE(good_.grippers[0].grasped.empty());
  }

  // Refused, with `field` in the reason, and the simulation exactly as it was.
  void expectRefused(const SimulationState& bad, const std::string& field) {
    SimulationState before;
    sim_->getState(before);
    const std::vector<double> inverse_mass = sim_->particles().inverse_mass;
    std::string reason;
    EXPECT_FALSE(sim_->setState(bad, reason));
    EXPECT_NE(reason.find(field), std::string::npos) << "reason: " << reason;
    SimulationState after;
    sim_->getState(after);
    EXPECT_EQ(bytesOf(after), bytesOf(before));
    EXPECT_EQ(sim_->particles().inverse_mass, inverse_mass);
  }

  std::unique_ptr<Simulation> sim_;
  SimulationState good_;
};

TEST_F(SimStateRefusal, WrongParticleCount) {
  SimulationState bad = good_;
  bad.position.pop_back();
  expectRefused(bad, "positions: 399 given, the scene has 400 particles");
}

TEST_F(SimStateRefusal, NonFiniteValues) {
  SimulationState bad = good_;
  bad.velocity[7].y() = std::numeric_limits<double>::quiet_NaN();
  expectRefused(bad, "velocities[7]: not finite");
  bad = good_;
  bad.position[3].x() = std::numeric_limits<double>::infinity();
  expectRefused(bad, "positions[3]");
  bad = good_;
  bad.grippers[0].target.orientation.w() = std::numeric_limits<double>::quiet_NaN();
  expectRefused(bad, "grippers[0].target.orientation");
  bad = good_;
  bad.colliders[1].pose.position.z() = std::numeric_limits<double>::quiet_NaN();
  expectRefused(bad, "colliders[1].pose.position");
  bad = good_;
  bad.time = -1.0;
  expectRefused(bad, "time");
}

TEST_F(SimStateRefusal, GraspsThatDoNotFit) {
  SimulationState bad = good_;
  bad.grippers[0].grasped[0] = 400;
  expectRefused(bad, "grippers[0].grasped[0]: particle 400 is not a cloth particle");
  bad = good_;
  bad.grippers[0].grasped.push_back(bad.grippers[0].grasped[0]);
  bad.grippers[0].grasp_offsets.push_back(Vec3::Zero());
  expectRefused(bad, "is held twice");
  bad = good_;
  bad.grippers[0].grasp_offsets.pop_back();
  expectRefused(bad, "grippers[0].grasp_offsets");
  bad = good_;
  bad.grippers[0].next_waypoint = 5;
  expectRefused(bad, "grippers[0].next_waypoint");
}

TEST_F(SimStateRefusal, BodiesOfAnotherScene) {
  SimulationState bad = good_;
  bad.grippers[0].name = "left";
  expectRefused(bad, "grippers[0].name: 'left', the scene's is 'hand'");
  bad = good_;
  bad.grippers.clear();
  expectRefused(bad, "grippers: 0 given, the scene has 1");
  bad = good_;
  bad.colliders.pop_back();
  expectRefused(bad, "colliders: 1 given");
  bad = good_;
  bad.robot_links.push_back(BodySnapshot());
  expectRefused(bad, "robot_links: 1 given, the scene has 0");
  bad = good_;
  bad.search_window = -1;
  expectRefused(bad, "search_window: -1 is not in [0, 1000] substeps");
  bad = good_;
  bad.mesh_contacts.push_back(MeshContactCache());
  expectRefused(bad, "mesh_contacts[0].collider: 0 is not a mesh collider");
}

TEST(SimStateFile, BadFilesAreRefusedWithTheReason) {
  Simulation sim(shippedScene("demo.yaml"));
  SimulationState state;
  sim.getState(state);
  std::stringstream file;
  writeState(file, state);
  const std::string bytes = file.str();
  SimulationState read;
  std::string reason;

  std::istringstream truncated(bytes.substr(0, bytes.size() / 2));
  EXPECT_FALSE(readState(truncated, read, reason));
  EXPECT_NE(reason.find("bytes"), std::string::npos) << reason;

  std::istringstream not_a_state("index,x,y,z\n0,1,2,3\n");
  EXPECT_FALSE(readState(not_a_state, read, reason));
  EXPECT_NE(reason.find("not a pbd_cloth state file"), std::string::npos) << reason;

  std::string newer = bytes;
  newer[8] = static_cast<char>(kStateFileVersion + 1);
  std::istringstream future(newer);
  EXPECT_FALSE(readState(future, read, reason));
  EXPECT_NE(reason.find("version " + std::to_string(kStateFileVersion + 1)), std::string::npos)
      << reason;

  // Version 1 had no search window (4 bytes), version 2 no chosen substeps and calm steps (8
  // bytes) and version 3 no ropes' segments (two counts of 8 bytes here, the last): all still
  // read, with none chosen and no ropes.
  const std::size_t ropes = 16;
  std::string first = bytes.substr(0, bytes.size() - 12 - ropes);
  first[8] = 1;
  std::istringstream old_file(first);
  ASSERT_TRUE(readState(old_file, read, reason)) << reason;
  EXPECT_EQ(read.search_window, 0);
  EXPECT_EQ(read.chosen_substeps, 0);
  EXPECT_TRUE(sameBits(read.position, state.position));
  std::string second = bytes.substr(0, bytes.size() - 8 - ropes);
  second[8] = 2;
  std::istringstream second_file(second);
  ASSERT_TRUE(readState(second_file, read, reason)) << reason;
  EXPECT_EQ(read.search_window, state.search_window);
  EXPECT_EQ(read.chosen_substeps, 0);
  std::string third = bytes.substr(0, bytes.size() - ropes);
  third[8] = 3;
  std::istringstream third_file(third);
  ASSERT_TRUE(readState(third_file, read, reason)) << reason;
  EXPECT_EQ(read.chosen_substeps, state.chosen_substeps);
  EXPECT_TRUE(read.rope_orientations.empty());

  std::istringstream trailing(bytes + "x");
  EXPECT_FALSE(readState(trailing, read, reason));
  EXPECT_NE(reason.find("1 bytes after the end"), std::string::npos) << reason;

  EXPECT_FALSE(readStateFile("/nonexistent/dir/state.bin", read, reason));
  EXPECT_NE(reason.find("/nonexistent/dir/state.bin"), std::string::npos) << reason;
}

TEST(SimStateFile, SolverDataRoundTripsAndEmptyMeansPositions) {
  SimulationState state;
  state.substep_start = {Vec3(1.0 / 3.0, -0.0, 1e-300)};
  state.mesh_contacts = {{4, 2, 17, 0.125, Vec3(0.1, 0.2, 0.3)}};
  state.search_window = 3;
  SimulationState read;
  std::string reason;
  ASSERT_TRUE(decodeSolverData(encodeSolverData(state), read, reason)) << reason;
  EXPECT_TRUE(sameBits(read.substep_start, state.substep_start));
  ASSERT_EQ(read.mesh_contacts.size(), 1u);
  EXPECT_EQ(read.mesh_contacts[0].triangle, 17);
  EXPECT_EQ(read.search_window, 3);
  EXPECT_FALSE(decodeSolverData({1, 2, 3}, read, reason));
  EXPECT_NE(reason.find("solver_data"), std::string::npos) << reason;
}

}  // namespace
}  // namespace pbd_cloth
