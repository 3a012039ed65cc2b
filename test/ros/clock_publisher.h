// A simulated clock for the rostests that run the node under /use_sim_time: publishes /clock every
// 2 ms of wall time, advancing `speed` simulated seconds per wall second, and can jump, go back
// or stop, as a simulator or a looping rosbag would. The tests take its time from now() rather
// than ros::Time::now(), which would lag by the round trip through /clock.
#pragma once

#include <atomic>
#include <chrono>
#include <mutex>
#include <thread>

#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>

namespace pbd_cloth_test {

class ClockPublisher {
 public:
  // Starts at `start` (s), `speed` simulated s per wall s.
  ClockPublisher(double start, double speed) : base_time_(start), speed_(speed) {
    ros::NodeHandle nh;
    publisher_ = nh.advertise<rosgraph_msgs::Clock>("/clock", 100);
    base_wall_ = Wall::now();
    thread_ = std::thread([this] { loop(); });
  }

  ~ClockPublisher() {
    running_ = false;
    thread_.join();
  }

  ClockPublisher(const ClockPublisher&) = delete;
  ClockPublisher& operator=(const ClockPublisher&) = delete;

  // The simulated time now (s).
  double now() {
    std::lock_guard<std::mutex> lock(mutex_);
    return nowLocked();
  }

  // Goes on from `time` (s) at the same speed: a jump ahead or back.
  void jumpTo(double time) {
    std::lock_guard<std::mutex> lock(mutex_);
    base_time_ = time;
    base_wall_ = Wall::now();
  }

  // Stops advancing (still published); resume() goes on from there.
  void freeze() {
    std::lock_guard<std::mutex> lock(mutex_);
    base_time_ = nowLocked();
    frozen_ = true;
  }
  void resume() {
    std::lock_guard<std::mutex> lock(mutex_);
    base_wall_ = Wall::now();
    frozen_ = false;
  }

  // The time of the latest /clock message (s).
  double lastPublished() {
    std::lock_guard<std::mutex> lock(mutex_);
    return last_published_;
  }

 private:
  using Wall = std::chrono::steady_clock;

  double nowLocked() const {
    if (frozen_) return base_time_;
    return base_time_ + speed_ * std::chrono::duration<double>(Wall::now() - base_wall_).count();
  }

  void loop() {
    while (running_ && ros::ok()) {
      rosgraph_msgs::Clock msg;
      {
        std::lock_guard<std::mutex> lock(mutex_);
        const double time = nowLocked();
        msg.clock = ros::Time(time);
        last_published_ = msg.clock.toSec();
      }
      publisher_.publish(msg);
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  }

  std::mutex mutex_;
  double base_time_;  // simulated time at base_wall_
  Wall::time_point base_wall_;
  double speed_;
  bool frozen_ = false;
  double last_published_ = 0.0;
  ros::Publisher publisher_;
  std::atomic<bool> running_{true};
  std::thread thread_;
};

}  // namespace pbd_cloth_test
