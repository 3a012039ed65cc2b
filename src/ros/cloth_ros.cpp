#include "pbd_cloth/ros/cloth_ros.h"

#include <malloc.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <sstream>

#include <geometry_msgs/WrenchStamped.h>
#include <rosgraph_msgs/Clock.h>
#include <visualization_msgs/MarkerArray.h>
#include <boost/make_shared.hpp>

#include "pbd_cloth/ClothState.h"
#include "pbd_cloth/ros/ros_conversions.h"
#include "pbd_cloth/ros/ros_params.h"
#include "pbd_cloth/ros/state_conversions.h"
#include "pbd_cloth/scene/scene_assets.h"
#include "pbd_cloth/sim/metrics.h"
#include "pbd_cloth/solver/scoped_timer.h"

namespace pbd_cloth {
namespace {

// Messages of ~state kept per subscriber while its connection is busy (ClothRos::ClothRos).
constexpr uint32_t kStateQueue = 10;

// ~grasp_by_name values, case-insensitive.
bool parseGrasp(std::string value, bool& grasp) {
  std::transform(value.begin(), value.end(), value.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  if (value == "true" || value == "1" || value == "grasp") {
    grasp = true;
    return true;
  }
  if (value == "false" || value == "0" || value == "release") {
    grasp = false;
    return true;
  }
  return false;
}

// A grasp that found nothing to hold is a valid request answered with success = false, so it is
// logged as a warning but not counted as a rejected input.
void logGrasp(const std::string& gripper, const GraspResult& result) {
  if (result.success) {
    ROS_INFO("Gripper '%s': %s", gripper.c_str(), result.message.c_str());
  } else {
    ROS_WARN("Gripper '%s': %s", gripper.c_str(), result.message.c_str());
  }
}

}  // namespace

ClothRos::ClothRos(ros::NodeHandle nh, ros::NodeHandle nh_private)
    : nh_(nh), nh_private_(nh_private) {
  try {
    SceneConfig scene = readSceneParameters(nh_private_);
    if (scene.robot.enabled && scene.robot.urdf_file.empty()) {
      loadRobotDescription(scene);
    }
    sim_ = std::make_unique<Simulation>(scene);
    // A step that blows up is undone and reported, never published (doc/reliability.md "Faults").
    sim_->setFaultRecovery(true);
    config_ = readNodeParameters(nh_private_);
  } catch (const ConfigError& error) {
    ROS_FATAL("Invalid parameter in %s: %s", nh_private_.getNamespace().c_str(), error.what());
    throw;
  }
  const SceneConfig& scene = sim_->scene();
  for (const std::string& warning : scene.load_warnings) {
    ROS_WARN("Scene: %s", warning.c_str());
  }
  for (const std::string& warning : sim_->startWarnings()) {
    ROS_WARN("Scene: %s", warning.c_str());
  }
  step_clock_ = StepClock(StepClock::Config{1.0 / scene.step_rate, config_.max_catch_up_steps});
  publish_ticks_ = PublishTicks(scene.publish_rate);
  ROS_INFO(
      "Cloth %dx%d (%d particles, %d triangles), %s with %d substeps, stepping at %.0f Hz, "
      "publishing at %.0f Hz in frame '%s'.",
      scene.cloth.rows, scene.cloth.cols, sim_->particles().size(),
      sim_->topology().triangleCount(), toString(scene.solver.method), scene.solver.substeps,
      scene.step_rate, scene.publish_rate, scene.frame_id.c_str());

  tf_listener_ = std::make_unique<tf2_ros::TransformListener>(tf_buffer_, nh_);
  pose_transformer_ = std::make_unique<PoseTransformer>(
      tf_buffer_, PoseTransformer::Config{scene.frame_id, config_.tf_timeout});

  // ~state keeps up to kStateQueue messages per subscriber while its connection is busy: a reset
  // or set state publishes its state at once and the next step's follows at free-running speed, so
  // with a queue of one the state a client asked for could be replaced before it was sent (a fresh
  // clone's CI saw it: PublishClock.ResetAnswersAndKeepsTheClockGoingForward).
  state_pub_ = nh_private_.advertise<ClothState>("state", kStateQueue);
  markers_pub_ = nh_private_.advertise<visualization_msgs::MarkerArray>("markers", 1);
  reset_service_ = nh_private_.advertiseService("reset", &ClothRos::resetCallback, this);
  get_state_service_ = nh_private_.advertiseService("get_state", &ClothRos::getStateCallback, this);
  set_state_service_ = nh_private_.advertiseService("set_state", &ClothRos::setStateCallback, this);
  // A std_msgs-only way to grasp by name, so a grasp on a gripper the scene does not have reaches
  // the node (a missing ~<name>/grasp service cannot be called) and is counted as rejected.
  grasp_by_name_sub_ =
      nh_private_.subscribe("grasp_by_name", 10, &ClothRos::graspByNameCallback, this);
  if (config_.fault_injection) {
    inject_fault_sub_ =
        nh_private_.subscribe("inject_fault", 10, &ClothRos::injectFaultCallback, this);
    ROS_WARN("~fault_injection is on: %s corrupts the next step on request (a test hook).",
             nh_private_.resolveName("inject_fault").c_str());
  }
  createBodies();
  cameras_ = std::make_unique<DepthCameras>(nh_private_, scene, tf_buffer_);

  reconfigure_ =
      std::make_unique<SolverReconfigure>(nh_private_, tuningFromSimulation(*sim_),
                                          [this](const SolverTuning& requested, unsigned groups) {
                                            return reconfigure(requested, groups);
                                          });
  diagnostics_ = std::make_unique<ClothDiagnostics>(nh_, nh_private_, nh_private_.getNamespace(),
                                                    config_.diagnostics);

  diagnostics_timer_ = nh_.createWallTimer(ros::WallDuration(diagnostics_->period()),
                                           &ClothRos::diagnosticsCallback, this);
  // Memory back to the system every few seconds, between steps (doc/reliability.md "Soak").
  memory_timer_ =
      nh_.createWallTimer(ros::WallDuration(kMemoryReleasePeriod), &ClothRos::memoryCallback, this);
  input_spinner_ = std::make_unique<ros::AsyncSpinner>(1, &input_queue_);
  input_spinner_->start();

  if (config_.publish_clock) {
    // The node is the clock: simulated time 0 is ROS time 0, so /clock starts at 0 on every run
    // and a recording made this way has the same stamps each time.
    // A queue of 100: at thousands of steps per second a follower's connection may lag a little.
    clock_pub_ = nh_.advertise<rosgraph_msgs::Clock>("/clock", 100);
    if (config_.max_real_time_factor > 0.0) {
      ROS_INFO("Publishing /clock from 0, at most %g simulated seconds per wall second.",
               config_.max_real_time_factor);
    } else {
      ROS_INFO("Publishing /clock from 0, stepping as fast as the machine allows.");
    }
    clock_running_ = true;
    clock_thread_ = std::thread(&ClothRos::clockLoop, this);
  } else {
    // Polled at twice the step rate: a step runs at most half a period after ROS time reached its
    // end. ROS time itself (/clock) is not a timer source here, since a ros::Timer on a clock that
    // jumps back or stops would stall rather than tell the node.
    if (ros::Time::isSimTime()) {
      ROS_INFO("/use_sim_time is true: stepping on /clock.");
    }
    step_timer_ = nh_.createWallTimer(ros::WallDuration(0.5 / scene.step_rate),
                                      &ClothRos::stepCallback, this);
  }
}

ClothRos::~ClothRos() {
  // Before any member goes: the clock thread and a pose callback in flight use the simulation,
  // the publishers and the tf buffer.
  clock_running_ = false;
  if (clock_thread_.joinable()) {
    clock_thread_.join();
  }
  input_spinner_->stop();
}

const char* ClothRos::kindName(BodyKind kind) {
  switch (kind) {
    case BodyKind::kGripper:
      return "gripper";
    case BodyKind::kObstacle:
      return "obstacle";
    case BodyKind::kRobotLink:
      return "robot link";
  }
  return "body";
}

void ClothRos::loadRobotDescription(SceneConfig& scene) const {
  // Resolved like any ROS name (robot_state_publisher's way): "robot_description" in the node's
  // namespace, so a robot in a namespace brings its own.
  const std::string parameter = nh_.resolveName(scene.robot.description);
  XmlRpc::XmlRpcValue value;
  if (!nh_.getParam(parameter, value)) {
    throw ConfigError("robot.description",
                      "no parameter '" + parameter +
                          "' with the robot's URDF (load it as robot_state_publisher needs it, "
                          "e.g. <param name=\"robot_description\" textfile=\"...urdf\"/>, or "
                          "give robot.urdf_file)");
  }
  if (value.getType() != XmlRpc::XmlRpcValue::TypeString) {
    throw ConfigError("robot.description",
                      "parameter '" + parameter + "' is not a string (it must hold the URDF text)");
  }
  loadRobot(scene, static_cast<std::string>(value), "parameter '" + parameter + "'");
  ROS_INFO("Robot '%s' from parameter '%s': %zu links.", scene.robot.model.name.c_str(),
           parameter.c_str(), scene.robot.model.links.size());
}

void ClothRos::createBodies() {
  ros::NodeHandle input_nh(nh_private_);
  input_nh.setCallbackQueue(&input_queue_);
  const int grippers = sim_->grippers().count();
  const int obstacles = sim_->obstacleCount();
  std::vector<int> links;
  for (int l = 0; l < sim_->robotLinks().count(); ++l) {
    if (sim_->robotLinks().hasCollision(l)) links.push_back(l);
  }
  bodies_.resize(grippers + obstacles + links.size());
  for (std::size_t k = 0; k < bodies_.size(); ++k) {
    Body& body = bodies_[k];
    const int i = static_cast<int>(k);
    body.follower = PoseFollower(config_.follower);
    if (i < grippers) {
      body.kind = BodyKind::kGripper;
      body.index = i;
      body.name = sim_->gripperName(body.index);
      body.tf_frame = sim_->scene().grippers[body.index].tf_frame;
    } else if (i < grippers + obstacles) {
      body.kind = BodyKind::kObstacle;
      body.index = i - grippers;
      body.name = sim_->obstacle(body.index).name;
      body.tf_frame = sim_->scene().obstacles[body.index].tf_frame;
    } else {
      // robot_state_publisher names each link's frame after the link.
      body.kind = BodyKind::kRobotLink;
      body.index = links[i - grippers - obstacles];
      body.name = sim_->robotLinkName(body.index);
      body.tf_frame = body.name;
      continue;
    }
    body.pose_topic = nh_private_.resolveName(body.name + "/pose");
    if (body.kind == BodyKind::kGripper) {
      body.grasp_service =
          nh_private_.advertiseService<std_srvs::SetBool::Request, std_srvs::SetBool::Response>(
              body.name + "/grasp", [this, &body](std_srvs::SetBool::Request& request,
                                                  std_srvs::SetBool::Response& response) {
                return graspCallback(body, request, response);
              });
      body.wrench_publisher =
          nh_private_.advertise<geometry_msgs::WrenchStamped>(body.name + "/wrench", 1);
    }
    if (!body.tf_frame.empty()) {
      // One source per body: a pose topic beside a followed frame would fight over it.
      ROS_INFO("%s '%s' follows tf frame '%s' (%s is not subscribed).", kindName(body.kind),
               body.name.c_str(), body.tf_frame.c_str(), body.pose_topic.c_str());
      continue;
    }
    // Every message is kept (up to 10) rather than only the latest, so each one is checked: an
    // out-of-order message is counted as such instead of silently replacing a newer one.
    body.pose_subscriber = input_nh.subscribe<geometry_msgs::PoseStamped>(
        body.name + "/pose", 10,
        [this, &body](const geometry_msgs::PoseStampedConstPtr& msg) { poseCallback(body, *msg); });
  }
  if (!links.empty()) {
    ROS_INFO(
        "%zu robot links with collision elements follow their tf frames in '%s' (posed by "
        "robot.joint_trajectory until their tf arrives).",
        links.size(), sim_->scene().frame_id.c_str());
  }
}

Pose ClothRos::currentPose(const Body& body) const {
  switch (body.kind) {
    case BodyKind::kGripper:
      return sim_->grippers().pose(body.index);
    case BodyKind::kObstacle:
      return sim_->obstacle(body.index).pose;
    case BodyKind::kRobotLink:
      break;
  }
  return sim_->robotLinks().pose(body.index);
}

void ClothRos::poseCallback(Body& body, const geometry_msgs::PoseStamped& msg) {
  const ros::Time stamp = msg.header.stamp;
  // Order first: an old message is refused before it waits for tf. Stamp 0 ("now", as
  // `rostopic pub` sends it) takes no part in the ordering.
  if (!stamp.isZero()) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (stamp < body.last_stamp) {
      std::ostringstream detail;
      detail << "stamp " << stamp << " is before the last accepted " << body.last_stamp;
      rejections_.reject(body.pose_topic, RejectReason::kOutOfOrder, detail.str());
      return;
    }
  }
  Pose pose;
  PoseTransformer::Failure failure;
  // Outside the lock: this may wait up to tf_timeout while the simulation steps on.
  if (!pose_transformer_->toSceneFrame(msg, pose, failure)) {
    rejections_.reject(body.pose_topic, failure.reason, failure.detail);
    return;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  if (!stamp.isZero()) {
    body.last_stamp = stamp;
  }
  body.follower.addSample(currentPose(body), pose, inputTime());
}

double ClothRos::inputTime() const {
  return config_.publish_clock ? stateTime().toSec() : ros::Time::now().toSec();
}

// Bodies that follow a tf frame take its latest transform every step; each new stamp is a sample
// for the follower, exactly like a pose message.
void ClothRos::pollTfFrames(double arrival) {
  std::string waiting;  // bodies whose frame has never been seen, for one warning
  for (Body& body : bodies_) {
    if (body.tf_frame.empty()) {
      continue;
    }
    Pose pose;
    ros::Time stamp;
    PoseTransformer::Failure failure;
    bool found = pose_transformer_->lookupFrame(body.tf_frame, pose, stamp, failure);
    // The latest transform of a frame whose broadcaster stopped stays in the buffer: for a link
    // that would be a ghost standing in the cloth; a gripper or obstacle would stay put anyway
    // (the follower never extrapolates), but silently. Stamp 0 is a static transform.
    const bool link = body.kind == BodyKind::kRobotLink;
    const double stale_after = link ? config_.robot_tf_timeout : config_.body_tf_timeout;
    if (found && !stamp.isZero() && arrival - stamp.toSec() > stale_after) {
      std::ostringstream detail;
      detail << "newest transform is " << arrival - stamp.toSec() << " s old ("
             << (link ? "~robot_tf_timeout " : "~body_tf_timeout ") << stale_after << " s)";
      if (!link) detail << "; the " << kindName(body.kind) << " stays where it is";
      failure = {RejectReason::kTfFailure, detail.str()};
      found = false;
    }
    if (!found) {
      if (body.kind == BodyKind::kRobotLink && body.tf_seen) {
        loseRobotLink(body, failure);
      } else if (body.tf_seen && body.tf_ok) {
        // Counted once per outage, not once per step of it.
        rejections_.reject(
            "tf frame '" + body.tf_frame + "' (" + kindName(body.kind) + " " + body.name + ")",
            failure.reason, failure.detail);
      } else if (!body.tf_seen) {
        // Not yet a rejected input: the broadcaster may simply start after this node.
        waiting += (waiting.empty() ? "" : ", ") + std::string(kindName(body.kind)) + " '" +
                   body.name + "' (frame '" + body.tf_frame + "': " + failure.detail + ")";
      }
      body.tf_ok = false;
      continue;
    }
    // A tf sample is timed by its stamp (the time the pose is of), not by when this poll saw it:
    // the step being driven ends at or before now, so a sample timed "now" would leave the body
    // at its start on every step that brings a new stamp, and a frame updated about once a step
    // (robot_state_publisher at 50 Hz) would hardly move. Stamp 0 (static): its arrival.
    const double sample_time = stamp.isZero() ? arrival : stamp.toSec();
    if (body.kind == BodyKind::kRobotLink && (!body.link_enabled || !body.follower.active())) {
      placeRobotLink(body, pose, sample_time);
    } else if (!body.follower.active() || stamp != body.last_stamp) {
      // A static frame keeps stamp 0: it becomes a sample once, then the body stays there.
      body.follower.addSample(currentPose(body), pose, sample_time);
    }
    body.last_stamp = stamp;
    body.tf_seen = body.tf_ok = true;
  }
  if (!waiting.empty()) {
    ROS_WARN_THROTTLE(10.0, "Waiting for tf of %s.", waiting.c_str());
  }
}

void ClothRos::loseRobotLink(Body& body, const PoseTransformer::Failure& failure) {
  if (body.link_enabled) {
    sim_->setRobotLinkEnabled(body.index, false);
    body.link_enabled = false;
  }
  if (body.tf_ok) {
    // Counted (and warned about, throttled per link) once per outage.
    rejections_.reject("tf frame '" + body.tf_frame + "' (robot link " + body.name + ")",
                       failure.reason,
                       failure.detail +
                           "; the link is left out of the collisions until its tf "
                           "returns");
  }
}

void ClothRos::placeRobotLink(Body& body, const Pose& pose, double arrival) {
  // Placed, not swept: where the link was (the scripted pose, or where its tf was lost) is not a
  // place it really moved from, and sweeping from there would push the cloth for nothing.
  sim_->setRobotLinkEnabled(body.index, false);
  sim_->setRobotLinkPose(body.index, pose);
  sim_->setRobotLinkEnabled(body.index, true);
  body.follower.reset();
  body.follower.addSample(pose, pose, arrival);
  if (!body.link_enabled) {
    ROS_INFO("Robot link '%s': its tf frame is back; it collides again.", body.name.c_str());
  }
  body.link_enabled = true;
}

// Bodies that have received a pose are moved to where their follower puts them at the end of the
// step; the core interpolates that motion across the substeps. Bodies that never received one keep
// their scripted trajectory (grippers) or their scene pose (obstacles).
void ClothRos::driveBodies(double step_end) {
  for (const Body& body : bodies_) {
    if (!body.follower.active()) {
      continue;
    }
    const Pose pose = body.follower.poseAt(step_end);
    switch (body.kind) {
      case BodyKind::kGripper:
        sim_->setGripperPose(body.index, pose);
        break;
      case BodyKind::kObstacle:
        sim_->setObstaclePose(body.index, pose);
        break;
      case BodyKind::kRobotLink:
        sim_->setRobotLinkPose(body.index, pose);
        break;
    }
  }
}

void ClothRos::stepCallback(const ros::WallTimerEvent& /*event*/) {
  std::lock_guard<std::mutex> lock(mutex_);
  const ros::Time now = ros::Time::now();
  const StepClock::Plan plan = step_clock_.update(now, sim_->time());
  if (plan.waiting) {
    if (!waiting_for_clock_) {
      ROS_INFO("/use_sim_time is true and no /clock has arrived yet: waiting for /clock to step.");
      waiting_for_clock_ = true;
    }
    return;
  }
  if (waiting_for_clock_) {
    ROS_INFO("/clock arrived (%.3f s): stepping.", now.toSec());
    waiting_for_clock_ = false;
  }
  if (plan.jumped_back) {
    std::ostringstream detail;
    detail << "ROS time went back by " << plan.jump << " s to " << now
           << " (a looping bag or a restarted simulator?)";
    rejections_.reject("/clock", RejectReason::kClockJump, detail.str());
    resetSimulation(now);
    return;
  }
  if (plan.skipped > 0.0) {
    ROS_WARN_THROTTLE(10.0,
                      "The simulation was %.3f s (%.0f steps) behind ROS time: it runs %d steps "
                      "(~max_catch_up_steps) and skips the other %.3f s of ROS time. Either /clock "
                      "jumped ahead or the machine cannot step at step_rate (real-time factor "
                      "%.2f).",
                      plan.behind, plan.behind * sim_->scene().step_rate, plan.steps, plan.skipped,
                      real_time_factor_.value());
  }
  // The steps due, within one step period of wall time: what is left over is still due at the
  // next call, and in between services and the reconfigure get their turn.
  const double period = 1.0 / sim_->scene().step_rate;
  const ros::WallTime start = ros::WallTime::now();
  for (int k = 0; k < plan.steps; ++k) {
    if (k > 0 && (ros::WallTime::now() - start).toSec() > period) break;
    stepOnce();
  }
}

void ClothRos::clockLoop() {
  using Clock = std::chrono::steady_clock;
  // Pacing for max_real_time_factor: the wall time each state is due at, counted from an anchor.
  // After a stall (a long service call) the anchor moves, so the node does not race to make up.
  Clock::time_point anchor_wall = Clock::now();
  double anchor_time = 0.0;
  while (clock_running_ && ros::ok()) {
    double state_time = 0.0;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stepOnce();
      const ros::Time now = stateTime();
      state_time = now.toSec();
      rosgraph_msgs::Clock clock;
      clock.clock = now;
      clock_pub_.publish(clock);
    }
    if (config_.max_real_time_factor <= 0.0) {
      // Lets a service or reconfigure waiting for the mutex in.
      std::this_thread::yield();
      continue;
    }
    const Clock::time_point due =
        anchor_wall + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(
                          (state_time - anchor_time) / config_.max_real_time_factor));
    const Clock::time_point now = Clock::now();
    if (due > now) {
      std::this_thread::sleep_until(due);
    } else if (now - due > std::chrono::milliseconds(100)) {
      anchor_wall = now;
      anchor_time = state_time;
    }
  }
}

void ClothRos::stepOnce() {
  const double period = 1.0 / sim_->scene().step_rate;
  pollTfFrames(inputTime());
  driveBodies(step_clock_.stateTime(sim_->time() + period).toSec());
  // The whole step, every attempt of it: with an accuracy target a step may run again
  // (Simulation::solveStep), and the solver's own figure is its last attempt's.
  double step_seconds = 0.0;
  {
    ScopedTimer step_timer(step_seconds);
    sim_->step();
  }
  if (sim_->faultGuard().lastStepRestored()) reportRestoredStep();
  real_time_factor_.add(ros::WallTime::now().toSec(), sim_->time());
  if (!config_.publish_clock) {
    clock_factor_.add(ros::Time::now().toSec(), sim_->time());
  }
  // The solver's own figures: Simulation::stats() would measure the state at every step.
  const StepStats& step_stats = sim_->solver().stats();
  diagnostics_->addStep(step_seconds, sim_->collisions().stats().truncated_searches,
                        step_stats.on_one_thread);
  warnAboutDegenerateConstraints();
  warnAboutTruncatedSearches();

  if (step_seconds > period) {
    // With an accuracy target the substeps are the controller's choice, not solver.substeps.
    const Simulation::AccuracyReport& accuracy = sim_->accuracy();
    ROS_WARN_THROTTLE(10.0,
                      "A step takes %.1f ms, longer than its period of %.1f ms: the simulation "
                      "runs slower than real time (factor %.2f). Lower step_rate or the cloth "
                      "size, or %s.",
                      1e3 * step_seconds, 1e3 * period, real_time_factor_.value(),
                      accuracy.active ? "raise solver.target_max_strain or lower "
                                        "solver.max_substeps (the strain target chose the "
                                        "substeps)"
                                      : "solver.substeps");
  }
  if (publish_ticks_.due(sim_->time())) {
    publishOutputs();
  }
  // A diverged state is not shown to the cameras either (publishOutputs reports it).
  if (!cameras_->empty() && allFinite(sim_->particles())) cameras_->afterStep(*sim_, stateTime());
}

// The step failed and Simulation undid it (fault recovery): the state is the one before it, at
// rest, and the simulation goes on. The diagnostics report it as an error too.
void ClothRos::reportRestoredStep() {
  ROS_ERROR_THROTTLE(
      5.0,
      "A step failed (%s): it was undone, back to the last good state at rest, and "
      "the simulation goes on (%llu undone since start; ~state "
      "stats.restored_steps).",
      describe(sim_->faultGuard().lastFault(), sim_->scene().solver.max_speed).c_str(),
      static_cast<unsigned long long>(sim_->faultGuard().restoredSteps()));
}

void ClothRos::injectFaultCallback(const std_msgs::String& msg) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (msg.data == "nan") {
    sim_->injectFaultForTesting(InjectedFault::kNaN);
  } else if (msg.data == "blowup") {
    sim_->injectFaultForTesting(InjectedFault::kBlowUp);
  } else {
    rejections_.reject(inject_fault_sub_.getTopic(), RejectReason::kBadValue,
                       "'" + msg.data + "' is not a fault: \"nan\" or \"blowup\"");
    return;
  }
  ROS_WARN("Fault injection: '%s' in the next step.", msg.data.c_str());
}

// Coincident particles (a cloth crushed flat by a gripper, a bad initial state) leave their stretch
// constraint without a direction: the solver skips it, and says so here, by index.
void ClothRos::warnAboutDegenerateConstraints() {
  const StepStats& stats = sim_->solver().stats();
  if (stats.degenerate_constraints == 0 || stats.first_degenerate_constraint < 0) return;
  const DistanceConstraint& con = sim_->topology().stretch[stats.first_degenerate_constraint];
  ROS_WARN_THROTTLE(5.0,
                    "%d stretch constraint(s) skipped in the last step: their particles coincide "
                    "(first: constraint %d between particles %d and %d); the other constraints "
                    "pull them apart. Counted in ~state stats.degenerate_constraints.",
                    stats.degenerate_constraints, stats.first_degenerate_constraint, con.i, con.j);
}

// A cloth crushed into itself (squeezed by a gripper onto a line or a point) puts every vertex
// within the thickness of hundreds of triangles: the self-collision search stops at its budget
// and skips the rest (SelfCollision::kPairsPerElement), so that the node keeps stepping.
void ClothRos::warnAboutTruncatedSearches() {
  const int truncated = sim_->collisions().stats().truncated_searches;
  if (truncated == 0) return;
  ROS_WARN_THROTTLE(5.0,
                    "%d self-collision search(es) in the last step stopped at their budget of %d "
                    "candidates per triangle and edge: the cloth is crushed into itself, and "
                    "self-contacts beyond the budget were skipped. Counted in ~state "
                    "stats.truncated_self_collision_searches.",
                    truncated, SelfCollision::kPairsPerElement);
}

void ClothRos::publishOutputs() {
  if (!allFinite(sim_->particles())) {
    // Publishing would hand NaNs to every consumer; the diagnostics report the error too.
    ROS_ERROR_THROTTLE(5.0,
                       "The simulation diverged (non-finite positions); nothing is published "
                       "until %s restarts it.",
                       reset_service_.getService().c_str());
    return;
  }
  publishState();
  publishMarkers();
  publishWrenches();
}

void ClothRos::memoryCallback(const ros::WallTimerEvent& /*event*/) {
  {
    // A soak found the node's resident memory growing by steps of megabytes with no leak
    // (heaptrack): the self-collision candidate list of a 10 x 10 cloth flung across itself by a
    // gripper jump grew to 3.7 MB in that step and kept it. It goes back to its reserve here.
    std::lock_guard<std::mutex> lock(mutex_);
    sim_->releaseExcessCapacity();
  }
#ifdef __GLIBC__
  // glibc keeps the free pages inside each thread's heap resident; give them back.
  malloc_trim(0);
#endif
}

void ClothRos::diagnosticsCallback(const ros::WallTimerEvent& /*event*/) {
  std::lock_guard<std::mutex> lock(mutex_);
  // The figures ~state reports, read the same way.
  SolverStats stats;
  RosConversions::toStatsMessage(*sim_, stats);
  SimulationHealth health;
  health.sim_time = stats.sim_time;
  health.step_period = 1.0 / sim_->scene().step_rate;
  health.real_time_factor = real_time_factor_.value();
  // Half a window: enough wall time that one late timer tick does not decide the verdict.
  health.real_time_factor_valid = real_time_factor_.span() >= 0.5;
  if (config_.publish_clock) {
    health.time_source = TimeSource::kOwnClock;
  } else if (ros::Time::isSimTime()) {
    health.time_source = TimeSource::kRosClock;
    health.clock_factor = clock_factor_.value();
    health.clock_factor_valid = clock_factor_.span() >= 0.5;
  }
  health.substeps = static_cast<int>(stats.substeps);
  health.iterations = static_cast<int>(stats.iterations);
  health.max_strain = stats.max_strain;
  health.max_penetration = stats.max_penetration;
  health.degenerate_constraints = static_cast<int>(stats.degenerate_constraints);
  health.target_max_strain = stats.target_max_strain;
  health.target_penetration = stats.target_penetration;
  health.structural_max_strain = stats.structural_max_strain;
  health.target_met = stats.target_met;
  health.target_budget_exhausted = stats.target_budget_exhausted;
  health.max_substeps = sim_->scene().solver.max_substeps;
  health.substeps_run = static_cast<int>(stats.substeps_run);
  health.finite = allFinite(sim_->particles());
  health.restored_steps = sim_->faultGuard().restoredSteps();
  if (health.restored_steps > 0) {
    health.last_fault = describe(sim_->faultGuard().lastFault(), sim_->scene().solver.max_speed);
  }
  health.has_cameras = !cameras_->empty();
  health.camera_images = cameras_->framesPublished();
  health.camera_images_dropped = cameras_->framesDropped();
  health.camera_images_without_tf = cameras_->framesWithoutTf();
  diagnostics_->report(health, rejections_);
}

bool ClothRos::resetCallback(std_srvs::Trigger::Request& /*request*/,
                             std_srvs::Trigger::Response& response) {
  std::lock_guard<std::mutex> lock(mutex_);
  // Otherwise simulated time 0 is now.
  resetSimulation(restartTime());
  announceClock();
  response.success = true;
  response.message = "back to the initial state";
  return true;
}

// The ROS time a reset or set state is stamped with. As the clock, the node keeps its time going
// forward, one step past the last state, so that no two states share a stamp and whoever follows
// /clock never sees it stand still or jump back; otherwise it is now.
ros::Time ClothRos::restartTime() const {
  if (!config_.publish_clock) return ros::Time::now();
  return stateTime() + ros::Duration(1.0 / sim_->scene().step_rate);
}

// As the clock: /clock at the restarted state's time at once, before its first step.
void ClothRos::announceClock() {
  if (!config_.publish_clock) return;
  rosgraph_msgs::Clock clock;
  clock.clock = stateTime();
  clock_pub_.publish(clock);
}

void ClothRos::resetSimulation(const ros::Time& origin) {
  sim_->reset();
  step_clock_.restart(origin);
  publish_ticks_.restart();
  cameras_->restart(0.0);
  // Grippers and obstacles are back at their scene poses: the next pose (or tf stamp) starts
  // afresh from there, and a replayed stream with earlier stamps is not out of order.
  for (Body& body : bodies_) {
    body.follower.reset();
    body.last_stamp = ros::Time();
    // The simulation starts with every link enabled; the next poll leaves out those without tf.
    body.link_enabled = true;
  }
  // Simulated time jumps back: old samples would give a negative rate.
  real_time_factor_.clear();
  clock_factor_.clear();
  // Publish the initial state at once, so a client sees it before the next step moves it.
  publishState();
}

bool ClothRos::getStateCallback(GetState::Request& /*request*/, GetState::Response& response) {
  std::lock_guard<std::mutex> lock(mutex_);
  SimulationState state;
  sim_->getState(state);
  StateConversions::toMessage(state, response.state);
  response.state.header.frame_id = sim_->scene().frame_id;
  response.state.header.stamp = stateTime();
  return true;
}

bool ClothRos::setStateCallback(SetState::Request& request, SetState::Response& response) {
  std::lock_guard<std::mutex> lock(mutex_);
  const std::string& frame = sim_->scene().frame_id;
  SimulationState state;
  std::string reason;
  if (!request.state.header.frame_id.empty() && request.state.header.frame_id != frame) {
    reason = "header.frame_id: '" + request.state.header.frame_id + "', the scene's is '" + frame +
             "' (states are not transformed)";
  }
  // Before the state changes: the ROS time the set state will be stamped with.
  const ros::Time stamp = restartTime();
  if (!reason.empty() || !StateConversions::fromMessage(request.state, state, reason) ||
      !sim_->setState(state, reason)) {
    rejections_.reject(set_state_service_.getService(), RejectReason::kBadValue,
                       reason + " (the state is unchanged)");
    response.success = false;
    response.message = reason;
    return true;
  }
  step_clock_.continueFrom(stamp, sim_->time());
  announceClock();
  publish_ticks_.restart(sim_->time());
  cameras_->restart(sim_->time());
  // As after a reset: bodies start afresh from the set poses, and simulated time jumped.
  for (Body& body : bodies_) {
    body.follower.reset();
    body.last_stamp = ros::Time();
    if (body.kind == BodyKind::kRobotLink)
      body.link_enabled = sim_->robotLinks().enabled(body.index);
  }
  real_time_factor_.clear();
  clock_factor_.clear();
  publishState();
  std::ostringstream message;
  message << "continuing from sim_time " << sim_->time() << " s";
  response.success = true;
  response.message = message.str();
  ROS_INFO("~set_state: %s.", response.message.c_str());
  return true;
}

bool ClothRos::graspCallback(const Body& body, std_srvs::SetBool::Request& request,
                             std_srvs::SetBool::Response& response) {
  std::lock_guard<std::mutex> lock(mutex_);
  const GraspResult result = sim_->setGrasp(body.index, request.data);
  response.success = result.success;
  response.message = result.message;
  logGrasp(body.name, result);
  return true;
}

void ClothRos::graspByNameCallback(const diagnostic_msgs::KeyValue& msg) {
  const std::string topic = grasp_by_name_sub_.getTopic();
  std::lock_guard<std::mutex> lock(mutex_);
  const int gripper = sim_->gripperIndex(msg.key);
  if (gripper < 0) {
    std::string names;
    for (int g = 0; g < sim_->grippers().count(); ++g) {
      names += (g > 0 ? ", " : "") + sim_->gripperName(g);
    }
    rejections_.reject(topic, RejectReason::kUnknownGripper,
                       "no gripper '" + msg.key +
                           "' in the scene (grippers: " + (names.empty() ? "none" : names) + ")");
    return;
  }
  bool grasp = false;
  if (!parseGrasp(msg.value, grasp)) {
    rejections_.reject(topic, RejectReason::kBadValue,
                       "value '" + msg.value + "' is not true/false (1/0, grasp/release)");
    return;
  }
  logGrasp(msg.key, sim_->setGrasp(gripper, grasp));
}

SolverTuning ClothRos::reconfigure(const SolverTuning& requested, unsigned groups) {
  std::lock_guard<std::mutex> lock(mutex_);
  std::string errors;
  if (!applyTuning(requested, groups, *sim_, errors)) {
    rejections_.reject(nh_private_.resolveName("set_parameters"), RejectReason::kBadValue,
                       errors + " (the previous value stays)");
  }
  const SolverTuning now = tuningFromSimulation(*sim_);
  ROS_INFO(
      "Solver tuning from the next step: %d substeps, %d iterations, tolerance %g m, %s, "
      "relaxation %g, damping %g 1/s, compliance stretch %g bend %g, friction %g/%g, target max "
      "strain %g, target penetration %g m, substeps %d..%d.",
      now.substeps, now.iterations, now.tolerance, now.ordering == 1 ? "jacobi" : "gauss_seidel",
      now.relaxation, now.damping, now.stretch_compliance, now.bend_compliance, now.friction_static,
      now.friction_kinetic, now.target_max_strain, now.target_penetration, now.min_substeps,
      now.max_substeps);
  return now;
}

void ClothRos::publishState() {
  if (state_pub_.getNumSubscribers() == 0) {
    return;
  }
  // A fresh message each time: a nodelet subscriber may still hold the previous one.
  const ClothStatePtr msg = boost::make_shared<ClothState>();
  msg->header.frame_id = sim_->scene().frame_id;
  msg->header.stamp = stateTime();
  RosConversions::toStateMessage(*sim_, *msg);
  msg->stats.real_time_factor = real_time_factor_.value();
  msg->stats.rejected_inputs = rejections_.total();
  state_pub_.publish(msg);
}

void ClothRos::publishMarkers() {
  // The mesh is the largest message of the node: build it only for someone who looks.
  if (markers_pub_.getNumSubscribers() == 0) {
    return;
  }
  std_msgs::Header header;
  header.frame_id = sim_->scene().frame_id;
  header.stamp = stateTime();
  const auto msg = boost::make_shared<visualization_msgs::MarkerArray>();
  RosConversions::toMarkerArray(*sim_, header, *msg);
  markers_pub_.publish(msg);
}

void ClothRos::publishWrenches() {
  for (const Body& body : bodies_) {
    if (body.kind != BodyKind::kGripper || body.wrench_publisher.getNumSubscribers() == 0) {
      continue;
    }
    const auto msg = boost::make_shared<geometry_msgs::WrenchStamped>();
    msg->header.frame_id = sim_->scene().frame_id;
    msg->header.stamp = stateTime();
    // The force the grasped particles' constraints pull on the gripper, in the scene frame. The
    // core reports no torque, so it stays zero.
    msg->wrench.force = RosConversions::toVector3(sim_->gripperForce(body.index));
    body.wrench_publisher.publish(msg);
  }
}

}  // namespace pbd_cloth
