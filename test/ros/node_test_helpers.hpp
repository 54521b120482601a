// Small helpers shared by the node's rostest gtests: collect messages from a topic, wait
// for a condition, call a Trigger service.
#pragma once

#include <gtest/gtest.h>
#include <ros/ros.h>
#include <std_srvs/Trigger.h>

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

 private:
  ros::Subscriber subscriber_;
  mutable std::mutex mutex_;
  std::vector<Message> messages_;
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

}  // namespace node_test
