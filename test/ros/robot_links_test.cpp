// The robot's links in cloth_node (robot_links.test, robot_links_scene.yaml,
// test/data/node_links.urdf from /robot_description). This client plays robot_state_publisher: it
// broadcasts world -> <link> for every link at 100 Hz and moves them in straight lines.
// - Every geometry kind (box, sphere, cylinder, mesh) sweeps through the hanging curtain at 2 m/s
//   and back: the cloth is pushed, and no published state has a penetration of the thickness.
// - pair_link has two collision elements 0.25 m apart; only the second reaches the cloth, and it
//   pushes it.
// - When pair_link's tf stops, the link is left out (the cloth falls back through where it stands,
//   one rejected input); when its tf returns on the other side of the cloth the link is placed
//   there without sweeping back through the cloth, and pushes it again when it moves.
// - An obstacle with tf_frame follows that frame, and its ~<name>/pose is not subscribed.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <geometry_msgs/TransformStamped.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <tf2_ros/transform_broadcaster.h>
#include <visualization_msgs/MarkerArray.h>

#include "pbd_cloth/ClothState.h"
#include "ros_test_helpers.h"

namespace {

using geometry_msgs::Point;
using pbd_cloth::ClothState;
using pbd_cloth_test::node;
using pbd_cloth_test::point;
using pbd_cloth_test::Recorder;
using pbd_cloth_test::StateRecorder;

constexpr double kSweepSpeed = 2.0;  // m/s
// The curtain particle at row 7, column 1: at rest at (0.04, 0, 0.72), in front of pair_link's
// second element when pair_link stands at x = -0.2, z = 0.72.
constexpr int kPairTarget = 7 * 12 + 1;

// Broadcasts world -> frame for each frame it knows at 100 Hz, stamped now; each frame moves in a
// straight line at its own speed towards its goal.
class FrameMover {
 public:
  FrameMover() : thread_([this] { loop(); }) {}
  ~FrameMover() {
    running_ = false;
    thread_.join();
  }

  // Puts the frame at `where` at once (and broadcasts it).
  void place(const std::string& frame, const Point& where) {
    std::lock_guard<std::mutex> lock(mutex_);
    Motion& m = motions_[frame];
    m.from = m.to = where;
    m.t0 = m.t1 = now();
    m.broadcasting = true;
  }

  // Moves the frame from where it is to `to` at `speed` m/s; returns the seconds it takes.
  double move(const std::string& frame, const Point& to, double speed) {
    std::lock_guard<std::mutex> lock(mutex_);
    Motion& m = motions_[frame];
    const double t = now();
    m.from = position(m, t);
    m.to = to;
    m.t0 = t;
    m.t1 = t + pbd_cloth_test::distance(m.from, to) / speed;
    return m.t1 - t;
  }

  // Stops broadcasting the frame (as if its publisher died); place() starts it again.
  void stop(const std::string& frame) {
    std::lock_guard<std::mutex> lock(mutex_);
    motions_[frame].broadcasting = false;
  }

 private:
  struct Motion {
    Point from, to;
    double t0 = 0.0, t1 = 0.0;
    bool broadcasting = true;
  };

  static double now() { return ros::WallTime::now().toSec(); }

  static Point position(const Motion& m, double t) {
    const double s = m.t1 > m.t0 ? std::min(std::max((t - m.t0) / (m.t1 - m.t0), 0.0), 1.0) : 1.0;
    return point(m.from.x + s * (m.to.x - m.from.x), m.from.y + s * (m.to.y - m.from.y),
                 m.from.z + s * (m.to.z - m.from.z));
  }

  void loop() {
    while (running_ && ros::ok()) {
      std::vector<geometry_msgs::TransformStamped> transforms;
      {
        std::lock_guard<std::mutex> lock(mutex_);
        const double t = now();
        const ros::Time stamp = ros::Time::now();
        for (const auto& entry : motions_) {
          if (!entry.second.broadcasting) continue;
          geometry_msgs::TransformStamped transform;
          transform.header.stamp = stamp;
          transform.header.frame_id = "world";
          transform.child_frame_id = entry.first;
          const Point p = position(entry.second, t);
          transform.transform.translation.x = p.x;
          transform.transform.translation.y = p.y;
          transform.transform.translation.z = p.z;
          transform.transform.rotation.w = 1.0;
          transforms.push_back(transform);
        }
      }
      if (!transforms.empty()) broadcaster_.sendTransform(transforms);
      ros::WallDuration(0.01).sleep();
    }
  }

  tf2_ros::TransformBroadcaster broadcaster_;
  std::mutex mutex_;
  std::map<std::string, Motion> motions_;
  std::atomic<bool> running_{true};
  std::thread thread_;
};

FrameMover& mover() {
  static FrameMover instance;
  return instance;
}

StateRecorder& states() {
  static StateRecorder recorder(node() + "/state");
  return recorder;
}

// The four single-shape links and where each crosses the curtain (x, z).
struct SweepLink {
  const char* frame;
  double x, z;
};
const std::vector<SweepLink>& sweepLinks() {
  static const std::vector<SweepLink> links = {{"box_link", 0.06, 0.75},
                                               {"sphere_link", 0.17, 0.65},
                                               {"cylinder_link", 0.28, 0.75},
                                               {"mesh_link", 0.39, 0.65}};
  return links;
}

double thickness() {
  double value = 0.0;
  ros::NodeHandle(node()).getParam("cloth/thickness", value);
  return value;
}

// Hanging still in its plane: slower than 1 cm/s everywhere (not just swinging through y = 0).
bool atRest(const ClothState& state) {
  for (std::size_t i = 0; i < state.positions.size(); ++i) {
    const auto& v = state.velocities[i];
    if (std::abs(state.positions[i].y) > 0.01 || v.x * v.x + v.y * v.y + v.z * v.z > 1e-4) {
      return false;
    }
  }
  return true;
}

double maxY(const ClothState& state) {
  double y = -1e9;
  for (const auto& p : state.positions) y = std::max(y, p.y);
  return y;
}

TEST(RobotLinks, EveryGeometrySweepsThroughTheClothAt2MetresPerSecondWithoutPenetration) {
  ASSERT_GT(thickness(), 0.0);
  ClothState state;
  ASSERT_TRUE(states().waitForNext(state, 20.0)) << "no ~state";
  // Every link in tf beside the cloth, the cloth at rest.
  for (const SweepLink& link : sweepLinks()) mover().place(link.frame, point(link.x, -0.2, link.z));
  mover().place("pair_link", point(-0.2, -0.5, 0.72));
  const double settled = state.stats.sim_time + 1.5;
  ASSERT_TRUE(states().waitForNext(
      state, 20.0, [&](const ClothState& s) { return s.stats.sim_time > settled; }));
  ASSERT_LT(maxY(state), 0.01) << "the cloth was disturbed before the sweep";

  const std::size_t from = states().count();
  double duration = 0.0;
  for (const SweepLink& link : sweepLinks()) {
    duration = mover().move(link.frame, point(link.x, 0.15, link.z), kSweepSpeed);
  }
  ros::WallDuration(duration + 0.7).sleep();
  for (const SweepLink& link : sweepLinks()) {
    duration = mover().move(link.frame, point(link.x, -0.2, link.z), kSweepSpeed);
  }
  ros::WallDuration(duration + 1.0).sleep();

  const std::vector<ClothState> recorded = states().since(from);
  ASSERT_GE(recorded.size(), 20u);
  double deepest = 0.0, furthest = -1e9;
  for (const ClothState& s : recorded) {
    ASSERT_TRUE(pbd_cloth_test::allFinite(s));
    EXPECT_LT(s.stats.max_penetration, thickness()) << "at sim_time " << s.stats.sim_time;
    deepest = std::max(deepest, s.stats.max_penetration);
    furthest = std::max(furthest, maxY(s));
  }
  std::printf(
      "sweep at %.1f m/s: %zu states, deepest penetration %.2e m (thickness %.3f m), "
      "cloth pushed to y = %.3f m\n",
      kSweepSpeed, recorded.size(), deepest, thickness(), furthest);
  // The links stop at y = 0.15 with their far sides at 0.18 to 0.195: the cloth is pushed there.
  EXPECT_GT(furthest, 0.15) << "the links did not push the cloth";
}

TEST(RobotLinks, ALinkWithTwoCollisionElementsPushesWithTheSecond) {
  for (const SweepLink& link : sweepLinks()) {
    mover().move(link.frame, point(link.x, -0.5, link.z), kSweepSpeed);
  }
  // The swinging cloth comes to rest (the scene's damping).
  ClothState state;
  ASSERT_TRUE(states().waitForNext(state, 30.0, atRest)) << "the cloth did not come to rest";

  // Its first element (x = -0.2) stays beside the cloth; the second (x = 0.05) goes through it.
  mover().place("pair_link", point(-0.2, -0.2, 0.72));
  ros::WallDuration(0.3).sleep();
  const double duration = mover().move("pair_link", point(-0.2, 0.1, 0.72), 1.0);
  ros::WallDuration(duration + 0.5).sleep();
  ASSERT_TRUE(states().waitForNext(state, 10.0));
  // The second sphere's far side is at y = 0.13.
  EXPECT_GT(state.positions[kPairTarget].y, 0.09)
      << "the second collision element did not push the cloth";
}

TEST(RobotLinks, ALinkWithoutTfIsLeftOutAndComesBack) {
  ClothState state;
  ASSERT_TRUE(states().waitForNext(state, 10.0));
  ASSERT_GT(state.positions[kPairTarget].y, 0.09) << "pair_link does not hold the cloth";
  const unsigned rejected = state.stats.rejected_inputs;

  // Its tf stops: after ~robot_tf_timeout (0.5 s) the link is left out, and the cloth falls back
  // through where the link stands, swings and comes to rest in its plane.
  mover().stop("pair_link");
  EXPECT_TRUE(states().waitForNext(state, 30.0, atRest))
      << "the cloth did not fall back to rest once pair_link's tf stopped";
  EXPECT_EQ(state.stats.rejected_inputs, rejected + 1) << "the lost tf is not counted once";

  // Back on the near side: placed there, not swept back through the cloth (which would push it
  // towards -y).
  const std::size_t from = states().count();
  mover().place("pair_link", point(-0.2, -0.2, 0.72));
  ros::WallDuration(1.0).sleep();
  for (const ClothState& s : states().since(from)) {
    EXPECT_GT(s.positions[kPairTarget].y, -0.01)
        << "the returning link swept through the cloth at sim_time " << s.stats.sim_time;
  }
  const double duration = mover().move("pair_link", point(-0.2, 0.1, 0.72), 1.0);
  ros::WallDuration(duration + 0.5).sleep();
  ASSERT_TRUE(states().waitForNext(state, 10.0));
  EXPECT_GT(state.positions[kPairTarget].y, 0.09) << "the returned link does not push the cloth";
  EXPECT_EQ(state.stats.rejected_inputs, rejected + 1);
}

TEST(RobotLinks, AnObstacleFollowsItsTfFrame) {
  Recorder<visualization_msgs::MarkerArray> markers(node() + "/markers");
  const Point where = point(0.7, 0.4, 0.3);
  mover().place("ball_frame", where);
  visualization_msgs::MarkerArray msg;
  EXPECT_TRUE(markers.waitForNext(msg, 10.0, [&](const visualization_msgs::MarkerArray& m) {
    for (const auto& marker : m.markers) {
      // The ball is obstacle 0: marker id 0 of ns obstacles.
      if (marker.ns == "obstacles" && marker.id == 0) {
        return pbd_cloth_test::distance(marker.pose.position, where) < 1e-6;
      }
    }
    return false;
  })) << "the ball did not follow ball_frame";
  // One source per obstacle: ~ball/pose is not subscribed while it follows tf.
  pbd_cloth_test::PosePublisher pose(node() + "/ball/pose");
  EXPECT_FALSE(pose.waitForSubscriber(1.0));
}

}  // namespace

int main(int argc, char** argv) { return pbd_cloth_test::runTests(argc, argv, "robot_links_test"); }
