// rostest (test/node_event.test): a top without spin falls; the node stops at the event,
// publishes it on the latched ~event topic, reports it as a diagnostics ERROR, keeps
// publishing the last valid pose at rest with fresh stamps, and never publishes a non-finite value.
#include <diagnostic_msgs/DiagnosticArray.h>
#include <geometry_msgs/PointStamped.h>
#include <geometry_msgs/WrenchStamped.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <std_msgs/String.h>

#include <cmath>
#include <string>

#include "node_test_helpers.hpp"

using node_test::finite;
using node_test::Recorder;
using node_test::trigger;
using node_test::wait_for;

namespace {

bool is_event_name(const std::string& name) { return name == "fallen" || name == "lift_off"; }

}  // namespace

TEST(NodeEvent, FallingTopEndsWithTheEventAndNoNaN) {
  ros::NodeHandle nh;
  Recorder<geometry_msgs::WrenchStamped> forces(nh, "/falling/normal_force", 100000);
  Recorder<geometry_msgs::PointStamped> points(nh, "/falling/contact_point", 100000);
  Recorder<diagnostic_msgs::DiagnosticArray> diagnostics(nh, "/diagnostics");
  // Latched: a late subscriber still gets the event.
  Recorder<std_msgs::String> events(nh, "/falling/event");
  // theta'' = (m g h / A0) sin(theta) = 245 s^-2 sin(theta): down in ~0.2 s; allow 20 s of wall time.
  ASSERT_TRUE(wait_for([&] { return events.size() >= 1; }, 20.0)) << "no event";
  const std::string event = events.messages().back().data;
  EXPECT_TRUE(is_event_name(event)) << event;

  // Afterwards: the same (last valid) pose at rest, republished with strictly increasing stamps.
  forces.clear();
  points.clear();
  ASSERT_TRUE(wait_for([&] { return forces.size() >= 50 && points.size() >= 50; }, 10.0));
  const auto frozen = forces.messages();
  for (size_t i = 0; i < frozen.size(); ++i) {
    ASSERT_TRUE(finite(frozen[i]));
    // At rest: no floor force (not the last R of the motion, frozen).
    EXPECT_EQ(frozen[i].wrench.force.x, 0.0);
    EXPECT_EQ(frozen[i].wrench.force.y, 0.0);
    EXPECT_EQ(frozen[i].wrench.force.z, 0.0);
    if (i > 0) {
      EXPECT_GT(frozen[i].header.stamp, frozen[i - 1].header.stamp);
    }
  }
  for (const auto& p : points.messages())
    ASSERT_TRUE(std::isfinite(p.point.x) && std::isfinite(p.point.y) && std::isfinite(p.point.z));

  // Diagnostics: ERROR naming the event.
  ASSERT_TRUE(wait_for(
      [&] {
        for (const auto& array : diagnostics.messages())
          for (const auto& status : array.status)
            if (status.level == diagnostic_msgs::DiagnosticStatus::ERROR &&
                status.message.find(event) != std::string::npos)
              return true;
        return false;
      },
      10.0))
      << "no diagnostics ERROR naming " << event;

  // ~reset clears the event (an empty string on the latched topic) and the top falls again.
  events.clear();
  EXPECT_TRUE(trigger("/falling/reset").success);
  ASSERT_TRUE(wait_for([&] { return events.size() >= 2; }, 20.0));
  const auto after_reset = events.messages();
  EXPECT_EQ(after_reset[0].data, "");
  EXPECT_EQ(after_reset[1].data, event);
}

int main(int argc, char** argv) { return node_test::run_node_tests(argc, argv, "test_node_event", 2); }
