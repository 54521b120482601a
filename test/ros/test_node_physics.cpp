// rostest (test/node_physics.test): the node's tf, topics and services against the physics.
// Four nodes run: /spinning_top (fixed tip, theta0 = 0.3, 500 Hz), /sleeping (theta0 = 0),
// /exact (the default scene with integrator: exact, 200 Hz) and /weightless (frictionless, g = 0,
// at rest without spin, 200 Hz: nothing drives the nutation, exact refuses it, auto runs dop853).
#include <diagnostic_msgs/DiagnosticArray.h>
#include <geometry_msgs/PointStamped.h>
#include <geometry_msgs/WrenchStamped.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <unistd.h>

#include "node_test_helpers.hpp"

using node_test::reconfigure;
using node_test::Recorder;
using node_test::trigger;
using node_test::wait_for;

namespace {

std::unique_ptr<tf2_ros::Buffer> tf_buffer;

double param(const std::string& name) {
  double value = 0.0;
  EXPECT_TRUE(ros::param::get(name, value)) << name;
  return value;
}

Eigen::Quaterniond rotation_of(const geometry_msgs::TransformStamped& t) {
  return Eigen::Quaterniond(t.transform.rotation.w, t.transform.rotation.x, t.transform.rotation.y,
                            t.transform.rotation.z);
}

Eigen::Vector3d translation_of(const geometry_msgs::TransformStamped& t) {
  return Eigen::Vector3d(t.transform.translation.x, t.transform.translation.y, t.transform.translation.z);
}

/// The symmetry axis of a fixed-tip top's body transform, after checking what holds in every
/// tick: a unit quaternion (the core projects |q| = 1 after every step: a few ulps) and G = h e_Z
/// (both come from the same state: equal to round-off times h, 1e-15 m; allow 1e-12 m).
Eigen::Vector3d axis_of_fixed_tip_top(const geometry_msgs::TransformStamped& t, double h) {
  const Eigen::Quaterniond q = rotation_of(t);
  EXPECT_NEAR(q.norm(), 1.0, 1e-12);
  const Eigen::Vector3d axis = q.normalized() * Eigen::Vector3d::UnitZ();
  EXPECT_NEAR((translation_of(t) - h * axis).norm(), 0.0, 1e-12);
  return axis;
}

}  // namespace

// Fixed tip: P = 0, so G = h e_Z, i.e. the translation of world -> top is h times the third
// column of its rotation (z_G = h e_Zz in particular), and the rotation is a unit quaternion.
TEST(Node, TransformPutsCentreOfMassAtTipDistanceAlongTheAxis) {
  const double h = param("/spinning_top/tip_distance");
  for (int sample = 0; sample < 20; ++sample) {
    geometry_msgs::TransformStamped t;
    ASSERT_NO_THROW(t = tf_buffer->lookupTransform("world", "top", ros::Time(0), ros::Duration(5.0)));
    const Eigen::Vector3d axis = axis_of_fixed_tip_top(t, h);
    EXPECT_NEAR(translation_of(t).z(), h * axis.z(), 1e-12);
    EXPECT_GT(translation_of(t).z(), 0.0);
    // The contact frame sits at the tip, which is the pivot at the origin.
    const auto contact = tf_buffer->lookupTransform("world", "contact", t.header.stamp, ros::Duration(1.0));
    EXPECT_NEAR(translation_of(contact).norm(), 0.0, 1e-12);
    ros::WallDuration(0.05).sleep();
  }
}

// A sleeping top (theta = 0, omega = (0, 0, omega_Z)) is an equilibrium: a_G = 0, so the
// floor carries its weight, R = m g, with no horizontal reaction (PHYSICS.md, sleeping top).
TEST(Node, SleepingTopNormalForceIsItsWeight) {
  ros::NodeHandle nh;
  Recorder<geometry_msgs::WrenchStamped> forces(nh, "/sleeping/normal_force");
  ASSERT_TRUE(wait_for([&] { return forces.size() >= 50; }, 10.0));
  const double weight = param("/sleeping/mass") * param("/sleeping/gravity");
  for (const auto& w : forces.messages()) {
    EXPECT_EQ(w.header.frame_id, "sleeping_contact");
    // Equilibrium holds exactly in the model; the integrator leaves round-off: 1e-12 N of 1 N.
    EXPECT_NEAR(w.wrench.force.z, weight, 1e-12 * weight);
    EXPECT_NEAR(std::hypot(w.wrench.force.x, w.wrench.force.y), 0.0, 1e-12 * weight);
  }
  // And its body frame stands upright at height h above the tip.
  const auto t = tf_buffer->lookupTransform("world", "sleeping_top", ros::Time(0), ros::Duration(5.0));
  EXPECT_NEAR(t.transform.translation.z, param("/sleeping/tip_distance"), 1e-12);
}

// The default scene through the closed-form integrator: started at rest at theta0 with
// thetadot0 = phidot0 = 0, u = cos(theta) stays between the roots u0 and u1 of the cubic
// f(u) = (u0 - u) [beta (1 - u^2) - a^2 (u0 - u)] (PHYSICS.md; Goldstein 5.7 with
// L_z = C omega_Z u0 and E' = m g h u0), a = C omega_Z / A0, beta = 2 m g h / A0, so theta
// nutates between theta0 and acos(u1), u1 the smaller root of beta u^2 - a^2 u + a^2 u0 - beta.
TEST(Node, ExactIntegratorNutatesBetweenTheRootsOfTheCubic) {
  const double m = param("/exact/mass"), g = param("/exact/gravity"), h = param("/exact/tip_distance");
  const double a0 = param("/exact/inertia_transverse") + m * h * h;
  const double a = param("/exact/inertia_axial") * param("/exact/initial/spin") / a0;
  const double beta = 2.0 * m * g * h / a0;
  const double theta0 = param("/exact/initial/tilt"), u0 = std::cos(theta0);
  const double u1 = (a * a - std::sqrt(a * a * a * a - 4.0 * beta * (a * a * u0 - beta))) / (2.0 * beta);
  const double theta1 = std::acos(u1), width = theta1 - theta0;
  ASSERT_GT(width, 1e-3);  // the shipped scene nutates by ~0.012 rad
  double lowest = theta1, highest = theta0;
  for (int sample = 0; sample < 150; ++sample) {
    geometry_msgs::TransformStamped t;
    ASSERT_NO_THROW(t = tf_buffer->lookupTransform("world", "exact_top", ros::Time(0), ros::Duration(5.0)));
    const Eigen::Vector3d axis = axis_of_fixed_tip_top(t, h);
    const double theta = std::acos(std::min(1.0, axis.z()));
    // exact is at 1e-13 rad (test_exact); the band is checked to 1e-9 rad of its 1.2e-2 width.
    EXPECT_GE(theta, theta0 - 1e-9);
    EXPECT_LE(theta, theta1 + 1e-9);
    lowest = std::min(lowest, theta);
    highest = std::max(highest, theta);
    ros::WallDuration(0.007).sleep();  // ~1 s of samples over ~17 nutation periods (58 ms)
  }
  // It moves through the band rather than sitting at its start.
  EXPECT_LT(lowest, theta0 + 0.2 * width);
  EXPECT_GT(highest, theta1 - 0.2 * width);
}

// Diagnostics say what runs and why: auto runs exact on the shipped scene, and dop853 with
// exact's refusal where exact cannot start (a weightless top at rest: nothing drives the nutation).
TEST(Node, DiagnosticsSayWhichIntegratorAutoRunsAndWhy) {
  ros::NodeHandle nh;
  Recorder<diagnostic_msgs::DiagnosticArray> diagnostics(nh, "/diagnostics");
  // The value of a key in the latest status of that name ("" until one arrives).
  auto value_of = [&](const std::string& status_name, const std::string& key) {
    std::string value;
    for (const auto& array : diagnostics.messages())
      for (const auto& status : array.status)
        if (status.name == status_name)
          for (const auto& entry : status.values)
            if (entry.key == key) value = entry.value;
    return value;
  };
  ASSERT_TRUE(wait_for(
      [&] {
        return !value_of("spinning_top: simulation", "integrator").empty() &&
               !value_of("weightless: simulation", "integrator").empty();
      },
      10.0))
      << "no diagnostics from /spinning_top and /weightless";
  const std::string shipped = value_of("spinning_top: simulation", "integrator");
  EXPECT_EQ(shipped.rfind("auto: exact: closed form", 0), 0u) << shipped;
  EXPECT_EQ(value_of("spinning_top: simulation", "integrator method"), "exact");
  EXPECT_EQ(value_of("spinning_top: simulation", "integrator fallback reason"), "");
  const std::string weightless = value_of("weightless: simulation", "integrator");
  EXPECT_EQ(weightless.rfind("auto: dop853, tolerance 1e-12 (exact refused: ", 0), 0u) << weightless;
  EXPECT_EQ(value_of("weightless: simulation", "integrator method"), "dop853");
  EXPECT_NE(value_of("weightless: simulation", "integrator fallback reason").find("nothing drives the nutation"),
            std::string::npos);
}

// Each tick advances exactly 1/rate of simulated time, however long it took: consecutive
// stamps differ by 1/rate to the nanosecond rounding of ros::Time (2 ns allowed).
TEST(Node, StampsAdvanceByExactlyOneTickAndNeverRepeat) {
  ros::NodeHandle nh;
  Recorder<geometry_msgs::PointStamped> points(nh, "/spinning_top/contact_point");
  ASSERT_TRUE(wait_for([&] { return points.size() >= 300; }, 10.0));
  const double period = 1.0 / param("/spinning_top/rate");
  const auto messages = points.messages();
  for (size_t i = 1; i < messages.size(); ++i) {
    const double dt = (messages[i].header.stamp - messages[i - 1].header.stamp).toSec();
    ASSERT_NEAR(dt, period, 2e-9) << "at message " << i;
  }
  EXPECT_NE(messages.front().header.stamp, ros::Time(0));
}

// A friction coefficient in the fixed-tip scene and a negative g cannot describe the scene:
// the node refuses them, reports its previous configuration back and keeps running.
TEST(Node, InvalidReconfigureIsRefusedAndSimulationContinues) {
  ros::NodeHandle nh;
  const double g = param("/spinning_top/gravity");
  EXPECT_EQ(reconfigure("/spinning_top", "friction", 0.5), 0.0);
  EXPECT_EQ(reconfigure("/spinning_top", "gravity", -1.0), g);
  EXPECT_EQ(reconfigure("/spinning_top", "tolerance", 0.0), param("/spinning_top/tolerance"));
  EXPECT_EQ(reconfigure("/spinning_top", "rate", -5.0), param("/spinning_top/rate"));
  // A valid update is applied (and undone so that the other tests see the scene file).
  EXPECT_EQ(reconfigure("/spinning_top", "gravity", 9.0), 9.0);
  EXPECT_EQ(reconfigure("/spinning_top", "gravity", g), g);

  Recorder<geometry_msgs::PointStamped> points(nh, "/spinning_top/contact_point");
  ASSERT_TRUE(wait_for([&] { return points.size() >= 100; }, 10.0));
  const auto messages = points.messages();
  EXPECT_GT(messages.back().header.stamp, messages.front().header.stamp);
}

// A live rate change: ticks then advance by the new 1/rate exactly (stamps to 2 ns).
TEST(Node, LiveRateChangeGivesTheNewTickExactly) {
  ros::NodeHandle nh;
  const double rate = param("/spinning_top/rate");
  ASSERT_EQ(reconfigure("/spinning_top", "rate", 250.0), 250.0);
  ros::WallDuration(0.3).sleep();  // let ticks at the old rate arrive first
  Recorder<geometry_msgs::PointStamped> points(nh, "/spinning_top/contact_point");
  ASSERT_TRUE(wait_for([&] { return points.size() >= 100; }, 10.0));
  EXPECT_EQ(reconfigure("/spinning_top", "rate", rate), rate);
  const auto messages = points.messages();
  for (size_t i = 1; i < 100; ++i)
    ASSERT_NEAR((messages[i].header.stamp - messages[i - 1].header.stamp).toSec(), 1.0 / 250.0, 2e-9) << i;
}

// ~pause stops the ticks (no message, no tf, so no repeated stamps); ~step advances one
// tick; ~resume continues one tick after the last stamp; ~reset brings back the initial
// attitude while the stamps keep moving forward.
TEST(Node, PauseStepResumeAndResetKeepTimeMovingForward) {
  ros::NodeHandle nh;
  const double period = 1.0 / param("/spinning_top/rate");
  Recorder<geometry_msgs::PointStamped> points(nh, "/spinning_top/contact_point");
  ASSERT_TRUE(wait_for([&] { return points.size() >= 10; }, 10.0));

  EXPECT_TRUE(trigger("/spinning_top/pause").success);
  ros::WallDuration(0.3).sleep();  // let what was in flight arrive
  const size_t before = points.size();
  const ros::Time paused_stamp = points.messages().back().header.stamp;
  ros::WallDuration(0.5).sleep();
  EXPECT_EQ(points.size(), before) << "published while paused";

  EXPECT_FALSE(trigger("/spinning_top/resume").message.empty());
  ASSERT_TRUE(wait_for([&] { return points.size() >= before + 10; }, 10.0));
  EXPECT_NEAR((points.messages()[before].header.stamp - paused_stamp).toSec(), period, 2e-9);

  // Reset while paused, then one step: the pose is the initial one after a single tick.
  EXPECT_TRUE(trigger("/spinning_top/pause").success);
  ros::WallDuration(0.3).sleep();
  const ros::Time last_stamp = points.messages().back().header.stamp;
  EXPECT_TRUE(trigger("/spinning_top/reset").success);
  const size_t after_reset = points.size();
  EXPECT_TRUE(trigger("/spinning_top/step").success);
  ASSERT_TRUE(wait_for([&] { return points.size() == after_reset + 1; }, 5.0));
  const ros::Time step_stamp = points.messages().back().header.stamp;
  EXPECT_NEAR((step_stamp - last_stamp).toSec(), period, 2e-9);

  const auto t = tf_buffer->lookupTransform("world", "top", step_stamp, ros::Duration(5.0));
  const double h = param("/spinning_top/tip_distance");
  const double tilt = param("/spinning_top/initial/tilt");
  const double heading = param("/spinning_top/initial/heading");
  // e_Z(0) = (sin t sin phi, -sin t cos phi, cos t) (PHYSICS.md). Starting from rest the axis
  // moves by ~(m g h sin t / A0) dt^2 / 2 = 1.5e-4 rad in one 2 ms tick: allow 1e-3 rad.
  const Eigen::Vector3d e_z0(std::sin(tilt) * std::sin(heading), -std::sin(tilt) * std::cos(heading), std::cos(tilt));
  EXPECT_NEAR((translation_of(t) - h * e_z0).norm(), 0.0, 1e-3 * h);

  EXPECT_FALSE(trigger("/spinning_top/step").message.empty());
  EXPECT_TRUE(trigger("/spinning_top/resume").success);
  EXPECT_FALSE(trigger("/spinning_top/step").success) << "step must refuse while running";
  ASSERT_TRUE(wait_for([&] { return points.size() >= after_reset + 20; }, 10.0));
  const auto messages = points.messages();
  for (size_t i = 1; i < messages.size(); ++i) ASSERT_GT(messages[i].header.stamp, messages[i - 1].header.stamp);
}

// `rosbag record` of the node's topics gives a bag that holds every one of them.
TEST(Node, RosbagRecordsTfClockAndTopics) {
  char directory[] = "/tmp/spinning_top_bag_XXXXXX";
  ASSERT_NE(mkdtemp(directory), nullptr);
  const std::string bag = std::string(directory) + "/top.bag";
  const std::string topics =
      "/tf /clock /diagnostics /spinning_top/contact_point /spinning_top/normal_force /spinning_top/markers";
  const std::string record = "timeout 30 rosbag record -q -O " + bag + " --duration=3 " + topics + " >/dev/null 2>&1";
  ASSERT_EQ(std::system(record.c_str()), 0) << record;
  FILE* info = popen(("rosbag info --yaml --key=topics " + bag).c_str(), "r");
  ASSERT_NE(info, nullptr);
  std::string text;
  char buffer[4096];
  while (fgets(buffer, sizeof buffer, info) != nullptr) text += buffer;
  EXPECT_EQ(pclose(info), 0);
  for (const char* topic : {"/tf", "/clock", "/diagnostics", "/spinning_top/contact_point",
                            "/spinning_top/normal_force", "/spinning_top/markers"})
    EXPECT_NE(text.find(std::string("topic: ") + topic + "\n"), std::string::npos) << topic << " not in\n" << text;
  std::remove(bag.c_str());
  rmdir(directory);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_node_physics");
  ros::NodeHandle nh;
  ros::AsyncSpinner spinner(2);
  spinner.start();
  tf_buffer = std::make_unique<tf2_ros::Buffer>();
  auto listener = std::make_unique<tf2_ros::TransformListener>(*tf_buffer);
  const int result = RUN_ALL_TESTS();
  listener.reset();
  tf_buffer.reset();
  return result;
}
