// rostest (test/node_bad_parameter.test): the node binary started with one bad private
// parameter must exit non-zero, name the parameter in its ROS_FATAL message, and publish
// nothing. A valid start is the control: it must still be running when we stop it.
#include <geometry_msgs/PointStamped.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <string>

#include "node_test_helpers.hpp"

using node_test::Recorder;

namespace {

using node_test::Outcome;

/// Runs the node as `name` with the given private-parameter arguments, for at most
/// `seconds` (then `timeout` ends it with exit code 124).
Outcome run_node(const std::string& name, const std::string& arguments, int seconds = 20) {
  return node_test::run_command("timeout " + std::to_string(seconds) + " " SPINNING_TOP_NODE_EXECUTABLE " __name:=" +
                                name + " " + arguments);
}

void expect_refused(const std::string& name, const std::string& arguments, const std::string& parameter,
                    const std::string& reason = "") {
  ros::NodeHandle nh;
  Recorder<geometry_msgs::PointStamped> points(nh, "/" + name + "/contact_point");
  const Outcome outcome = run_node(name, arguments);
  EXPECT_NE(outcome.exit_code, 0) << arguments;
  EXPECT_NE(outcome.exit_code, 124) << arguments << ": still running after 20 s";
  EXPECT_NE(outcome.output.find("FATAL"), std::string::npos) << outcome.output;
  EXPECT_NE(outcome.output.find("invalid parameter ~" + parameter + " "), std::string::npos)
      << "expected ~" << parameter << " named in:\n" << outcome.output;
  EXPECT_NE(outcome.output.find(reason), std::string::npos) << "expected '" << reason << "' in:\n" << outcome.output;
  ros::WallDuration(0.2).sleep();
  EXPECT_EQ(points.size(), 0u) << arguments << ": published before exiting";
}

}  // namespace

TEST(NodeBadParameter, NegativeMass) { expect_refused("bad_mass", "_mass:=-1.0", "mass"); }
TEST(NodeBadParameter, MassThatIsNotANumber) { expect_refused("bad_mass_text", "_mass:=heavy", "mass"); }
TEST(NodeBadParameter, AxialInertiaAboveTwiceTransverse) {
  expect_refused("bad_inertia", "_inertia_axial:=1e-4 _inertia_transverse:=4e-5", "inertia_axial");
}
TEST(NodeBadParameter, FrictionInTheFixedTipScene) { expect_refused("bad_friction", "_friction:=0.1", "friction"); }
TEST(NodeBadParameter, TiltWithTheAxisBelowTheFloor) { expect_refused("bad_tilt", "_initial/tilt:=2.0", "initial/tilt"); }
// Several tops (~tops): a name listed twice, a top's position that is not a number, a top's own
// key named with its top.
TEST(NodeBadParameter, TopListedTwice) { expect_refused("bad_tops", "_tops:=[a,a]", "tops", "listed twice"); }
TEST(NodeBadParameter, TopPositionThatIsNotANumber) { expect_refused("bad_place", "_tops:=[a] _a/x:=far", "a/x"); }
TEST(NodeBadParameter, TopKeyNamesItsTop) { expect_refused("bad_top_key", "_tops:=[a] _a/mass:=-1.0", "a/mass"); }
TEST(NodeBadParameter, TiltOfTheWrongType) { expect_refused("bad_tilt_type", "_initial/tilt:=true", "initial/tilt"); }
TEST(NodeBadParameter, UnknownScene) { expect_refused("bad_scene", "_scene:=ice", "scene"); }
TEST(NodeBadParameter, UnknownIntegrator) { expect_refused("bad_integrator", "_integrator:=no_such_integrator", "integrator"); }
TEST(NodeBadParameter, ZeroRate) { expect_refused("bad_rate", "_rate:=0", "rate"); }
TEST(NodeBadParameter, NegativeRealTimeFactor) {
  expect_refused("bad_rtf", "_real_time_factor:=-1", "real_time_factor");
}
TEST(NodeBadParameter, FrameWithLeadingSlash) { expect_refused("bad_frame", "_world_frame:=/world", "world_frame"); }
// A spin the simulator cannot resolve: the node used to advertise, then hang (issue 10).
TEST(NodeBadParameter, SpinBeyondWhatTheSimulatorResolves) { expect_refused("bad_spin", "_initial/spin:=1e12", "initial/spin"); }
TEST(NodeBadParameter, FrameWithASpace) { expect_refused("bad_frame_space", "'_world_frame:=my world'", "world_frame"); }
// A scalar where the initial state's dictionary belongs would hide every initial/ key.
TEST(NodeBadParameter, InitialThatIsNotADictionary) { expect_refused("bad_initial", "_initial:=5", "initial"); }
// A number given as a string is a string: refused like any other wrong type (README).
TEST(NodeBadParameter, GravityGivenAsAString) {
  ros::param::set("/bad_gravity_text/gravity", std::string("9.8"));
  expect_refused("bad_gravity_text", "", "gravity");
  ros::param::del("/bad_gravity_text/gravity");
}
// YAML 1.1 (`rosparam load`, `rosparam set`, a launch file's <rosparam>) reads an exponent
// without a dot (`step: 1e-5`) as text: refused, and the message says why and how to write it.
TEST(NodeBadParameter, ExponentWithoutADotIsTextAndTheMessageSaysSo) {
  ros::param::set("/bad_step_text/step", std::string("1e-5"));
  const Outcome outcome = run_node("bad_step_text", "_integrator:=rk4");
  ros::param::del("/bad_step_text/step");
  EXPECT_NE(outcome.exit_code, 0);
  EXPECT_NE(outcome.output.find("invalid parameter ~step "), std::string::npos) << outcome.output;
  EXPECT_NE(outcome.output.find("write it with a dot, e.g. 1.0e-8"), std::string::npos) << outcome.output;
}
// The real-time factor is bounded: 1e300 asked the timer for a period of 1e-303 s.
TEST(NodeBadParameter, HugeRealTimeFactor) {
  expect_refused("bad_rtf_huge", "_real_time_factor:=1.0e+300", "real_time_factor");
}
// The work budget of one callback must leave the node responsive.
TEST(NodeBadParameter, TickBudgetOutsideItsRange) { expect_refused("bad_budget", "_tick_budget:=5.0", "tick_budget"); }

// The control: the same binary with valid parameters runs (and publishes) until stopped.
TEST(NodeBadParameter, ValidParametersKeepTheNodeRunning) {
  ros::NodeHandle nh;
  Recorder<geometry_msgs::PointStamped> points(nh, "/good/contact_point");
  const Outcome outcome = run_node("good", "_rate:=100 _publish_clock:=false _body_frame:=good_top "
                                   "_contact_frame:=good_contact _mas:=0.2", 3);
  EXPECT_EQ(outcome.exit_code, 124) << outcome.output;
  EXPECT_GT(points.size(), 0u);
  // An unknown key is a warning, not fatal, with what it probably meant.
  EXPECT_NE(outcome.output.find("ignoring unknown parameter /good/mas (did you mean ~mass?)"), std::string::npos)
      << outcome.output;
}

int main(int argc, char** argv) { return node_test::run_node_tests(argc, argv, "test_node_bad_parameter", 1); }
