// Live tuning of cloth_node through dynamic_reconfigure (reconfigure.test, small_scene.yaml):
// the server starts from the scene, a change shows in ~state from the next steps on, a value the
// scene validation refuses is counted and snaps back, and a value outside Solver.cfg's range is
// clamped by dynamic_reconfigure before the node sees it (applied clamped, not counted).
#include <string>

#include <dynamic_reconfigure/Config.h>
#include <dynamic_reconfigure/Reconfigure.h>
#include <gtest/gtest.h>
#include <ros/ros.h>

#include "pbd_cloth/ClothState.h"
#include "ros_test_helpers.h"

namespace {

using pbd_cloth::ClothState;
using pbd_cloth_test::node;
using pbd_cloth_test::Recorder;
using pbd_cloth_test::StateRecorder;

// Sends one request; returns the configuration the server answers with (the values in effect).
dynamic_reconfigure::Config reconfigure(const dynamic_reconfigure::Config& request) {
  dynamic_reconfigure::Reconfigure srv;
  srv.request.config = request;
  EXPECT_TRUE(pbd_cloth_test::callService(node() + "/set_parameters", srv));
  return srv.response.config;
}

dynamic_reconfigure::Config intRequest(const std::string& name, int value) {
  dynamic_reconfigure::Config config;
  dynamic_reconfigure::IntParameter parameter;
  parameter.name = name;
  parameter.value = value;
  config.ints.push_back(parameter);
  return config;
}

dynamic_reconfigure::Config doubleRequest(const std::string& name, double value) {
  dynamic_reconfigure::Config config;
  dynamic_reconfigure::DoubleParameter parameter;
  parameter.name = name;
  parameter.value = value;
  config.doubles.push_back(parameter);
  return config;
}

bool findInt(const dynamic_reconfigure::Config& config, const std::string& name, int& value) {
  for (const auto& parameter : config.ints) {
    if (parameter.name == name) {
      value = parameter.value;
      return true;
    }
  }
  return false;
}

bool findDouble(const dynamic_reconfigure::Config& config, const std::string& name, double& value) {
  for (const auto& parameter : config.doubles) {
    if (parameter.name == name) {
      value = parameter.value;
      return true;
    }
  }
  return false;
}

TEST(Reconfigure, StartsFromTheScene) {
  int scene_substeps = 0;
  ASSERT_TRUE(ros::NodeHandle(node()).getParam("solver/substeps", scene_substeps));
  Recorder<dynamic_reconfigure::Config> updates(node() + "/parameter_updates");
  dynamic_reconfigure::Config config;
  ASSERT_TRUE(updates.waitForNext(config, 10.0)) << "nothing latched on ~parameter_updates";
  int substeps = 0;
  ASSERT_TRUE(findInt(config, "substeps", substeps));
  EXPECT_EQ(substeps, scene_substeps) << "not Solver.cfg's default: the scene's value";
}

TEST(Reconfigure, SubstepsChangeShowsInTheState) {
  StateRecorder states(node() + "/state");
  ClothState state;
  ASSERT_TRUE(states.waitForNext(state, 10.0));
  const int wanted = state.stats.substeps == 3 ? 5 : 3;

  int answered = 0;
  ASSERT_TRUE(findInt(reconfigure(intRequest("substeps", wanted)), "substeps", answered));
  EXPECT_EQ(answered, wanted);
  EXPECT_TRUE(states.waitForNext(
      state, 5.0,
      [wanted](const ClothState& s) { return s.stats.substeps == static_cast<unsigned>(wanted); }))
      << "~state.stats.substeps never showed " << wanted;
  // One pass per substep (iterations 1, tolerance 0): the solver really runs the new count.
  EXPECT_EQ(state.stats.iterations, static_cast<unsigned>(wanted));
  int parameter = 0;
  EXPECT_TRUE(ros::NodeHandle(node()).getParam("substeps", parameter));
  EXPECT_EQ(parameter, wanted);
  EXPECT_TRUE(pbd_cloth_test::allFinite(state));
}

TEST(Reconfigure, IterationsChangeShowsInTheState) {
  StateRecorder states(node() + "/state");
  ClothState state;
  ASSERT_TRUE(states.waitForNext(state, 10.0));
  const unsigned substeps = state.stats.substeps;
  reconfigure(intRequest("iterations", 2));
  EXPECT_TRUE(states.waitForNext(state, 5.0, [substeps](const ClothState& s) {
    return s.stats.iterations == 2 * substeps;
  })) << "~state.stats.iterations never became 2 per substep";
}

TEST(Reconfigure, RefusedValueIsCountedAndSnapsBack) {
  StateRecorder states(node() + "/state");
  ClothState before;
  ASSERT_TRUE(states.waitForNext(before, 10.0));
  double kinetic_before = 0.0;
  double static_friction = 0.0;
  {
    Recorder<dynamic_reconfigure::Config> updates(node() + "/parameter_updates");
    dynamic_reconfigure::Config config;
    ASSERT_TRUE(updates.waitForNext(config, 10.0));
    ASSERT_TRUE(findDouble(config, "friction_kinetic", kinetic_before));
    ASSERT_TRUE(findDouble(config, "friction_static", static_friction));
  }
  // Kinetic friction above static friction: the scene validation refuses it.
  double answered = 0.0;
  ASSERT_TRUE(findDouble(reconfigure(doubleRequest("friction_kinetic", static_friction + 1.0)),
                         "friction_kinetic", answered));
  EXPECT_DOUBLE_EQ(answered, kinetic_before) << "the refused value should snap back";
  ClothState after;
  EXPECT_TRUE(states.waitForNext(after, 5.0, [&](const ClothState& s) {
    return s.stats.rejected_inputs > before.stats.rejected_inputs;
  }));
  EXPECT_TRUE(pbd_cloth_test::allFinite(after));
}

// dynamic_reconfigure's server clamps a request to Solver.cfg's range before the callback: the
// node gets relaxation 1.99 (the cfg's maximum) for 5.0, applies it, answers with it, and has
// nothing to refuse or count (doc/reliability.md, "Bad input").
TEST(Reconfigure, OutOfRangeValueIsClampedNotCounted) {
  StateRecorder states(node() + "/state");
  ClothState before;
  ASSERT_TRUE(states.waitForNext(before, 10.0));
  double answered = 0.0;
  ASSERT_TRUE(findDouble(reconfigure(doubleRequest("relaxation", 5.0)), "relaxation", answered));
  EXPECT_DOUBLE_EQ(answered, 1.99) << "not clamped to Solver.cfg's maximum";
  double parameter = 0.0;
  EXPECT_TRUE(ros::NodeHandle(node()).getParam("relaxation", parameter));
  EXPECT_DOUBLE_EQ(parameter, 1.99);
  // Ten more states (1/3 s at 30 Hz): the count stays where it was.
  ClothState after;
  for (int k = 0; k < 10; ++k) ASSERT_TRUE(states.waitForNext(after, 5.0));
  EXPECT_EQ(after.stats.rejected_inputs, before.stats.rejected_inputs);
  EXPECT_TRUE(pbd_cloth_test::allFinite(after));
  reconfigure(doubleRequest("relaxation", 1.0));
}

}  // namespace

int main(int argc, char** argv) { return pbd_cloth_test::runTests(argc, argv, "reconfigure_test"); }
