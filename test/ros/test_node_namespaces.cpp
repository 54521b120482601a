// Two nodes in the namespaces r1 and r2 (node_namespaces.test): one /clock, frames per namespace,
// the follower stamped on the publisher's clock, and a take-over when the publisher goes.
#include <gtest/gtest.h>
#include <ros/master.h>
#include <rosgraph_msgs/Clock.h>
#include <tf2_msgs/TFMessage.h>

#include <map>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include "node_test_helpers.hpp"

using node_test::run_command;
using node_test::publishers_of;
using node_test::wait_for;

namespace {

const std::string kR1 = "/r1/spinning_top", kR2 = "/r2/spinning_top";

std::string joined(const std::vector<std::string>& names) {
  std::string text;
  for (const std::string& name : names) text += (text.empty() ? "" : ", ") + name;
  return "[" + text + "]";
}

/// Every /clock and /tf message with the node that published it.
class Listener {
 public:
  explicit Listener(ros::NodeHandle& nh) {
    clock_ = nh.subscribe("/clock", 100000, &Listener::on_clock, this);
    tf_ = nh.subscribe("/tf", 100000, &Listener::on_tf, this);
  }
  ~Listener() {
    clock_.shutdown();
    tf_.shutdown();
  }
  struct Clock {
    ros::Time time;
    std::string publisher;
  };
  struct Transform {
    std::string publisher, parent, child;
    ros::Time stamp;
  };
  std::vector<Clock> clocks() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return clocks_;
  }
  std::vector<Transform> transforms() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return transforms_;
  }
  bool publishes_tf(const std::string& node) const {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const Transform& t : transforms_)
      if (t.publisher == node) return true;
    return false;
  }

 private:
  void on_clock(const ros::MessageEvent<rosgraph_msgs::Clock const>& event) {
    std::lock_guard<std::mutex> lock(mutex_);
    clocks_.push_back({event.getMessage()->clock, event.getPublisherName()});
  }
  void on_tf(const ros::MessageEvent<tf2_msgs::TFMessage const>& event) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& t : event.getMessage()->transforms)
      transforms_.push_back({event.getPublisherName(), t.header.frame_id, t.child_frame_id, t.header.stamp});
  }
  mutable std::mutex mutex_;
  std::vector<Clock> clocks_;
  std::vector<Transform> transforms_;
  ros::Subscriber clock_, tf_;
};

TEST(NodeNamespaces, OneClockAndFramesPerNamespace) {
  ros::NodeHandle nh;
  Listener listener(nh);
  ASSERT_TRUE(wait_for([&] { return listener.publishes_tf(kR1) && listener.publishes_tf(kR2); }, 60.0))
      << "both nodes on /tf";
  ASSERT_TRUE(wait_for([&] { return listener.clocks().size() >= 100; }, 20.0));
  // Frames: each node its own children (r1/..., r2/...) under the shared world, none shared.
  std::map<std::string, std::set<std::string>> children;
  std::set<std::string> parents;
  for (const Listener::Transform& t : listener.transforms()) {
    children[t.publisher].insert(t.child);
    parents.insert(t.parent);
  }
  EXPECT_EQ(parents, std::set<std::string>({"world"}));
  EXPECT_EQ(children[kR1], std::set<std::string>({"r1/top", "r1/contact"}));
  EXPECT_EQ(children[kR2], std::set<std::string>({"r2/top", "r2/contact"}));
  EXPECT_EQ(children.size(), 2u) << "other publishers of /tf";

  // What a subscriber saw from the start: one publisher, a time that only goes forward.
  const std::vector<Listener::Clock> clocks = listener.clocks();
  long backwards = 0;
  std::map<std::string, long> clocks_from;
  for (size_t i = 0; i < clocks.size(); ++i) {
    ++clocks_from[clocks[i].publisher];
    if (i > 0 && !(clocks[i].time > clocks[i - 1].time)) ++backwards;
  }
  EXPECT_EQ(backwards, 0) << "of " << clocks.size() << " /clock messages";
  EXPECT_EQ(clocks_from.size(), 1u) << "nodes whose /clock the test received";
  // Exactly one publisher of /clock, the same one all along (sampled for 2 s).
  const std::vector<std::string> first = publishers_of("/clock");
  ASSERT_EQ(first.size(), 1u) << "publishers of /clock: " << joined(first);
  const std::string publisher = first.front();
  ASSERT_TRUE(publisher == kR1 || publisher == kR2) << publisher;
  const std::string follower = publisher == kR1 ? kR2 : kR1;
  for (int i = 0; i < 10; ++i) {
    ros::WallDuration(0.2).sleep();
    EXPECT_EQ(joined(publishers_of("/clock")), joined(first));
  }
  EXPECT_EQ(clocks_from[publisher], static_cast<long>(clocks.size())) << "/clock messages not from " << publisher;

  // The follower's ticks are stamped with the publisher's clock times (both at 100 Hz).
  std::set<ros::Time> clock_times;
  for (const auto& c : clocks) clock_times.insert(c.time);
  long follower_stamps = 0, follower_off_clock = 0;
  for (const Listener::Transform& t : listener.transforms())
    if (t.publisher == follower && t.stamp >= clocks.front().time && t.stamp <= clocks.back().time) {
      ++follower_stamps;
      follower_off_clock += clock_times.count(t.stamp) == 0;
    }
  EXPECT_GE(follower_stamps, 50);
  EXPECT_EQ(follower_off_clock, 0) << "of " << follower_stamps << " stamps of " << follower
                                   << " are not times of the /clock it follows";
  std::printf("[ measured ] /clock from %s: %zu messages, %ld back; %ld stamps of %s on its clock\n",
              publisher.c_str(), clocks.size(), backwards, follower_stamps, follower.c_str());

  // The publisher goes: the follower takes /clock over, going on from where it was.
  const size_t before = listener.clocks().size();
  const node_test::Outcome killed = run_command("rosnode kill " + publisher);
  ASSERT_EQ(killed.exit_code, 0) << killed.output;
  ASSERT_TRUE(wait_for([&] { return joined(publishers_of("/clock")) == joined({follower}); }, 20.0))
      << "publishers of /clock: " << joined(publishers_of("/clock"));
  ASSERT_TRUE(wait_for([&] {
    const auto all = listener.clocks();
    return all.size() > before && all.back().publisher == follower && all.size() >= before + 50;
  }, 20.0));
  const std::vector<Listener::Clock> after = listener.clocks();
  long after_backwards = 0;
  for (size_t i = before; i < after.size(); ++i)
    if (i > 0 && !(after[i].time > after[i - 1].time)) ++after_backwards;
  EXPECT_EQ(after_backwards, 0) << "/clock went back at the take-over";
}

}  // namespace

int main(int argc, char** argv) { return node_test::run_node_tests(argc, argv, "test_node_namespaces", 2); }
