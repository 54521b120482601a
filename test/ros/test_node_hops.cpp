// rostest (test/node_hops.test): the node follows the top off the floor and back (doc/spec/HYBRID.md).
// "hopper" lifts off, lands and hops on: every transition reaches ~event and ~event_stamped with
// its time, in order; diagnostics stay OK; in flight the floor force is zero and the tip (state,
// contact frame) is above the floor. "faller" flies at once and its rim reaches the floor in
// flight: the terminal event, a diagnostics ERROR, and from then on the top at rest (zero twist,
// zero force, no force arrow). Everything asserted is simulated time and physics, not wall time.
#include <diagnostic_msgs/DiagnosticArray.h>
#include <geometry_msgs/TwistStamped.h>
#include <geometry_msgs/WrenchStamped.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <std_msgs/String.h>
#include <tf2_msgs/TFMessage.h>
#include <visualization_msgs/MarkerArray.h>

#include <cmath>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "node_test_helpers.hpp"
#include "spinning_top/TopEvent.h"
#include "spinning_top/TopState.h"

using node_test::Recorder;
using node_test::trigger;
using node_test::wait_for;

namespace {

// The core's times for these launches (`simulate --config config/frictionless.yaml --set
// initial/tilt=0.8 --set initial/precession_rate=60`, and =80 with initial/spin=20): the node runs
// the same core on the same keys, and its ticks do not change the located times.
constexpr double kHopperFirstLiftOff = 0.0093554170714874804;
constexpr double kHopperFirstLanding = 0.092399519925093349;
constexpr double kFallerFall = 0.010305916974365987;

/// What one top publishes, recorded from before the paused node resumes.
struct TopRecording {
  TopRecording(ros::NodeHandle& nh, const std::string& top)
      : events(nh, "/spinning_top/" + top + "/event_stamped", 100000),
        event_names(nh, "/spinning_top/" + top + "/event", 100000),
        states(nh, "/spinning_top/" + top + "/state", 100000),
        forces(nh, "/spinning_top/" + top + "/normal_force", 100000),
        twists(nh, "/spinning_top/" + top + "/twist", 100000),
        markers(nh, "/spinning_top/" + top + "/markers", 100000) {}
  bool connected() const {
    return events.publishers() > 0 && event_names.publishers() > 0 && states.publishers() > 0 &&
           forces.publishers() > 0 && twists.publishers() > 0 && markers.publishers() > 0;
  }
  /// The top's simulated time in its last ~state (-1 before the first).
  double time() const {
    const auto s = states.messages();
    return s.empty() ? -1.0 : s.back().time;
  }
  Recorder<spinning_top::TopEvent> events;
  Recorder<std_msgs::String> event_names;
  Recorder<spinning_top::TopState> states;
  Recorder<geometry_msgs::WrenchStamped> forces;
  Recorder<geometry_msgs::TwistStamped> twists;
  Recorder<visualization_msgs::MarkerArray> markers;
};

struct Recording {
  explicit Recording(ros::NodeHandle& nh)
      : hopper(nh, "hopper"), faller(nh, "faller"), tf(nh, "/tf", 100000), diagnostics(nh, "/diagnostics", 1000) {}
  TopRecording hopper, faller;
  Recorder<tf2_msgs::TFMessage> tf;
  Recorder<diagnostic_msgs::DiagnosticArray> diagnostics;
};

/// The recording of the whole run: subscribed first, then the paused node resumes (once).
Recording& recording() {
  static std::unique_ptr<Recording> recording;
  if (!recording) {
    ros::NodeHandle nh;
    recording = std::make_unique<Recording>(nh);
    EXPECT_TRUE(wait_for([&] { return recording->hopper.connected() && recording->faller.connected(); }, 30.0))
        << "the node's topics never connected";
    EXPECT_TRUE(trigger("/spinning_top/resume").success);
  }
  return *recording;
}

/// Waits (up to 120 s of wall time on a loaded machine) until `top` has simulated `time` seconds.
void wait_until(const TopRecording& top, double time) {
  ASSERT_TRUE(wait_for([&] { return top.time() >= time; }, 120.0)) << "simulated only to " << top.time() << " s";
}

std::vector<std::string> names_of(const std::vector<spinning_top::TopEvent>& events) {
  std::vector<std::string> names;
  for (const auto& e : events) names.push_back(e.event);
  return names;
}

bool is_zero(const geometry_msgs::Vector3& v) { return v.x == 0.0 && v.y == 0.0 && v.z == 0.0; }

}  // namespace

// Every transition on ~event_stamped, in time order, with the top's time and its stamp, and the
// same names on ~event (std_msgs/String, for scripts).
TEST(Hops, EveryTransitionIsPublishedInOrderWithItsTime) {
  Recording& r = recording();
  wait_until(r.hopper, 0.5);
  const auto events = r.hopper.events.messages();
  ASSERT_GE(events.size(), 10u);
  EXPECT_EQ(events[0].event, "lift_off");
  EXPECT_NEAR(events[0].time, kHopperFirstLiftOff, 1e-12);
  EXPECT_EQ(events[1].event, "landing");
  EXPECT_NEAR(events[1].time, kHopperFirstLanding, 1e-12);
  int lift_offs = 0, landings = 0;
  for (size_t i = 0; i < events.size(); ++i) {
    const auto& e = events[i];
    EXPECT_EQ(e.name, "hopper");
    EXPECT_FALSE(e.terminal) << i;
    EXPECT_EQ(e.header.frame_id, "world");
    // On the frictionless floor the flights and the contacts alternate; a landing followed by a
    // lift-off at once gives two events at the same time.
    EXPECT_EQ(e.event, i % 2 == 0 ? "lift_off" : "landing") << i;
    EXPECT_EQ(e.phase, e.event == "lift_off" ? "flight" : "contact") << i;
    lift_offs += e.event == "lift_off";
    landings += e.event == "landing";
    // Both happen on the floor; the stamp is the instant itself (sim time, the top started at 0).
    EXPECT_EQ(e.contact_point.z, 0.0) << i;
    EXPECT_NEAR(e.header.stamp.toSec(), e.time, 2e-9) << i;
    if (i > 0) {
      EXPECT_GE(e.time, events[i - 1].time) << i;
      EXPECT_GE(e.header.stamp, events[i - 1].header.stamp) << i;
      if (e.event == "landing") {
        EXPECT_GT(e.time, events[i - 1].time) << "a flight of no time at " << i;
      }
    }
  }
  EXPECT_GE(lift_offs, 5);
  EXPECT_GE(landings, 5);
  // ~event: the same names in the same order (both subscribed before the first tick).
  const auto texts = r.hopper.event_names.messages();
  const std::vector<std::string> stamped = names_of(events);
  ASSERT_GE(texts.size(), 10u);
  for (size_t i = 0; i < std::min(texts.size(), stamped.size()); ++i) EXPECT_EQ(texts[i].data, stamped[i]) << i;
}

// Lift-offs, landings and take-offs are the motion: the top's own diagnostics stay OK through them.
TEST(Hops, DiagnosticsStayOkThroughHops) {
  Recording& r = recording();
  wait_until(r.hopper, 0.5);
  // Statuses come at 1 Hz of wall time: wait for a few that have counted hops.
  auto hopping_statuses = [&] {
    std::vector<diagnostic_msgs::DiagnosticStatus> found;
    for (const auto& array : r.diagnostics.messages())
      for (const auto& status : array.status) {
        if (status.name != "spinning_top: hopper") continue;
        for (const auto& kv : status.values)
          if (kv.key == "lift-offs" && std::stol(kv.value) > 0) found.push_back(status);
      }
    return found;
  };
  ASSERT_TRUE(wait_for([&] { return hopping_statuses().size() >= 3; }, 60.0)) << "no diagnostics of the hops";
  for (const auto& array : r.diagnostics.messages())
    for (const auto& status : array.status)
      if (status.name == "spinning_top: hopper") {
        EXPECT_EQ(status.level, diagnostic_msgs::DiagnosticStatus::OK) << status.message;
      }
}

// In flight: R = 0 and no horizontal force (~state, ~normal_force), the tip above the floor in
// ~state and in the contact frame on /tf, G where the body frame is. On the floor: the tip at z = 0.
TEST(Hops, InFlightNoFloorForceAndTheTipAboveTheFloor) {
  Recording& r = recording();
  wait_until(r.hopper, 0.5);
  std::map<ros::Time, spinning_top::TopState> flying;
  int on_floor = 0;
  for (const auto& s : r.hopper.states.messages()) {
    EXPECT_TRUE(s.phase == "contact" || s.phase == "flight") << s.phase;  // no skim without friction
    EXPECT_EQ(s.event, "");
    if (s.phase == "flight") {
      EXPECT_EQ(s.normal_force, 0.0) << s.time;
      EXPECT_TRUE(is_zero(s.contact_force)) << s.time;
      EXPECT_GT(s.contact_point.z, 0.0) << s.time;
      flying[s.header.stamp] = s;
    } else {
      EXPECT_EQ(s.contact_point.z, 0.0) << s.time;
      EXPECT_GE(s.normal_force, 0.0) << s.time;
      ++on_floor;
    }
  }
  EXPECT_GT(flying.size(), 50u);  // the first flight alone lasts 83 ticks
  EXPECT_GT(on_floor, 50);
  size_t forces_in_flight = 0;
  for (const auto& w : r.hopper.forces.messages())
    if (flying.count(w.header.stamp)) {
      EXPECT_TRUE(is_zero(w.wrench.force)) << w.header.stamp;
      ++forces_in_flight;
    }
  EXPECT_GT(forces_in_flight, 50u);
  size_t frames_in_flight = 0;
  for (const auto& message : r.tf.messages())
    for (const auto& t : message.transforms) {
      const auto it = flying.find(t.header.stamp);
      if (it == flying.end()) continue;
      if (t.child_frame_id == "hopper/contact") {
        EXPECT_EQ(t.transform.translation.z, it->second.contact_point.z);
        EXPECT_EQ(t.transform.translation.x, it->second.contact_point.x);
        ++frames_in_flight;
      } else if (t.child_frame_id == "hopper/top") {
        EXPECT_EQ(t.transform.translation.z, it->second.center_of_mass.z);
      }
    }
  EXPECT_GT(frames_in_flight, 50u);
}

// The faller: lift_off at the release, then fallen (terminal) when its rim reaches the floor in
// flight; diagnostics ERROR naming it; from then on the final pose at rest.
TEST(Hops, AFallenTopIsShownAtRest) {
  Recording& r = recording();
  ASSERT_TRUE(wait_for([&] { return r.faller.events.size() >= 2; }, 120.0));
  // Its time stops at the fall; the stamps (the world's time) go on.
  ASSERT_TRUE(wait_for(
      [&] {
        const auto states = r.faller.states.messages();
        return !states.empty() && states.back().header.stamp.toSec() > kFallerFall + 0.1;
      },
      120.0));
  const auto events = r.faller.events.messages();
  ASSERT_EQ(names_of(events), (std::vector<std::string>{"lift_off", "fallen"}));
  EXPECT_EQ(events[0].time, 0.0);
  EXPECT_FALSE(events[0].terminal);
  EXPECT_TRUE(events[1].terminal);
  EXPECT_NEAR(events[1].time, kFallerFall, 1e-12);
  EXPECT_GT(events[1].contact_point.z, 0.0) << "the rim touched first: the tip is still in the air";
  const ros::Time fall = events[1].header.stamp;

  size_t twists = 0, forces = 0, states = 0, arrows = 0;
  for (const auto& t : r.faller.twists.messages())
    if (t.header.stamp > fall) {
      EXPECT_TRUE(is_zero(t.twist.linear) && is_zero(t.twist.angular)) << t.header.stamp;
      ++twists;
    }
  for (const auto& w : r.faller.forces.messages())
    if (w.header.stamp > fall) {
      EXPECT_TRUE(is_zero(w.wrench.force)) << w.header.stamp;
      ++forces;
    }
  for (const auto& s : r.faller.states.messages())
    if (s.header.stamp > fall) {
      EXPECT_EQ(s.event, "fallen");
      EXPECT_EQ(s.time, events[1].time);  // the run ended there
      EXPECT_EQ(s.spin, 0.0);
      EXPECT_TRUE(is_zero(s.angular_velocity) && is_zero(s.center_of_mass_velocity));
      EXPECT_EQ(s.normal_force, 0.0);
      EXPECT_TRUE(is_zero(s.contact_force));
      EXPECT_EQ(s.contact_point.z, events[1].contact_point.z);  // the final pose
      ++states;
    }
  for (const auto& array : r.faller.markers.messages())
    for (const auto& m : array.markers)
      if (m.ns == "force" && m.header.stamp > fall) {
        EXPECT_EQ(m.action, visualization_msgs::Marker::DELETE);
        ++arrows;
      }
  EXPECT_GT(twists, 50u);
  EXPECT_GT(forces, 50u);
  EXPECT_GT(states, 50u);
  EXPECT_GT(arrows, 3u);

  ASSERT_TRUE(wait_for(
      [&] {
        for (const auto& array : r.diagnostics.messages())
          for (const auto& status : array.status)
            if (status.name == "spinning_top: faller" && status.level == diagnostic_msgs::DiagnosticStatus::ERROR &&
                status.message.find("fallen") != std::string::npos)
              return true;
        return false;
      },
      30.0))
      << "no diagnostics ERROR naming fallen";
}

int main(int argc, char** argv) { return node_test::run_node_tests(argc, argv, "test_node_hops", 2); }
