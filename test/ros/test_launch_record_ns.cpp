// Issue 20, item 2: `record:=true` under <group ns="r1"> (launch_record_ns.test). The test runs
// in /r1 and subscribes only to the node's ~twist: the node's ~wait_for_subscriber waits for
// ~contact_point and ~state, which only the recorder subscribes to, so ticks prove that the
// recorder found the node's topics in the namespace.
#include <geometry_msgs/TwistStamped.h>
#include <ros/master.h>
#include <xmlrpcpp/XmlRpcValue.h>

#include <algorithm>
#include <set>

#include "node_test_helpers.hpp"

namespace {

using node_test::Recorder;
using node_test::wait_for;

/// The nodes subscribed to `topic` according to the master.
std::set<std::string> subscribers(const std::string& topic) {
  XmlRpc::XmlRpcValue args, result, payload;
  args[0] = ros::this_node::getName();
  std::set<std::string> nodes;
  if (!ros::master::execute("getSystemState", args, result, payload, true)) return nodes;
  XmlRpc::XmlRpcValue& subscriptions = payload[1];
  for (int i = 0; i < subscriptions.size(); ++i)
    if (static_cast<std::string>(subscriptions[i][0]) == topic)
      for (int j = 0; j < subscriptions[i][1].size(); ++j) nodes.insert(static_cast<std::string>(subscriptions[i][1][j]));
  return nodes;
}

TEST(LaunchRecordNs, TheRecorderSubscribesAndTheNodeTicks) {
  ros::NodeHandle nh;  // in /r1, as the launch file's nodes
  ASSERT_EQ(nh.getNamespace(), "/r1");
  Recorder<geometry_msgs::TwistStamped> twists(nh, "spinning_top/twist");
  // A generous hang guard: the node starts (a few s on a loaded machine), then ticks at 200 Hz.
  ASSERT_TRUE(wait_for([&] { return twists.size() >= 20; }, 60.0))
      << "no ticks: the node waits for a subscriber to /r1/spinning_top/contact_point and state ("
      << twists.size() << " twists)";
  const auto received = twists.messages();
  EXPECT_GT(received.back().header.stamp, received.front().header.stamp);
  for (const char* topic : {"contact_point", "state", "normal_force", "twist", "status", "markers", "event",
                            "event_stamped"})
    EXPECT_EQ(subscribers(std::string("/r1/spinning_top/") + topic).count("/r1/record"), 1u) << topic;
  for (const char* topic : {"/tf", "/tf_static", "/clock", "/diagnostics"})
    EXPECT_EQ(subscribers(topic).count("/r1/record"), 1u) << topic;
}

}  // namespace

int main(int argc, char** argv) { return node_test::run_node_tests(argc, argv, "test_launch_record_ns", 2); }
