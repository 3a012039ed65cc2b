// The ROS side of the simulator. cloth_node and ClothNodelet both build this one class, so the two
// entry points cannot drift apart. In the node's private namespace:
//   ~state, ~markers          out at publish_rate of simulated time (markers only built while
//                             someone subscribes), stamped with the time of the state they carry
//   ~<gripper>/pose           in: geometry_msgs/PoseStamped in any tf frame (not subscribed when
//                             the gripper follows its scene tf_frame instead)
//   ~<obstacle>/pose          in: the same, for obstacles (moved as kinematic colliders; not
//                             subscribed when the obstacle follows its scene tf_frame)
//   ~<gripper>/grasp          std_srvs/SetBool: true grasps what is within the radius (success
//                             false and the reason when nothing is), false releases
//   ~<gripper>/wrench         out: geometry_msgs/WrenchStamped, the force the cloth pulls on the
//                             gripper, in the scene frame (torque not computed: zero)
//   ~grasp_by_name            in: diagnostic_msgs/KeyValue {key: gripper, value: true|false}. The
//                             same as ~<gripper>/grasp, but a name the scene lacks reaches the node
//                             and is counted as a rejected input (a missing service cannot be
//                             called, so it could never be counted)
//   ~reset                    std_srvs/Trigger
//   ~get_state, ~set_state    pbd_cloth/GetState, SetState: the full dynamic state, and continuing
//                             from one (same scene). A state that does not fit is refused
//                             (success false, the reason; counted as a rejected input) and nothing
//                             changes. After a set, simulated time continues from the state's
//                             sim_time while stamps keep going forward: the set state is stamped
//                             with the ROS time of the call (with ~publish_clock: the node's clock
//                             then, which does not go back), and the bodies stay at the state's
//                             poses until their next pose or tf sample.
//   ~set_parameters, ...      dynamic_reconfigure of cfg/Solver.cfg (solver_reconfigure.h)
//   ~<camera>/depth/image_raw, camera_info, points
//                             out: the scene's simulated depth cameras (depth_cameras.h)
//   /diagnostics              cloth_diagnostics.h
//   /clock                    out, only with ~publish_clock: rosgraph_msgs/Clock after every step
//   /<robot.description>      parameter (default /robot_description, resolved in the node's
//                             namespace): the URDF text, read at start-up when the scene has
//                             `robot:` without robot.urdf_file
//   tf                        in: tf_frame of grippers and obstacles, and every robot link that has
//                             collision elements (frame = link name, as robot_state_publisher
//                             publishes it), looked up in the scene frame every step
// Node settings beside the scene: ~tf_timeout, ~pose_period, ~max_pose_period,
// ~min_real_time_factor, ~max_catch_up_steps, ~publish_clock, ~max_real_time_factor,
// ~robot_tf_timeout (Config below).
//
// Robot links. Each link with collision elements follows its tf frame through a PoseFollower like
// any body. Until its tf first arrives the simulation poses it by robot.joint_trajectory. It is
// placed at its first tf pose without sweeping there (it was never really at the scripted pose).
// A link whose tf is missing, or whose newest transform is older than ~robot_tf_timeout of ROS
// time (a static transform, stamp 0, never ages), is left out of the collisions with a warning
// naming it (counted once per outage as a rejected input); when its tf returns it is placed there
// and collides again.
//
// Time. The state at simulated time t is the world at ROS time origin + t (step_clock.h), and that
// is the stamp of every message carrying it. Normally ROS time drives the steps: ros::Time::now()
// (/clock when /use_sim_time is true, the wall clock otherwise) is polled every half step period
// and the steps due are run, at most ~max_catch_up_steps at once (beyond that the origin moves
// forward, with a warning); with /use_sim_time and no /clock yet nothing steps; when ROS time goes
// back (a looping bag) the simulation resets and the jump counts as a rejected input. With
// ~publish_clock the node is the clock instead: it steps as fast as it can (or at most
// ~max_real_time_factor simulated seconds per wall second) and publishes each state's time on
// /clock, from 0 at start; a ~reset keeps /clock going forward. Pose samples are timed in ROS time
// and each step drives the bodies to where their follower puts them at the state time at its end.
// The real-time factor is simulated seconds per wall second.
//
// Pose messages are smoothed into one target per step by a PoseFollower per body (see
// pose_follower.h for the policy). Refused inputs (pose_transformer.h, input_rejections.h) leave
// the body where its last good input put it.
//
// Threads. Steps, publishing, services and reconfigure run on the node handle's callback queue
// (with ~publish_clock the steps and their publishing run on a thread of their own instead).
// Pose messages run on a queue of their own with its own thread: bringing a pose into the scene
// frame may wait up to tf_timeout for tf, and that wait must not hold up the steps. The tf
// listener fills the buffer from its own thread. `mutex_` guards the simulation and the inputs.
#pragma once

#include <atomic>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <diagnostic_msgs/KeyValue.h>
#include <geometry_msgs/PoseStamped.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <std_msgs/String.h>
#include <std_srvs/SetBool.h>
#include <std_srvs/Trigger.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include "pbd_cloth/GetState.h"
#include "pbd_cloth/SetState.h"
#include "pbd_cloth/ros/cloth_diagnostics.h"
#include "pbd_cloth/ros/depth_cameras.h"
#include "pbd_cloth/ros/input_rejections.h"
#include "pbd_cloth/ros/pose_follower.h"
#include "pbd_cloth/ros/pose_transformer.h"
#include "pbd_cloth/ros/publish_ticks.h"
#include "pbd_cloth/ros/real_time_factor.h"
#include "pbd_cloth/ros/solver_reconfigure.h"
#include "pbd_cloth/ros/step_clock.h"
#include "pbd_cloth/sim/simulation.h"

namespace pbd_cloth {

class ClothRos {
 public:
  // Node settings beside the scene, private parameters of their own (ros_params.h reads them).
  struct Config {
    double tf_timeout = 0.1;        // ~tf_timeout (wall s): how long a pose waits for its transform
    PoseFollower::Config follower;  // ~pose_period, ~max_pose_period
    ClothDiagnostics::Config diagnostics;  // ~min_real_time_factor
    // ~max_catch_up_steps: steps run at once when ROS time is ahead; beyond, the origin moves.
    int max_catch_up_steps = 10;
    bool publish_clock = false;  // ~publish_clock: the node steps freely and publishes /clock
    // ~max_real_time_factor: with publish_clock, at most this many simulated s per wall s; 0: no
    // limit.
    double max_real_time_factor = 0.0;
    // ~robot_tf_timeout (s of ROS time): a robot link whose newest transform is older is left out.
    // robot_state_publisher sends moving links at 50 Hz: 0.5 s is 25 missed messages.
    double robot_tf_timeout = 0.5;
    // ~body_tf_timeout (s of ROS time): a gripper or obstacle following a tf frame whose newest
    // transform is older stays where it is, with a warning (its broadcaster may have died while
    // the gripper holds the cloth: following the stale transform would be the same, but silent).
    double body_tf_timeout = 0.5;
    // ~fault_injection: a test hook. On, the node subscribes ~inject_fault (std_msgs/String,
    // "nan" or "blowup") and corrupts its next step from inside (Simulation::injectFaultForTesting)
    // so a test can see the recovery. Off by default; never on in a robot's launch file.
    bool fault_injection = false;
  };

  // Reads and validates the scene and the node settings, builds the simulation and starts the
  // timers. On an invalid value it logs ROS_FATAL naming the key and its allowed range and
  // rethrows the ConfigError, so the caller can exit non-zero instead of simulating something the
  // user did not ask for.
  ClothRos(ros::NodeHandle nh, ros::NodeHandle nh_private);
  ~ClothRos();

  ClothRos(const ClothRos&) = delete;
  ClothRos& operator=(const ClothRos&) = delete;

 private:
  enum class BodyKind { kGripper, kObstacle, kRobotLink };
  static const char* kindName(BodyKind kind);

  // A gripper or an obstacle driven by ~<name>/pose or by a tf frame, or a robot link driven by
  // its tf frame.
  struct Body {
    BodyKind kind = BodyKind::kGripper;
    int index = 0;  // in the simulation's grippers, obstacles or robot links
    std::string name;
    std::string pose_topic;  // resolved, for warnings (not for robot links)
    std::string tf_frame;    // followed instead of pose_topic when not empty
    PoseFollower follower;
    ros::Time last_stamp;      // of the last accepted pose (message or tf)
    bool tf_seen = false;      // tf_frame was found at least once
    bool tf_ok = false;        // the last poll of tf_frame succeeded
    bool link_enabled = true;  // robot links: collides (mirrors RobotLinks::enabled)
    ros::Subscriber pose_subscriber;
    ros::ServiceServer grasp_service;  // grippers only
    ros::Publisher wrench_publisher;   // grippers only
  };

  // Reads the URDF from the parameter robot.description names when the scene has a robot without
  // robot.urdf_file (ConfigError naming the parameter when it is missing or does not parse).
  void loadRobotDescription(SceneConfig& scene) const;
  void createBodies();
  // Runs the steps ROS time says are due (not with publish_clock).
  void stepCallback(const ros::WallTimerEvent& event);
  // The loop of the thread that steps and publishes /clock (publish_clock only).
  void clockLoop();
  void diagnosticsCallback(const ros::WallTimerEvent& event);
  // Between steps: buffers an extreme step outgrew go back to their reserve
  // (Simulation::releaseExcessCapacity) and the heap's free pages back to the system (glibc).
  void memoryCallback(const ros::WallTimerEvent& event);
  static constexpr double kMemoryReleasePeriod = 5.0;  // s of wall time
  bool resetCallback(std_srvs::Trigger::Request& request, std_srvs::Trigger::Response& response);
  bool getStateCallback(GetState::Request& request, GetState::Response& response);
  bool setStateCallback(SetState::Request& request, SetState::Response& response);
  void poseCallback(Body& body, const geometry_msgs::PoseStamped& msg);
  bool graspCallback(const Body& body, std_srvs::SetBool::Request& request,
                     std_srvs::SetBool::Response& response);
  void graspByNameCallback(const diagnostic_msgs::KeyValue& msg);
  void injectFaultCallback(const std_msgs::String& msg);
  void reportRestoredStep();
  SolverTuning reconfigure(const SolverTuning& requested, unsigned groups);

  // All expect mutex_ held.
  Pose currentPose(const Body& body) const;
  // The ROS time of the current state.
  ros::Time stateTime() const { return step_clock_.stateTime(sim_->time()); }
  // The ROS time a pose sample arrives at (s): now, or with publish_clock the state's time (the
  // node's own clock, without the round trip through /clock).
  double inputTime() const;
  // One step: tf samples, bodies driven to the step's end, the step, and the state published when
  // the step crossed a publish tick.
  void stepOnce();
  // Back to the initial state with simulated time 0 at `origin`; publishes that state.
  ros::Time restartTime() const;
  void announceClock();
  void resetSimulation(const ros::Time& origin);
  void pollTfFrames(double arrival);
  // A robot link's tf: lost (left out of the collisions) or found (placed without a sweep).
  void loseRobotLink(Body& body, const PoseTransformer::Failure& failure);
  void placeRobotLink(Body& body, const Pose& pose, double arrival);
  void driveBodies(double step_end);
  void publishOutputs();
  void publishState();
  void publishMarkers();
  void publishWrenches();
  void warnAboutDegenerateConstraints();
  void warnAboutTruncatedSearches();

  ros::NodeHandle nh_;
  ros::NodeHandle nh_private_;
  Config config_;

  std::mutex mutex_;  // guards the simulation and every Body's input state
  std::unique_ptr<Simulation> sim_;
  StepClock step_clock_;
  PublishTicks publish_ticks_;
  bool waiting_for_clock_ = false;  // logged that no /clock has arrived yet
  RealTimeFactor real_time_factor_;
  // Simulated s per s of ROS time, for the diagnostics under /use_sim_time: whether the steps
  // keep up with /clock.
  RealTimeFactor clock_factor_;
  InputRejections rejections_;  // has its own lock: the input thread rejects without mutex_

  tf2_ros::Buffer tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  std::unique_ptr<PoseTransformer> pose_transformer_;

  // Before the bodies: their subscribers detach from it when they are destroyed.
  ros::CallbackQueue input_queue_;
  // Grippers, obstacles, then robot links with collision elements; never resized after start-up
  // (callbacks hold references into it).
  std::vector<Body> bodies_;

  ros::Publisher state_pub_;
  ros::Publisher markers_pub_;
  ros::Publisher clock_pub_;  // publish_clock only
  ros::ServiceServer reset_service_;
  ros::ServiceServer get_state_service_;
  ros::ServiceServer set_state_service_;
  ros::Subscriber grasp_by_name_sub_;
  ros::Subscriber inject_fault_sub_;  // ~fault_injection only
  std::unique_ptr<SolverReconfigure> reconfigure_;
  std::unique_ptr<ClothDiagnostics> diagnostics_;
  std::unique_ptr<DepthCameras> cameras_;  // cameras: (depth_cameras.h), its own render thread
  // Declared last so they stop first on destruction, before the simulation they drive.
  ros::WallTimer step_timer_;
  ros::WallTimer diagnostics_timer_;
  ros::WallTimer memory_timer_;
  std::unique_ptr<ros::AsyncSpinner> input_spinner_;
  std::atomic<bool> clock_running_{false};
  std::thread clock_thread_;  // publish_clock only
};

}  // namespace pbd_cloth
