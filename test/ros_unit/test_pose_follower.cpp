// The policy that spreads pose messages over the steps (pose_follower.h): first-order hold, one
// sample period of latency, never past the latest pose.
#include <gtest/gtest.h>

#include <cmath>

#include "pbd_cloth/ros/pose_follower.h"

namespace pbd_cloth {
namespace {

Pose at(double x, double y, double z) {
  Pose pose;
  pose.position = Eigen::Vector3d(x, y, z);
  return pose;
}

TEST(PoseFollower, InactiveUntilTheFirstSample) {
  PoseFollower follower;
  EXPECT_FALSE(follower.active());
  follower.addSample(at(0, 0, 0), at(1, 0, 0), 10.0);
  EXPECT_TRUE(follower.active());
  follower.reset();
  EXPECT_FALSE(follower.active());
}

TEST(PoseFollower, MovesAtConstantSpeedOverTheDefaultPeriodFirst) {
  PoseFollower::Config config;
  config.default_period = 0.1;
  PoseFollower follower(config);
  follower.addSample(at(0, 0, 0), at(1, 0, 0), 10.0);
  EXPECT_NEAR(follower.poseAt(10.0).position.x(), 0.0, 1e-12);
  EXPECT_NEAR(follower.poseAt(10.025).position.x(), 0.25, 1e-9);
  EXPECT_NEAR(follower.poseAt(10.05).position.x(), 0.5, 1e-9);
  EXPECT_NEAR(follower.poseAt(10.1).position.x(), 1.0, 1e-12);
  // Held at the sample afterwards: no extrapolation past the latest pose.
  EXPECT_NEAR(follower.poseAt(11.0).position.x(), 1.0, 1e-12);
}

TEST(PoseFollower, LearnsTheSamplePeriod) {
  PoseFollower::Config config;
  config.default_period = 0.1;
  config.period_smoothing = 0.5;
  PoseFollower follower(config);
  follower.addSample(at(0, 0, 0), at(1, 0, 0), 0.0);
  follower.addSample(at(0.5, 0, 0), at(2, 0, 0), 0.02);  // the first interval replaces the guess
  EXPECT_NEAR(follower.period(), 0.02, 1e-12);
  EXPECT_NEAR(follower.poseAt(0.03).position.x(), 1.25, 1e-9);  // half way from 0.5 to 2
  follower.addSample(at(2, 0, 0), at(3, 0, 0), 0.06);           // averaged: 0.5 * 0.02 + 0.5 * 0.04
  EXPECT_NEAR(follower.period(), 0.03, 1e-12);
}

TEST(PoseFollower, LongGapsCountAsMaxPeriod) {
  PoseFollower::Config config;
  config.max_period = 0.5;
  config.period_smoothing = 1.0;
  PoseFollower follower(config);
  follower.addSample(at(0, 0, 0), at(1, 0, 0), 0.0);
  follower.addSample(at(1, 0, 0), at(2, 0, 0), 30.0);  // a user typing poses by hand
  EXPECT_NEAR(follower.period(), 0.5, 1e-12);
  EXPECT_NEAR(follower.poseAt(30.5).position.x(), 2.0, 1e-12);
}

TEST(PoseFollower, TurnsAlongTheShortestArc) {
  PoseFollower follower;
  Pose turned = at(0, 0, 0);
  turned.orientation = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ());
  follower.addSample(at(0, 0, 0), turned, 0.0);
  const Eigen::Quaterniond half = follower.poseAt(0.5 * follower.period()).orientation;
  EXPECT_NEAR(half.angularDistance(Eigen::Quaterniond::Identity()), M_PI / 4, 1e-9);
}

}  // namespace
}  // namespace pbd_cloth
