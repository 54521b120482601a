// rostest (test/node_many_tops.test), issue 19: a node with hundreds of tops starts, spawns and
// stops cleanly. The test starts the node binary itself (fork/exec) on the test's master.
//   - SIGINT at any point of the start-up ends the node with exit code 0 (it trapped, SIGTRAP,
//     exit 133, publishing /tf_static on a publisher that the shutdown had invalidated);
//   - a spawn does the same work whatever the count of tops: the messages and parameters one
//     spawn publishes and writes, counted, are the same for the 1st and the 30th spawn, and by
//     default it registers nothing with the master (whose lists of a node's registrations are
//     searched linearly);
//   - SIGINT with many tops: exit code 0 (the time it takes is printed, not asserted);
//   - ~top_topics, ~top_reset_services, ~spawn_topics and ~spawn_reset_services: each top
//     registers what they list, and no more; ~states and ~events carry every top.
// Nothing here depends on the machine's load: the SIGINTs are sent at stages of the start the
// test sees (parameters the node writes), and the wall bounds are hang guards only.
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>
#include <signal.h>
#include <sys/wait.h>
#include <tf2_msgs/TFMessage.h>
#include <unistd.h>
#include <xmlrpcpp/XmlRpcValue.h>

#include <ros/master.h>
#include <ros/this_node.h>

#include <algorithm>
#include <cstdio>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "node_test_helpers.hpp"
#include "spinning_top/Spawn.h"
#include "spinning_top/TopEvent.h"
#include "spinning_top/TopState.h"
#include "spinning_top/TopStateArray.h"

using node_test::Recorder;
using node_test::wait_for;

namespace {

/// The node binary as `name`, with private parameters given on the parameter server first.
pid_t start_node(const std::string& name, const std::vector<std::string>& arguments = {}) {
  std::vector<std::string> args = {SPINNING_TOP_NODE_EXECUTABLE, "__name:=" + name};
  args.insert(args.end(), arguments.begin(), arguments.end());
  const pid_t pid = fork();
  if (pid == 0) {
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(&a[0]);
    argv.push_back(nullptr);
    execv(argv[0], argv.data());
    _exit(127);
  }
  return pid;
}

/// SIGKILLs the node if a failed assertion returns before the test has reaped it: a node left
/// behind keeps the test run's output open (CI's `make run_tests | tee` waited for it for ever).
struct ReapAtExit {
  pid_t pid;
  ~ReapAtExit() {
    int status = 0;
    if (pid > 0 && waitpid(pid, &status, WNOHANG) == 0) {
      kill(pid, SIGKILL);
      waitpid(pid, &status, 0);
    }
  }
};

/// Waits for the child's exit (at most `guard` wall seconds, then SIGKILL); its wait status, or -1.
int wait_exit(pid_t pid, double guard, double* seconds = nullptr) {
  const ros::WallTime start = ros::WallTime::now();
  int status = 0;
  pid_t done = 0;
  while ((done = waitpid(pid, &status, WNOHANG)) == 0 && (ros::WallTime::now() - start).toSec() < guard)
    ros::WallDuration(0.005).sleep();
  if (seconds != nullptr) *seconds = (ros::WallTime::now() - start).toSec();
  if (done == 0) {
    kill(pid, SIGKILL);
    waitpid(pid, &status, 0);
    return -1;
  }
  return status;
}

std::string describe(int status) {
  if (status == -1) return "still running after the guard (killed)";
  if (WIFSIGNALED(status)) return "killed by signal " + std::to_string(WTERMSIG(status));
  return "exit code " + std::to_string(WEXITSTATUS(status));
}

/// ~tops: `count` names t000, t001, ... for the node `name`, every pivot static (fixed tip,
/// after_lift_off: stop), so that the start publishes /tf_static.
void many_tops(const std::string& name, int count) {
  XmlRpc::XmlRpcValue tops;
  tops.setSize(count);
  for (int i = 0; i < count; ++i) {
    char top[16];
    std::snprintf(top, sizeof top, "t%03d", i);
    tops[i] = std::string(top);
  }
  ros::param::del("/" + name);
  ros::param::set("/" + name + "/tops", tops);
  ros::param::set("/" + name + "/after_lift_off", std::string("stop"));
  ros::param::set("/" + name + "/rate", 100.0);
  ros::param::set("/" + name + "/publish_clock", false);
  ros::param::set("/" + name + "/body_frame", name + "_top");
  ros::param::set("/" + name + "/contact_frame", name + "_contact");
}

}  // namespace

namespace {
std::pair<int, int> registrations_of(const std::string& node);
}  // namespace

// SIGINT while the tops are being started (after the 10th, after the 150th) and once the last
// one is there: each time a clean exit, 0, within the guard, and nothing of the node left on the
// master (the start unregisters what it advertised in one call, as a running node does).
TEST(ManyTops, SigintDuringTheStartEndsTheNodeCleanly) {
  const int count = 300;
  for (const std::string stage : {"t010", "t150", "t299"}) {
    const std::string name = "starting_" + stage;
    many_tops(name, count);
    const pid_t pid = start_node(name);
    ASSERT_GT(pid, 0);
    const ReapAtExit reap{pid};
    // Each top writes its URDF as it starts: the stage is there when its parameter is.
    const bool reached = wait_for([&] { return ros::param::has("/" + name + "/" + stage + "/robot_description"); }, 120.0);
    ASSERT_EQ(kill(pid, SIGINT), 0);
    double seconds = 0.0;
    const int status = wait_exit(pid, 60.0, &seconds);
    EXPECT_TRUE(reached) << stage << " never started";
    EXPECT_TRUE(status != -1 && WIFEXITED(status) && WEXITSTATUS(status) == 0)
        << "SIGINT after " << stage << " started: " << describe(status);
    std::printf("[ measured ] SIGINT after %s of %d tops started: %s, %.3f s after SIGINT\n", stage.c_str(), count,
                describe(status).c_str(), seconds);
    const auto left = registrations_of("/" + name);
    EXPECT_EQ(left.first, 0) << "topics of the node left on the master after SIGINT after " << stage;
    EXPECT_EQ(left.second, 0) << "services of the node left on the master after SIGINT after " << stage;
    ros::param::del("/" + name);
  }
}

namespace {

/// The topics and services of `node` whose names start with `prefix` (getSystemState).
std::pair<int, int> registrations_under(const std::string& node, const std::string& prefix) {
  XmlRpc::XmlRpcValue args, result, payload;
  args[0] = ros::this_node::getName();
  if (!ros::master::execute("getSystemState", args, result, payload, true)) return {-1, -1};
  int topics = 0, services = 0;
  for (int kind : {0, 2})  // publishers, services
    for (int i = 0; i < payload[kind].size(); ++i)
      if (static_cast<std::string>(payload[kind][i][0]).rfind(prefix, 0) == 0)
        for (int j = 0; j < payload[kind][i][1].size(); ++j)
          if (static_cast<std::string>(payload[kind][i][1][j]) == node) ++(kind == 0 ? topics : services);
  return {topics, services};
}

/// All the topics and services the master lists for `node`.
std::pair<int, int> registrations_of(const std::string& node) { return registrations_under(node, ""); }

/// Whether the master lists `node` among the publishers of `topic`.
bool publishes(const std::string& node, const std::string& topic) {
  const std::vector<std::string> publishers = node_test::publishers_of(topic);
  return std::find(publishers.begin(), publishers.end(), node) != publishers.end();
}

}  // namespace

// What one spawn does, counted: /tf_static is republished only when the set of pivots changes
// (each spawn sent every pivot again: with 50 pivots, 50 transforms per spawn of any top), a
// spawn registers nothing with the master, for the 1st top as for the 30th (~spawn_topics and
// ~spawn_reset_services are empty by default; it registered 7 topics and 1 service), and it sends
// nothing to /rosout (roscpp puts the names of all the node's topics in each record: with 1,000
// tops, 7,000 names, ~165 kB a spawn, and rosout.log grew by the square of the count). Then SIGINT:
// exit code 0, and the master keeps nothing of the node (its topics unregistered in one call).
TEST(ManyTops, ASpawnDoesTheSameWorkWhateverTheCountAndTheNodeLeavesCleanly) {
  const std::string name = "spawner";
  many_tops(name, 50);
  ros::param::set("/" + name + "/start_paused", true);
  ros::NodeHandle nh;
  Recorder<tf2_msgs::TFMessage> tf_static(nh, "/tf_static", 1000);
  Recorder<rosgraph_msgs::Log> log(nh, "/rosout", 10000);
  const auto records_of_node = [&] {
    const auto records = log.messages();
    return std::count_if(records.begin(), records.end(), [&](const auto& m) { return m.name == "/" + name; });
  };
  ros::WallDuration(0.5).sleep();
  const uint32_t rosout_publishers = log.publishers();  // connected to this test before the node
  const pid_t pid = start_node(name);
  ASSERT_GT(pid, 0);
  const ReapAtExit reap{pid};
  ASSERT_TRUE(ros::service::waitForService("/" + name + "/spawn", ros::Duration(120.0)));
  ASSERT_TRUE(wait_for([&] { return tf_static.size() >= 1; }, 30.0)) << "no /tf_static";
  ros::WallDuration(0.5).sleep();
  ASSERT_EQ(tf_static.size(), 1u) << "the start published its pivots more than once";
  EXPECT_EQ(tf_static.messages().back().transforms.size(), 50u);
  // That its /rosout reaches us, so that no record during the spawns means none was sent. Its
  // start-up lines may come before its /rosout is connected to us (on a busy machine they did),
  // so: the connection, then a line asked for (~reset logs one at INFO; it sends no /tf_static).
  ASSERT_TRUE(wait_for([&] { return log.publishers() > rosout_publishers; }, 60.0)) << "its /rosout never connected";
  ASSERT_TRUE(node_test::trigger("/" + name + "/reset").success);
  ASSERT_TRUE(wait_for([&] { return records_of_node() >= 1; }, 30.0)) << "no /rosout record of the node";

  ros::ServiceClient spawn = nh.serviceClient<spinning_top::Spawn>("/" + name + "/spawn", true);
  ros::WallDuration(0.5).sleep();  // the start-up's last lines
  const auto records_before_spawns = records_of_node();
  std::vector<std::pair<int, int>> added;  // registrations each spawn added
  for (int i = 0; i < 30; ++i) {
    spinning_top::Spawn srv;
    srv.request.name = "flying" + std::to_string(i);
    srv.request.keys = {"after_lift_off=fly"};  // a tip that may fly: no static pivot
    srv.request.x = 0.1 * i;
    ASSERT_TRUE(spawn.call(srv) && srv.response.success) << srv.response.message;
    // Under the top's own namespace: the node's own registrations cannot race the count.
    added.push_back(registrations_under("/" + name, "/" + name + "/" + srv.request.name + "/"));
  }
  ros::WallDuration(0.5).sleep();
  const auto spawn_records = records_of_node() - records_before_spawns;
  EXPECT_EQ(spawn_records, 0) << "/rosout records during 30 spawns; the last: " << log.messages().back().msg;
  for (std::size_t i = 0; i < added.size(); ++i) {
    EXPECT_EQ(added[i].first, 0) << "topics registered by spawn " << i;
    EXPECT_EQ(added[i].second, 0) << "services registered by spawn " << i;
  }
  // The tops of ~tops have theirs (~top_topics, ~top_reset_services: all by default).
  EXPECT_EQ(registrations_under("/" + name, "/" + name + "/t049/"), std::make_pair(7, 1));
  spinning_top::Spawn pivot;
  pivot.request.name = "pivoting";
  pivot.request.keys = {"after_lift_off=stop"};
  pivot.request.y = 0.5;
  ASSERT_TRUE(spawn.call(pivot) && pivot.response.success) << pivot.response.message;
  ASSERT_TRUE(wait_for([&] { return tf_static.size() >= 2; }, 10.0));
  ros::WallDuration(0.5).sleep();
  const auto statics = tf_static.messages();
  EXPECT_EQ(statics.size(), 2u) << "/tf_static messages: 1 at the start, then 1 for the one new pivot";
  EXPECT_EQ(statics.back().transforms.size(), 51u);

  const ros::WallTime sent = ros::WallTime::now();
  ASSERT_EQ(kill(pid, SIGINT), 0);
  double seconds = 0.0;
  const int status = wait_exit(pid, 60.0, &seconds);
  EXPECT_TRUE(status != -1 && WIFEXITED(status) && WEXITSTATUS(status) == 0) << describe(status);
  const auto left = registrations_of("/" + name);
  EXPECT_EQ(left.first, 0) << "topics of the node left on the master";
  EXPECT_EQ(left.second, 0) << "services of the node left on the master";
  std::printf("[ measured ] SIGINT with 81 tops: %s, %.3f s\n", describe(status).c_str(),
              (ros::WallTime::now() - sent).toSec());
  ros::param::del("/" + name);
}

// ~top_topics and ~top_reset_services choose what each top of ~tops registers with the master,
// ~spawn_topics and ~spawn_reset_services what a spawned top does: with hundreds of tops, fewer
// registrations per top keep a spawn's cost flat and the shutdown short (bench/node_scale.py
// --per-top). With [state] and no reset services, the tops of ~tops register their
// ~<name>/state alone (1 topic, no service); with [state] and reset services, each spawned top
// its ~<name>/state and ~<name>/reset. Each state comes with the top's name, ~states carries
// every top in the node's order (every 2nd tick: ~states_rate), ~events a spawned top's event,
// and SIGINT leaves nothing of the node on the master.
TEST(ManyTops, TopTopicsChooseWhatEachTopRegisters) {
  const std::string name = "lean";
  many_tops(name, 3);
  XmlRpc::XmlRpcValue topics;
  topics.setSize(1);
  topics[0] = std::string("state");
  ros::param::set("/" + name + "/top_topics", topics);
  ros::param::set("/" + name + "/top_reset_services", false);
  ros::param::set("/" + name + "/spawn_topics", topics);
  ros::param::set("/" + name + "/spawn_reset_services", true);
  ros::param::set("/" + name + "/states_rate", 50.0);  // every 2nd tick of 100 Hz
  const std::string node = "/" + name;
  const pid_t pid = start_node(name);
  ASSERT_GT(pid, 0);
  const ReapAtExit reap{pid};
  ASSERT_TRUE(ros::service::waitForService(node + "/spawn", ros::Duration(120.0)));
  EXPECT_TRUE(publishes(node, node + "/t002/state"));
  for (const char* absent : {"contact_point", "normal_force", "twist", "markers", "event", "event_stamped"})
    EXPECT_FALSE(publishes(node, node + "/t002/" + absent)) << absent << " is not in ~top_topics";
  EXPECT_EQ(registrations_under(node, node + "/t002/reset").second, 0) << "~top_reset_services is false";

  ros::NodeHandle nh;
  Recorder<spinning_top::TopEvent> events(nh, node + "/events", 100);
  ASSERT_TRUE(wait_for([&] { return events.publishers() > 0; }, 30.0)) << "~events never connected";
  ros::ServiceClient spawn = nh.serviceClient<spinning_top::Spawn>(node + "/spawn", true);
  // Counted under each spawned top's own namespace: the node may still be registering its own
  // services (dynamic_reconfigure's, roscpp's logger services) when ~spawn is first answered.
  for (int i = 0; i < 5; ++i) {
    spinning_top::Spawn srv;
    srv.request.name = "s" + std::to_string(i);
    srv.request.keys = {"after_lift_off=fly"};
    srv.request.x = 0.1 * i;
    ASSERT_TRUE(spawn.call(srv) && srv.response.success) << srv.response.message;
    const auto added = registrations_under(node, node + "/" + srv.request.name + "/");
    EXPECT_EQ(added.first, 1) << "topics registered by spawn " << i;
    EXPECT_EQ(added.second, 1) << "services registered by spawn " << i;
  }
  Recorder<spinning_top::TopState> states(nh, node + "/s4/state", 100);
  ASSERT_TRUE(wait_for([&] { return states.size() >= 3; }, 30.0)) << "no ~s4/state";
  EXPECT_EQ(states.messages().back().name, "s4");

  // ~states: every top at each tick, in the node's order, with the tick's stamp; each entry as
  // the top's own ~state of that tick.
  Recorder<spinning_top::TopStateArray> all(nh, node + "/states", 100);
  ASSERT_TRUE(wait_for([&] { return all.size() >= 3 && states.size() >= 10; }, 30.0)) << "no ~states";
  const std::vector<std::string> order = {"t000", "t001", "t002", "s0", "s1", "s2", "s3", "s4"};
  const auto arrays = all.messages();
  for (std::size_t i = 1; i < arrays.size(); ++i)  // ~states_rate 50 Hz at 100 Hz: every 2nd tick
    EXPECT_NEAR((arrays[i].header.stamp - arrays[i - 1].header.stamp).toSec(), 0.02, 1e-6) << "~states_rate";
  const auto own = states.messages();
  int matched = 0;
  for (const auto& array : arrays) {
    ASSERT_EQ(array.states.size(), order.size());
    for (std::size_t i = 0; i < order.size(); ++i) {
      EXPECT_EQ(array.states[i].name, order[i]);
      EXPECT_EQ(array.states[i].header.stamp, array.header.stamp);
    }
    for (const auto& s4 : own)
      if (s4.header.stamp == array.header.stamp) {
        const spinning_top::TopState& in_array = array.states[7];
        EXPECT_EQ(in_array.time, s4.time);
        EXPECT_EQ(in_array.tilt, s4.tilt);
        EXPECT_EQ(in_array.heading, s4.heading);
        EXPECT_EQ(in_array.spin_angle, s4.spin_angle);
        EXPECT_EQ(in_array.normal_force, s4.normal_force);
        EXPECT_EQ(in_array.contact_point.x, s4.contact_point.x);
        ++matched;
      }
  }
  EXPECT_GT(matched, 0) << "no tick in both ~states and ~s4/state";

  // ~events: a spawned top whose release is an event (R < 0 at t = 0 on a tip that may not fly).
  spinning_top::Spawn stopped;
  stopped.request.name = "stopped";
  stopped.request.scene_file = SPINNING_TOP_SOURCE_DIR "/config/extreme/lift_off.yaml";
  stopped.request.keys = {"after_lift_off=stop", "initial/precession_rate=150"};
  stopped.request.x = 1.0;
  ASSERT_TRUE(spawn.call(stopped) && stopped.response.success) << stopped.response.message;
  EXPECT_NE(stopped.response.message.find(node + "/states"), std::string::npos) << stopped.response.message;
  const auto first_of_stopped = [&] {
    for (const auto& e : events.messages())
      if (e.name == "stopped") return std::make_unique<spinning_top::TopEvent>(e);
    return std::unique_ptr<spinning_top::TopEvent>();
  };
  ASSERT_TRUE(wait_for([&] { return first_of_stopped() != nullptr; }, 30.0)) << "no event of 'stopped' on ~events";
  const spinning_top::TopEvent event = *first_of_stopped();
  EXPECT_EQ(event.event, "lift_off");
  EXPECT_TRUE(event.terminal);
  EXPECT_EQ(event.time, 0.0);

  ASSERT_EQ(kill(pid, SIGINT), 0);
  const int status = wait_exit(pid, 60.0);
  EXPECT_TRUE(status != -1 && WIFEXITED(status) && WEXITSTATUS(status) == 0) << describe(status);
  const auto left = registrations_of(node);
  EXPECT_EQ(left.first, 0) << "topics of the node left on the master";
  EXPECT_EQ(left.second, 0) << "services of the node left on the master";
  ros::param::del(node);
}

int main(int argc, char** argv) { return node_test::run_node_tests(argc, argv, "test_node_many_tops", 2); }
