// Several tops in one node, set_state, refused live changes, the twist (node_tops.test).
#include <dynamic_reconfigure/Reconfigure.h>
#include <geometry_msgs/PointStamped.h>
#include <geometry_msgs/TwistStamped.h>
#include <gtest/gtest.h>
#include <rosgraph_msgs/Clock.h>
#include <std_msgs/String.h>
#include <tf2_msgs/TFMessage.h>

#include <Eigen/Geometry>
#include <cmath>
#include <map>
#include <set>

#include "node_test_helpers.hpp"
#include "spinning_top/Kill.h"
#include "spinning_top/SetState.h"
#include "spinning_top/Spawn.h"
#include "spinning_top/TopState.h"
#include "spinning_top/TopStateArray.h"

using node_test::Recorder;
using node_test::trigger;
using node_test::wait_for;

namespace {

template <class Service>
typename Service::Response call(const std::string& name, typename Service::Request request) {
  EXPECT_TRUE(ros::service::waitForService(name, ros::Duration(10.0))) << name;
  Service srv;
  srv.request = request;
  EXPECT_TRUE(ros::service::call(name, srv)) << name;
  return srv.response;
}

std::set<double> stamps(const std::vector<geometry_msgs::PointStamped>& messages) {
  std::set<double> s;
  for (const auto& m : messages) s.insert(m.header.stamp.toSec());
  return s;
}

// Two tops from ~tops in one node: each its own frames and topics at the tick rate, one /clock
// that only goes forward, and both tops stamped alike at every tick.
TEST(Tops, TwoTopsShareOneClock) {
  ros::NodeHandle nh;
  Recorder<geometry_msgs::PointStamped> slow(nh, "/spinning_top/slow/contact_point", 10000);
  Recorder<geometry_msgs::PointStamped> fast(nh, "/spinning_top/fast/contact_point", 10000);
  Recorder<rosgraph_msgs::Clock> clock(nh, "/clock", 10000);
  Recorder<tf2_msgs::TFMessage> tf(nh, "/tf", 10000);
  Recorder<tf2_msgs::TFMessage> tf_static(nh, "/tf_static", 10);
  ASSERT_TRUE(wait_for([&] { return slow.size() >= 600 && fast.size() >= 600; }, 20.0));
  const ros::WallTime start = ros::WallTime::now();
  const size_t slow_before = slow.size();
  ros::WallDuration(2.0).sleep();
  // Each top's topic at the tick rate (500 Hz at real-time factor 1; 25 % for a shared CI machine).
  const double rate = (slow.size() - slow_before) / (ros::WallTime::now() - start).toSec();
  EXPECT_NEAR(rate, 500.0, 125.0);

  const auto clocks = clock.messages();
  for (size_t i = 1; i < clocks.size(); ++i) ASSERT_GT(clocks[i].clock, clocks[i - 1].clock) << i;
  // Stamps alike: every stamp of one top is a stamp of the other (over the stretch both recorded).
  const std::set<double> a = stamps(slow.messages()), b = stamps(fast.messages());
  const double first = std::max(*a.begin(), *b.begin()), last = std::min(*a.rbegin(), *b.rbegin());
  size_t compared = 0;
  for (const double t : a)
    if (t >= first && t <= last) {
      EXPECT_EQ(b.count(t), 1u) << t;
      ++compared;
    }
  EXPECT_GT(compared, 500u);
  // One tf message per tick holds both bodies; the fixed tips' pivots (after_lift_off: stop, so
  // they never move) are static, at their places.
  std::map<std::string, int> bodies;
  for (const auto& message : tf.messages())
    for (const auto& t : message.transforms) ++bodies[t.child_frame_id];
  EXPECT_GT(bodies["slow/top"], 500);
  EXPECT_EQ(bodies["slow/top"], bodies["fast/top"]);
  EXPECT_EQ(bodies.count("slow/contact"), 0u) << "a fixed tip's contact frame belongs on /tf_static";
  std::map<std::string, geometry_msgs::Vector3> pivots;
  for (const auto& message : tf_static.messages())
    for (const auto& t : message.transforms) pivots[t.child_frame_id] = t.transform.translation;
  ASSERT_EQ(pivots.count("slow/contact"), 1u);
  ASSERT_EQ(pivots.count("fast/contact"), 1u);
  EXPECT_EQ(pivots["slow/contact"].y, 0.1);
  EXPECT_EQ(pivots["fast/contact"].y, -0.1);
  EXPECT_EQ(slow.messages().back().point.y, 0.1);

  // Each top's URDF for rviz's RobotModel: one link named as its body frame, with its mass.
  std::string urdf;
  ASSERT_TRUE(ros::param::get("/spinning_top/fast/robot_description", urdf));
  EXPECT_NE(urdf.find("<link name=\"fast/top\">"), std::string::npos) << urdf;
  EXPECT_NE(urdf.find("<mass value=\"0.10000000000000001\"/>"), std::string::npos) << urdf;
}

// ~spawn adds a top with its own keys, refuses bad ones naming the key, and ~kill removes it. A
// spawned top has no topics of its own by default (~spawn_topics): its state is on ~states.
TEST(Tops, SpawnAndKill) {
  ros::NodeHandle nh;
  Recorder<spinning_top::TopStateArray> states(nh, "/spinning_top/states");
  // The states of `name` in ~states, in time order.
  const auto states_of = [&](const std::string& name) {
    std::vector<spinning_top::TopState> of;
    for (const auto& array : states.messages())
      for (const auto& s : array.states)
        if (s.name == name) of.push_back(s);
    return of;
  };
  spinning_top::Spawn::Request bad;
  bad.name = "third";
  bad.keys = {"initial/tilt=2.0"};
  auto refused = call<spinning_top::Spawn>("/spinning_top/spawn", bad);
  EXPECT_FALSE(refused.success);
  EXPECT_NE(refused.message.find("initial/tilt"), std::string::npos) << refused.message;
  bad.keys = {"mas=1"};
  refused = call<spinning_top::Spawn>("/spinning_top/spawn", bad);
  EXPECT_FALSE(refused.success);
  EXPECT_NE(refused.message.find("mass"), std::string::npos) << "a typo gets the nearest key: " << refused.message;
  bad.keys = {};
  bad.name = "slow";
  EXPECT_FALSE(call<spinning_top::Spawn>("/spinning_top/spawn", bad).success) << "the name is taken";

  spinning_top::Spawn::Request request;
  request.name = "third";
  request.keys = {"initial/spin=90", "initial/tilt=0.2"};
  request.x = 0.3;
  const auto spawned = call<spinning_top::Spawn>("/spinning_top/spawn", request);
  ASSERT_TRUE(spawned.success) << spawned.message;
  EXPECT_TRUE(node_test::publishers_of("/spinning_top/third/state").empty())
      << "a spawned top has no ~<name>/state by default";
  ASSERT_TRUE(wait_for([&] { return states_of("third").size() >= 50; }, 10.0));
  const spinning_top::TopState s = states_of("third").front();
  EXPECT_EQ(s.name, "third");
  EXPECT_EQ(s.spin, 90.0);
  EXPECT_EQ(s.contact_point.x, 0.3);
  // Its own time started at 0 when it was spawned, seconds after the world's (stamps are the
  // world's simulated time under use_sim_time).
  EXPECT_LT(s.time, s.header.stamp.toSec() - 1.0) << "a spawned top starts at its own time 0";

  spinning_top::Kill::Request kill;
  kill.name = "third";
  EXPECT_TRUE(call<spinning_top::Kill>("/spinning_top/kill", kill).success);
  ros::WallDuration(0.3).sleep();
  const size_t after = states_of("third").size();
  const size_t arrays = states.size();
  ros::WallDuration(0.5).sleep();
  EXPECT_GT(states.size(), arrays) << "~states stopped";
  EXPECT_EQ(states_of("third").size(), after) << "published after ~kill";
  EXPECT_FALSE(call<spinning_top::Kill>("/spinning_top/kill", kill).success) << "killed twice";
  EXPECT_FALSE(ros::param::has("/spinning_top/third/robot_description")) << "a killed top's URDF stays";
  // A later /tf_static subscriber gets the pivots of the tops that are left, not the killed one's.
  // (The test's other nodes latch their own pivots on /tf_static too.)
  Recorder<tf2_msgs::TFMessage> tf_static(nh, "/tf_static", 10);
  std::set<std::string> frames;
  ASSERT_TRUE(wait_for([&] {
    frames.clear();
    for (const auto& message : tf_static.messages())
      for (const auto& t : message.transforms) frames.insert(t.child_frame_id);
    return frames.count("slow/contact") > 0;
  }, 5.0));
  EXPECT_EQ(frames.count("fast/contact"), 1u);
  EXPECT_EQ(frames.count("third/contact"), 0u) << "a killed top's pivot is still latched";
}

// ~set_state, read back from ~state over two ticks (paused, then ~step twice): the spin is a
// constant of motion, the pivot is where it was put, the angles moved by their rates x dt
// (1e-3 rad: the second-order term, |theta''| dt^2 / 2, is below 1e-4 rad here), and the rates at
// the first tick are the central differences of the angles over both ticks (error
// dt^2 |theta'''| / 6 < 2e-3 rad/s for a nutation at ~40 rad/s of 0.05 rad; tolerance 0.02 rad/s).
TEST(Tops, SetStateIsReadBack) {
  ros::NodeHandle nh;
  Recorder<spinning_top::TopState> states(nh, "/spinning_top/slow/state");
  ASSERT_TRUE(wait_for([&] { return states.size() > 0; }, 10.0));
  EXPECT_TRUE(trigger("/spinning_top/pause").success);
  ros::WallDuration(0.3).sleep();
  spinning_top::SetState::Request request;
  request.name = "slow";
  request.tilt = 0.5;
  request.heading = 1.0;
  request.precession_rate = 2.0;
  request.nutation_rate = -1.0;
  request.spin = 77.0;
  request.x = -0.25;
  request.y = 0.15;
  const auto set = call<spinning_top::SetState>("/spinning_top/set_state", request);
  ASSERT_TRUE(set.success) << set.message;
  states.clear();
  EXPECT_TRUE(trigger("/spinning_top/step").success);
  ASSERT_TRUE(wait_for([&] { return states.size() == 1; }, 5.0));
  EXPECT_TRUE(trigger("/spinning_top/step").success);
  ASSERT_TRUE(wait_for([&] { return states.size() == 2; }, 5.0));
  const spinning_top::TopState s = states.messages()[0], s2 = states.messages()[1];
  const double dt = 1.0 / 500.0;
  EXPECT_NEAR(s.time, dt, 1e-12);
  EXPECT_NEAR(s2.time, 2.0 * dt, 1e-12);
  EXPECT_EQ(s.spin, 77.0);
  EXPECT_EQ(s.contact_point.x, -0.25);
  EXPECT_EQ(s.contact_point.y, 0.15);
  EXPECT_NEAR(s.tilt, 0.5 - dt, 1e-3);           // thetadot = -1 rad/s
  EXPECT_NEAR(s.heading, 1.0 + 2.0 * dt, 1e-3);  // phidot = 2 rad/s
  EXPECT_NEAR(s.nutation_rate, (s2.tilt - 0.5) / (2.0 * dt), 0.02);
  EXPECT_NEAR(s.precession_rate, (s2.heading - 1.0) / (2.0 * dt), 0.02);
  EXPECT_EQ(s.event, "");

  // The core's refusals: the axis below the floor, a sideways velocity where G cannot move so.
  request.tilt = 2.0;
  auto refused = call<spinning_top::SetState>("/spinning_top/set_state", request);
  EXPECT_FALSE(refused.success);
  EXPECT_NE(refused.message.find("initial/tilt"), std::string::npos) << refused.message;
  request.tilt = 0.5;
  request.velocity_x = 1.0;
  refused = call<spinning_top::SetState>("/spinning_top/set_state", request);
  EXPECT_FALSE(refused.success);
  EXPECT_NE(refused.message.find("velocity_x"), std::string::npos) << refused.message;
  request.name = "nobody";
  EXPECT_FALSE(call<spinning_top::SetState>("/spinning_top/set_state", request).success);
  EXPECT_TRUE(trigger("/spinning_top/resume").success);
}

// A refused live change is visible to the caller (the configuration sent back, and the latched
// ~status), changes nothing, and nothing non-finite is published; an accepted body change goes
// on from the current state.
TEST(Tops, LiveChangesAndRefusals) {
  ros::NodeHandle nh;
  Recorder<std_msgs::String> status(nh, "/spinning_top/status");
  Recorder<spinning_top::TopState> fast(nh, "/spinning_top/fast/state", 10000);
  ASSERT_TRUE(wait_for([&] { return fast.size() > 10; }, 10.0));
  EXPECT_EQ(node_test::reconfigure("/spinning_top", "mass", -1.0), 0.1) << "the old mass is sent back";
  ASSERT_TRUE(wait_for([&] { return !status.messages().empty() && status.messages().back().data.find("refused") == 0; }, 5.0));
  EXPECT_NE(status.messages().back().data.find("mass"), std::string::npos) << status.messages().back().data;
  EXPECT_EQ(node_test::reconfigure("/spinning_top", "inertia_axial", 1.0), node_test::reconfigure("/spinning_top", "inertia_axial", NAN));
  ASSERT_TRUE(wait_for([&] { return status.messages().back().data.find("inertia_axial") != std::string::npos; }, 5.0));

  // A kick: the spin of every top becomes 120 rad/s, the tilt goes on continuously.
  fast.clear();
  EXPECT_EQ(node_test::reconfigure("/spinning_top", "spin", 120.0), 120.0);
  ASSERT_TRUE(wait_for([&] { return status.messages().back().data.find("applied") == 0; }, 5.0));
  ASSERT_TRUE(wait_for([&] { return fast.size() > 100; }, 10.0));
  const auto states = fast.messages();
  EXPECT_EQ(states.back().spin, 120.0);
  for (size_t i = 1; i < states.size(); ++i) {
    ASSERT_TRUE(std::isfinite(states[i].tilt) && std::isfinite(states[i].normal_force));
    // At most thetadot x 2 ms between ticks: continuous across the change.
    EXPECT_LT(std::abs(states[i].tilt - states[i - 1].tilt), 0.05) << i;
    EXPECT_GT(states[i].time, states[i - 1].time) << "the top's time goes on across the change";
  }
  EXPECT_NEAR(states.back().energy_balance, 0.0, 1e-9) << "the energy is rebaselined at the change";
}

// ~twist against the pose: omega from successive attitudes (tf), G's velocity from successive
// positions; central differences over 2 ticks of 0.1 ms, whose error (omega dt)^2 / 6 ~ 4e-5 of
// omega at 150 rad/s is within the 1e-3 relative tolerance.
TEST(Tops, TwistIsThePoseDerivative) {
  ros::NodeHandle nh;
  Recorder<tf2_msgs::TFMessage> tf(nh, "/tf", 100000);
  Recorder<geometry_msgs::TwistStamped> twist(nh, "/smooth/twist", 100000);
  ASSERT_TRUE(wait_for([&] { return twist.size() > 300; }, 20.0));
  std::map<double, geometry_msgs::Transform> poses;
  for (const auto& message : tf.messages())
    for (const auto& t : message.transforms)
      if (t.child_frame_id == "smooth_top") poses[t.header.stamp.toSec()] = t.transform;
  int compared = 0;
  for (const auto& w : twist.messages()) {
    const ros::Time t = w.header.stamp;
    const ros::Duration dt(1e-4);
    const auto before = poses.find((t - dt).toSec()), after = poses.find((t + dt).toSec());
    if (before == poses.end() || after == poses.end()) continue;
    auto q = [](const geometry_msgs::Transform& p) {
      return Eigen::Quaterniond(p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z);
    };
    auto x = [](const geometry_msgs::Transform& p) {
      return Eigen::Vector3d(p.translation.x, p.translation.y, p.translation.z);
    };
    const Eigen::AngleAxisd turn(q(after->second) * q(before->second).conjugate());
    const Eigen::Vector3d omega = turn.axis() * turn.angle() / 2e-4;
    const Eigen::Vector3d velocity = (x(after->second) - x(before->second)) / 2e-4;
    const Eigen::Vector3d published_omega(w.twist.angular.x, w.twist.angular.y, w.twist.angular.z);
    const Eigen::Vector3d published_velocity(w.twist.linear.x, w.twist.linear.y, w.twist.linear.z);
    EXPECT_NEAR((omega - published_omega).norm(), 0.0, 1e-3 * published_omega.norm());
    EXPECT_NEAR((velocity - published_velocity).norm(), 0.0, 1e-3 * std::max(published_velocity.norm(), 1e-3));
    ++compared;
  }
  EXPECT_GT(compared, 100);
}

// ~reload reads the keys again: a new tilt for "fast" is its state one tick after; a bad one is
// refused naming the key (response and ~status) and nothing changes (the top's time goes on).
TEST(Tops, ReloadReadsTheParametersAgain) {
  ros::NodeHandle nh;
  Recorder<spinning_top::TopState> fast(nh, "/spinning_top/fast/state");
  Recorder<std_msgs::String> status(nh, "/spinning_top/status");
  ASSERT_TRUE(wait_for([&] { return fast.size() > 0; }, 10.0));
  EXPECT_TRUE(trigger("/spinning_top/pause").success);
  ros::WallDuration(0.3).sleep();
  ros::param::set("/spinning_top/fast/initial/tilt", 0.4);
  const auto reloaded = trigger("/spinning_top/reload");
  EXPECT_TRUE(reloaded.success) << reloaded.message;
  fast.clear();
  EXPECT_TRUE(trigger("/spinning_top/step").success);
  ASSERT_TRUE(wait_for([&] { return fast.size() == 1; }, 5.0));
  const double dt = 1.0 / 500.0;
  EXPECT_NEAR(fast.messages()[0].time, dt, 1e-12);
  EXPECT_NEAR(fast.messages()[0].tilt, 0.4, 1e-3);  // from rest: (m g h sin(theta) / A') dt^2 / 2
  EXPECT_EQ(fast.messages()[0].spin, 150.0) << "the key's spin, not the live kick's";

  ros::param::set("/spinning_top/fast/initial/tilt", 2.5);
  const auto refused = trigger("/spinning_top/reload");
  EXPECT_FALSE(refused.success);
  EXPECT_NE(refused.message.find("fast/initial/tilt"), std::string::npos) << refused.message;
  ASSERT_TRUE(wait_for([&] { return !status.messages().empty() && status.messages().back().data.find("refused") == 0; }, 5.0));
  EXPECT_TRUE(trigger("/spinning_top/step").success);
  ASSERT_TRUE(wait_for([&] { return fast.size() == 2; }, 5.0));
  EXPECT_NEAR(fast.messages()[1].time, 2.0 * dt, 1e-12) << "a refused reload changed the top";
  // ~reset_reads_parameters makes ~reset do the same.
  ros::param::set("/spinning_top/fast/initial/tilt", 0.35);
  ros::param::set("/spinning_top/reset_reads_parameters", true);
  EXPECT_TRUE(trigger("/spinning_top/reset").success);
  ros::param::set("/spinning_top/reset_reads_parameters", false);
  EXPECT_TRUE(trigger("/spinning_top/step").success);
  ASSERT_TRUE(wait_for([&] { return fast.size() == 3; }, 5.0));
  EXPECT_NEAR(fast.messages()[2].time, dt, 1e-12);
  EXPECT_NEAR(fast.messages()[2].tilt, 0.35, 1e-3);
  ros::param::set("/spinning_top/fast/initial/tilt", 0.3);
  EXPECT_TRUE(trigger("/spinning_top/resume").success);
}

// ~wait_for_subscriber (what record:=true sets): seconds after the start, the first message a
// late subscriber gets is the first tick's, stamped 1/rate (simulated time, origin 0).
TEST(Tops, WaitsForTheFirstSubscriber) {
  ros::WallDuration(1.0).sleep();
  ros::NodeHandle nh;
  Recorder<geometry_msgs::PointStamped> points(nh, "/waiting/contact_point");
  ros::WallDuration(0.5).sleep();
  EXPECT_EQ(points.size(), 0u) << "ran before ~state had a subscriber";
  Recorder<spinning_top::TopState> states(nh, "/waiting/state");
  ASSERT_TRUE(wait_for([&] { return points.size() >= 10 && states.size() >= 10; }, 10.0));
  EXPECT_EQ(points.messages().front().header.stamp, ros::Time(1.0 / 500.0));
  EXPECT_EQ(states.messages().front().header.stamp, ros::Time(1.0 / 500.0));
}

}  // namespace

int main(int argc, char** argv) { return node_test::run_node_tests(argc, argv, "test_node_tops", 2); }
