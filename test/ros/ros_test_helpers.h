// Shared by the gtest clients of the rostests (each test/ros/*.cpp is its own executable, so the
// shared parts live in this header).
#pragma once

#include <algorithm>
#include <cmath>
#include <functional>
#include <mutex>
#include <string>
#include <vector>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <geometry_msgs/PoseStamped.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <std_srvs/SetBool.h>
#include <std_srvs/Trigger.h>

#include "pbd_cloth/ClothState.h"

namespace pbd_cloth_test {

// The node under test: the client's private parameter ~node (rostest <param name="node" .../>),
// so one client serves cloth_node, the nodelet and a namespaced node alike.
inline std::string nodeName(const std::string& fallback = "/cloth_node") {
  std::string name;
  return ros::NodeHandle("~").getParam("node", name) ? name : fallback;
}

// nodeName() read once (after ros::init): the name every test of a client talks to.
inline const std::string& node() {
  static const std::string name = nodeName();
  return name;
}

inline double distance(const geometry_msgs::Point& a, const geometry_msgs::Point& b) {
  return std::sqrt((a.x - b.x) * (a.x - b.x) + (a.y - b.y) * (a.y - b.y) +
                   (a.z - b.z) * (a.z - b.z));
}

inline geometry_msgs::Point point(double x, double y, double z) {
  geometry_msgs::Point p;
  p.x = x;
  p.y = y;
  p.z = z;
  return p;
}

inline bool allFinite(const pbd_cloth::ClothState& state) {
  return std::all_of(state.positions.begin(), state.positions.end(), [](const auto& p) {
    return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
  });
}

// A pose with identity orientation, stamped now.
inline geometry_msgs::PoseStamped poseStamped(const std::string& frame,
                                              const geometry_msgs::Point& position) {
  geometry_msgs::PoseStamped msg;
  msg.header.frame_id = frame;
  msg.header.stamp = ros::Time::now();
  msg.pose.position = position;
  msg.pose.orientation.w = 1.0;
  return msg;
}

// Keeps every message of a topic; the AsyncSpinner in main() fills it while a test waits.
template <typename Message>
class Recorder {
 public:
  // `queue_size`: messages kept while the spinner is busy (raise it for /clock at thousands of
  // messages per second).
  explicit Recorder(const std::string& topic, uint32_t queue_size = 100) {
    ros::NodeHandle nh;
    subscriber_ = nh.subscribe(topic, queue_size, &Recorder::callback, this);
  }

  // Unsubscribes before the messages and the mutex go: roscpp waits for a callback in flight on a
  // spinner thread, which would otherwise write into a destroyed vector (seen with /clock at
  // thousands of messages per second).
  ~Recorder() { subscriber_.shutdown(); }
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;

  // True once a publisher of the topic is connected (nothing it sent before was lost).
  bool waitForPublisher(double timeout = 10.0) {
    const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(timeout);
    while (ros::ok() && subscriber_.getNumPublishers() == 0) {
      if (ros::WallTime::now() > deadline) return false;
      ros::WallDuration(0.01).sleep();
    }
    return true;
  }

  // The first message that arrives after this call and satisfies `accept`, or false on timeout.
  bool waitForNext(Message& out, double timeout,
                   const std::function<bool(const Message&)>& accept = nullptr) {
    return waitFrom(count(), out, timeout, accept);
  }

  // As above, from the `first`-th message received (count() taken before triggering it).
  bool waitFrom(std::size_t first, Message& out, double timeout,
                const std::function<bool(const Message&)>& accept = nullptr) {
    std::size_t seen = first;
    const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(timeout);
    while (ros::ok() && ros::WallTime::now() < deadline) {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        for (; seen < messages_.size(); ++seen) {
          if (!accept || accept(messages_[seen])) {
            out = messages_[seen];
            return true;
          }
        }
      }
      ros::WallDuration(0.005).sleep();
    }
    return false;
  }

  // Copies of the messages received from the `first`-th on.
  std::vector<Message> since(std::size_t first) {
    std::lock_guard<std::mutex> lock(mutex_);
    return std::vector<Message>(messages_.begin() + std::min(first, messages_.size()),
                                messages_.end());
  }

  std::size_t count() {
    std::lock_guard<std::mutex> lock(mutex_);
    return messages_.size();
  }

 private:
  void callback(const Message& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    messages_.push_back(msg);
  }

  ros::Subscriber subscriber_;
  std::mutex mutex_;
  std::vector<Message> messages_;
};

using StateRecorder = Recorder<pbd_cloth::ClothState>;

// For Recorder<diagnostic_msgs::DiagnosticArray>::waitForNext / waitFrom: a report whose status
// `name` is a WARN with `text` in its message.
inline std::function<bool(const diagnostic_msgs::DiagnosticArray&)> warnsWith(
    const std::string& name, const std::string& text) {
  return [name, text](const diagnostic_msgs::DiagnosticArray& report) {
    for (const auto& status : report.status) {
      if (status.name == name && status.level == diagnostic_msgs::DiagnosticStatus::WARN &&
          status.message.find(text) != std::string::npos) {
        return true;
      }
    }
    return false;
  };
}

template <typename Service>
bool callService(const std::string& name, Service& service, double timeout = 10.0) {
  return ros::service::waitForService(name, ros::Duration(timeout)) &&
         ros::service::call(name, service);
}

inline bool callReset(const std::string& node) {
  std_srvs::Trigger trigger;
  return callService(node + "/reset", trigger) && trigger.response.success;
}

// The state the node publishes from inside ~reset: simulated time exactly 0.
inline bool resetAndReceiveInitialState(const std::string& node, StateRecorder& recorder,
                                        pbd_cloth::ClothState& initial) {
  // A first message proves the subscription is connected, so the reset state cannot be missed.
  pbd_cloth::ClothState any;
  if (!recorder.waitForNext(any, 10.0)) {
    return false;
  }
  // Counted before the call: the node publishes before the service returns.
  const std::size_t before = recorder.count();
  if (!callReset(node)) {
    return false;
  }
  return recorder.waitFrom(before, initial, 5.0, [](const pbd_cloth::ClothState& msg) {
    return msg.stats.sim_time < 1e-9;
  });
}

inline bool callGrasp(const std::string& service_name, bool grasp,
                      std_srvs::SetBool::Response* response = nullptr) {
  std_srvs::SetBool srv;
  srv.request.data = grasp;
  const bool called = callService(service_name, srv);
  if (response != nullptr) *response = srv.response;
  return called && srv.response.success;
}

// Publishes poses of one body on its ~<name>/pose topic.
class PosePublisher {
 public:
  explicit PosePublisher(const std::string& topic) {
    ros::NodeHandle nh;
    publisher_ = nh.advertise<geometry_msgs::PoseStamped>(topic, 10);
  }

  // True once the node is connected (a message before that would be lost).
  bool waitForSubscriber(double timeout = 10.0) {
    const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(timeout);
    while (ros::ok() && publisher_.getNumSubscribers() == 0) {
      if (ros::WallTime::now() > deadline) return false;
      ros::WallDuration(0.01).sleep();
    }
    return true;
  }

  void publish(const geometry_msgs::PoseStamped& msg) { publisher_.publish(msg); }

  // Moves the body in a straight line at `rate` messages per second over `duration` seconds,
  // as a robot driver would stream its poses.
  void stream(const std::string& frame, const geometry_msgs::Point& from,
              const geometry_msgs::Point& to, double duration, double rate = 30.0) {
    const int count = std::max(1, static_cast<int>(std::ceil(duration * rate)));
    for (int k = 1; k <= count && ros::ok(); ++k) {
      const double s = static_cast<double>(k) / count;
      publish(poseStamped(frame, point(from.x + s * (to.x - from.x), from.y + s * (to.y - from.y),
                                       from.z + s * (to.z - from.z))));
      ros::WallDuration(1.0 / rate).sleep();
    }
  }

 private:
  ros::Publisher publisher_;
};

// The standard main of these clients: a spinner fills the recorders while the tests wait.
inline int runTests(int argc, char** argv, const char* node_name) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, node_name);
  ros::AsyncSpinner spinner(2);
  spinner.start();
  const int result = RUN_ALL_TESTS();
  spinner.stop();
  ros::shutdown();
  return result;
}

}  // namespace pbd_cloth_test
