// Small helpers shared by the node's rostest gtests: collect messages from a topic, wait
// for a condition, call a Trigger service or dynamic_reconfigure, check a force, run the tests.
#pragma once

#include <dynamic_reconfigure/DoubleParameter.h>
#include <dynamic_reconfigure/Reconfigure.h>
#include <geometry_msgs/WrenchStamped.h>
#include <gtest/gtest.h>
#include <ros/master.h>
#include <ros/ros.h>
#include <std_srvs/Trigger.h>

#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <mutex>
#include <string>
#include <vector>

namespace node_test {

/// Keeps every message received on a topic (callbacks run on an AsyncSpinner).
template <class Message>
class Recorder {
 public:
  Recorder(ros::NodeHandle& nh, const std::string& topic, uint32_t queue = 1000) {
    subscriber_ = nh.subscribe<Message>(topic, queue, [this](const typename Message::ConstPtr& m) {
      std::lock_guard<std::mutex> lock(mutex_);
      messages_.push_back(*m);
    });
  }
  // The subscription ends before the messages and the mutex go: a callback running on another
  // spinner thread must not find them destroyed (roscpp's shutdown waits for it).
  ~Recorder() { subscriber_.shutdown(); }
  std::vector<Message> messages() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return messages_;
  }
  size_t size() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return messages_.size();
  }
  void clear() {
    std::lock_guard<std::mutex> lock(mutex_);
    messages_.clear();
  }
  /// Publishers connected (e.g. to wait for them before starting a paused node).
  uint32_t publishers() const { return subscriber_.getNumPublishers(); }

 private:
  mutable std::mutex mutex_;
  std::vector<Message> messages_;
  ros::Subscriber subscriber_;  // last: destroyed first
};

/// Polls a condition every 10 ms of wall time until it holds or `timeout` wall seconds pass.
inline bool wait_for(const std::function<bool()>& condition, double timeout) {
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(timeout);
  while (ros::WallTime::now() < deadline) {
    if (condition()) return true;
    ros::WallDuration(0.01).sleep();
  }
  return condition();
}

/// Calls a std_srvs/Trigger service (waiting for it); returns the response.
inline std_srvs::Trigger::Response trigger(const std::string& service) {
  EXPECT_TRUE(ros::service::waitForService(service, ros::Duration(10.0))) << service;
  std_srvs::Trigger srv;
  EXPECT_TRUE(ros::service::call(service, srv)) << service;
  return srv.response;
}

/// Sets one double of `node` (e.g. "/spinning_top") through dynamic_reconfigure; returns the
/// value the node reports back as its configuration (the previous one when it refuses).
inline double reconfigure(const std::string& node, const std::string& name, double value) {
  EXPECT_TRUE(ros::service::waitForService(node + "/set_parameters", ros::Duration(10.0)));
  dynamic_reconfigure::Reconfigure srv;
  dynamic_reconfigure::DoubleParameter parameter;
  parameter.name = name;
  parameter.value = value;
  srv.request.config.doubles.push_back(parameter);
  // roscpp's non-persistent service calls fail now and then under load, the server logging
  // "Exception thrown while deserializing service call: Buffer Overrun" (ros/ros_comm#1976; CI
  // saw it once in ~30 calls in a row, after the node had answered). An update is refused or
  // applied alike however often it is sent, so a transport failure is retried, twice at most.
  bool called = false;
  for (int attempt = 0; attempt < 3 && !called; ++attempt) {
    if (attempt > 0) std::printf("[ measured ] set_parameters %s = %g: call failed, retried\n", name.c_str(), value);
    called = ros::service::call(node + "/set_parameters", srv);
  }
  EXPECT_TRUE(called) << name << " = " << value;
  for (const auto& d : srv.response.config.doubles)
    if (d.name == name) return d.value;
  ADD_FAILURE() << name << " missing from the reconfigure response";
  return NAN;
}

/// A message as a failure may print it: at most 300 characters.
inline std::string shown(const std::string& message) {
  return message.size() <= 300 ? message : message.substr(0, 300) + "... (" + std::to_string(message.size()) + " characters)";
}

inline bool finite(const geometry_msgs::WrenchStamped& w) {
  return std::isfinite(w.wrench.force.x) && std::isfinite(w.wrench.force.y) && std::isfinite(w.wrench.force.z);
}

/// What a shell command printed (stdout and stderr) and its exit code (-1 if it did not exit).
struct Outcome {
  int exit_code;
  std::string output;
};

inline Outcome run_command(const std::string& command) {
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  EXPECT_NE(pipe, nullptr) << command;
  Outcome outcome{-1, ""};
  if (pipe == nullptr) return outcome;
  char buffer[4096];
  while (fgets(buffer, sizeof buffer, pipe) != nullptr) outcome.output += buffer;
  const int status = pclose(pipe);
  outcome.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return outcome;
}

/// A rostest gtest's main: ROS node `name`, callbacks on an AsyncSpinner of `threads` threads.
inline int run_node_tests(int argc, char** argv, const char* name, int threads) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, name);
  ros::NodeHandle nh;
  ros::AsyncSpinner spinner(threads);
  spinner.start();
  const int result = RUN_ALL_TESTS();
  ros::shutdown();
  return result;
}

/// The publishers of a topic as the master lists them (its getSystemState).
inline std::vector<std::string> publishers_of(const std::string& topic) {
  XmlRpc::XmlRpcValue request, response, payload;
  request[0] = ros::this_node::getName();
  std::vector<std::string> nodes;
  if (!ros::master::execute("getSystemState", request, response, payload, false)) return {"(master did not answer)"};
  for (int i = 0; i < payload[0].size(); ++i)
    if (static_cast<std::string>(payload[0][i][0]) == topic)
      for (int j = 0; j < payload[0][i][1].size(); ++j) nodes.push_back(static_cast<std::string>(payload[0][i][1][j]));
  return nodes;
}

}  // namespace node_test
