// A node following the /clock the test publishes (node_follow_clock.test).
#include <diagnostic_msgs/DiagnosticArray.h>
#include <gtest/gtest.h>
#include <ros/master.h>
#include <rosgraph_msgs/Clock.h>
#include <tf2_msgs/TFMessage.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <set>
#include <string>
#include <vector>

#include "node_test_helpers.hpp"
#include "spinning_top/TopState.h"

using node_test::Recorder;
using node_test::publishers_of;
using node_test::wait_for;

namespace {

/// The node's diagnostics says which clock it goes by.
std::string clock_of(const std::vector<diagnostic_msgs::DiagnosticArray>& arrays) {
  std::string clock;
  for (const auto& array : arrays)
    for (const auto& status : array.status)
      if (status.name == "follower: simulation")
        for (const auto& kv : status.values)
          if (kv.key == "clock") clock = kv.value;
  return clock;
}

class FollowClock : public testing::Test {
 protected:
  void SetUp() override {
    clock_ = nh_.advertise<rosgraph_msgs::Clock>("/clock", 100);
    publish(t0_);
    pid_ = fork();
    if (pid_ == 0) {
      const std::string scene = "_scene_file:=" + std::string(SPINNING_TOP_SOURCE_DIR) + "/config/fixed_tip.yaml";
      execl(SPINNING_TOP_NODE_EXECUTABLE, SPINNING_TOP_NODE_EXECUTABLE, "__name:=follower", scene.c_str(),
            "_rate:=100", static_cast<char*>(nullptr));
      _exit(127);
    }
    ASSERT_GT(pid_, 0);
  }
  void TearDown() override {
    if (pid_ > 0) {
      kill(pid_, SIGINT);
      int status = 0;
      waitpid(pid_, &status, 0);
    }
  }
  void publish(const ros::Time& time) {
    rosgraph_msgs::Clock message;
    message.clock = time;
    clock_.publish(message);
  }
  /// Publishes `time` and waits for the node's state stamped with it.
  bool step_to(const ros::Time& time, Recorder<spinning_top::TopState>& state) {
    publish(time);
    return wait_for([&] {
      const auto all = state.messages();
      return !all.empty() && all.back().header.stamp >= time;
    }, 20.0);
  }

  ros::NodeHandle nh_;
  ros::Publisher clock_;
  const ros::Time t0_{1000, 0};
  pid_t pid_ = -1;
};

TEST_F(FollowClock, TicksAreTakenAtTheExternalTimesAndStampedWithThem) {
  Recorder<spinning_top::TopState> state(nh_, "/follower/state", 10000);
  Recorder<tf2_msgs::TFMessage> tf(nh_, "/tf", 10000);
  Recorder<diagnostic_msgs::DiagnosticArray> diagnostics(nh_, "/diagnostics", 1000);
  // The node found our /clock at its start and follows it (diagnostics say so), so that the next
  // message anchors its time; until then its ticks wait.
  ASSERT_TRUE(wait_for([&] { return clock_of(diagnostics.messages()).find("follows the /clock of") == 0; }, 30.0))
      << "clock: " << clock_of(diagnostics.messages());
  EXPECT_EQ(clock_of(diagnostics.messages()), "follows the /clock of " + ros::this_node::getName());
  // Connected: the node (under use_sim_time, roscpp's own /clock subscription, which the node's
  // shares) besides this process's own.
  ASSERT_TRUE(wait_for([&] { return state.publishers() > 0 && tf.publishers() > 0 && clock_.getNumSubscribers() >= 2; },
                       20.0));
  EXPECT_EQ(state.size(), 0u) << "ticks before the clock moved";
  publish(t0_);  // the anchor: the node's time now is t0

  // Lockstep: each clock time one tick (10 ms) later; a state stamped with it, its time the
  // ticks since the start.
  const ros::Duration tick(0.01);
  ros::Time now = t0_;
  for (int k = 1; k <= 30; ++k) {
    now += tick;
    ASSERT_TRUE(step_to(now, state)) << "no state stamped " << now;
  }
  // Several ticks at once: the clock jumps 0.2 s ahead.
  now += ros::Duration(0.2);
  ASSERT_TRUE(step_to(now, state));
  std::vector<spinning_top::TopState> states = state.messages();
  ASSERT_EQ(states.size(), 50u);
  for (size_t i = 0; i < states.size(); ++i) {
    EXPECT_EQ(states[i].header.stamp, t0_ + ros::Duration(0.01 * static_cast<double>(i + 1))) << i;
    EXPECT_EQ(states[i].time, static_cast<double>(i + 1) / 100.0) << i;
  }

  // The clock goes back (its source restarted): the top goes on from where it was, stamped on
  // the new time line.
  const ros::Time restart = t0_ + ros::Duration(0.05);
  publish(restart);
  now = restart;
  for (int k = 1; k <= 5; ++k) {
    now += tick;
    publish(now);
  }
  ASSERT_TRUE(wait_for([&] { return state.size() >= 55u; }, 20.0)) << state.size();
  states = state.messages();
  ASSERT_EQ(states.size(), 55u);
  for (size_t i = 50; i < 55; ++i) {
    EXPECT_EQ(states[i].header.stamp, restart + ros::Duration(0.01 * static_cast<double>(i - 49))) << i;
    EXPECT_EQ(states[i].time, static_cast<double>(i + 1) / 100.0) << i << ": the top went back";
  }

  // tf: the same stamps, the node's own frames; /clock: only ours, all along.
  std::set<ros::Time> state_stamps, tf_stamps;
  for (const auto& s : states) state_stamps.insert(s.header.stamp);
  for (const auto& message : tf.messages())
    for (const auto& t : message.transforms)
      if (t.child_frame_id == "top") tf_stamps.insert(t.header.stamp);
  EXPECT_EQ(tf_stamps, state_stamps);
  const std::vector<std::string> clock_publishers = publishers_of("/clock");
  ASSERT_EQ(clock_publishers.size(), 1u);
  EXPECT_EQ(clock_publishers.front(), ros::this_node::getName());
}

}  // namespace

int main(int argc, char** argv) { return node_test::run_node_tests(argc, argv, "test_node_follow_clock", 2); }
