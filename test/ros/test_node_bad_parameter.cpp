// rostest (test/node_bad_parameter.test): the node binary started with one bad private
// parameter must exit non-zero, name the parameter in its ROS_FATAL message, and publish
// nothing. A valid start is the control: it must still be running when we stop it.
#include <geometry_msgs/PointStamped.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <stdlib.h>
#include <unistd.h>

#include <fstream>
#include <sstream>
#include <string>

#include "node_test_helpers.hpp"

using node_test::Outcome;
using node_test::Recorder;

namespace {

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
// ~publish_clock takes auto, true or false (issue 20): anything else is refused by name.
TEST(NodeBadParameter, PublishClockNotAutoOrBool) {
  expect_refused("bad_clock", "_publish_clock:=maybe", "publish_clock");
}
TEST(NodeBadParameter, TiltWithTheAxisBelowTheFloor) { expect_refused("bad_tilt", "_initial/tilt:=2.0", "initial/tilt"); }
// Several tops (~tops): a name listed twice, a top's position that is not a number, a top's own
// key named with its top.
TEST(NodeBadParameter, TopListedTwice) { expect_refused("bad_tops", "_tops:=[a,a]", "tops", "listed twice"); }
TEST(NodeBadParameter, TopPositionThatIsNotANumber) { expect_refused("bad_place", "_tops:=[a] _a/x:=far", "a/x"); }
TEST(NodeBadParameter, TopKeyNamesItsTop) { expect_refused("bad_top_key", "_tops:=[a] _a/mass:=-1.0", "a/mass"); }
// ~top_topics names a top's own topics, each once; ~wait_for_subscriber needs one it waits for.
TEST(NodeBadParameter, TopTopicThatIsNotATopsTopic) {
  expect_refused("bad_top_topics", "_top_topics:=[state,clock]", "top_topics", "'clock' is not a top's topic");
}
TEST(NodeBadParameter, TopTopicListedTwice) {
  expect_refused("bad_top_topics_twice", "_top_topics:=[state,state]", "top_topics", "listed twice");
}
// ~spawn_topics and ~spawn_reset_services are read and refused as ~top_topics is, at the start
// (not at the first spawn).
TEST(NodeBadParameter, SpawnTopicThatIsNotATopsTopic) {
  expect_refused("bad_spawn_topics", "_spawn_topics:=[states]", "spawn_topics", "'states' is not a top's topic");
}
TEST(NodeBadParameter, SpawnResetServicesThatIsNotABool) {
  expect_refused("bad_spawn_reset", "_spawn_reset_services:=2", "spawn_reset_services");
}
TEST(NodeBadParameter, WaitingForATopicNoTopHas) {
  expect_refused("bad_wait", "_top_topics:=[event] _wait_for_subscriber:=true", "wait_for_subscriber");
}
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

// Issue 19, one file, two physics: the node reads a scene file itself (~scene_file, as the launch
// file gives it), with the reader `simulate --config` uses, instead of getting it through
// `rosparam load` (YAML 1.1, where `gravity: 010` is 8 while simulate's YAML 1.2 reads 10).
namespace {

/// A scene file in /tmp: a sleeping top (upright, spinning: R = m g at t = 0) with `extra` lines.
std::string scene_file(const std::string& extra) {
  char path[] = "/tmp/spinning_top_scene_XXXXXX.yaml";
  const int fd = mkstemps(path, 5);
  EXPECT_GE(fd, 0);
  close(fd);
  std::ofstream(path) << "scene: fixed_tip\nmass: 0.1\ninertia_transverse: 4.0e-5\ninertia_axial: 6.0e-5\n"
                         "tip_distance: 0.02\ninitial:\n  tilt: 0.0\n  spin: 150.0\n"
                      << extra;
  return path;
}

/// simulate's floor force at t = 0 for a scene file (NAN if it refuses the file).
double simulated_weight(const std::string& file) {
  const Outcome outcome = node_test::run_command(SIMULATE_EXECUTABLE " --config " + file + " --duration 0.01");
  if (outcome.exit_code != 0) return NAN;
  std::istringstream lines(outcome.output);
  std::string line;
  while (std::getline(lines, line))
    if (line.rfind("0,", 0) == 0) {  // the row at t = 0; normal_force is the 12th column
      std::istringstream cells(line);
      std::string cell;
      for (int i = 0; i < 12; ++i) std::getline(cells, cell, ',');
      return std::stod(cell);
    }
  return NAN;
}

}  // namespace

TEST(NodeBadParameter, SceneFileThatCannotBeRead) {
  expect_refused("bad_scene_file", "_scene_file:=/nonexistent/scene.yaml", "scene_file");
}

// The same file in both: the node's gravity is simulate's (R / m at the sleeping start), or both
// refuse the file naming gravity (a reader that refuses the forms YAML 1.1 and 1.2 read apart).
TEST(NodeBadParameter, TheNodeReadsASceneFileAsSimulateDoes) {
  const std::string file = scene_file("gravity: 010\n");
  const double weight = simulated_weight(file);
  ros::param::del("/same_file");
  const Outcome outcome = run_node("same_file", "_scene_file:=" + file + " _rate:=100 _publish_clock:=false "
                                   "_body_frame:=same_file_top _contact_frame:=same_file_contact", 2);
  if (std::isnan(weight)) {
    EXPECT_NE(outcome.exit_code, 0);
    EXPECT_NE(outcome.exit_code, 124) << "simulate refuses the file; the node ran with it:\n" << outcome.output;
    EXPECT_NE(outcome.output.find("gravity"), std::string::npos) << outcome.output;
  } else {
    EXPECT_EQ(outcome.exit_code, 124) << outcome.output;
    double gravity = 0.0;
    EXPECT_TRUE(ros::param::get("/same_file/gravity", gravity)) << "the node writes the values in force back";
    EXPECT_NEAR(gravity, weight / 0.1, 1e-12) << "simulate reads the file's gravity as " << weight / 0.1;
  }
  unlink(file.c_str());
  ros::param::del("/same_file");
}

// The node writes the files' values back to ~<key>; a later start with another file (the
// namespace not cleared, as with rosrun) takes the new file's values, not its own write-back,
// while a private parameter given explicitly still overrides the file.
TEST(NodeBadParameter, ASceneFileWinsOverTheNodesOwnWriteBackAndExplicitKeysOverrideIt) {
  const std::string first = scene_file("gravity: 5.0\n"), second = scene_file("gravity: 7.0\n");
  const std::string common = " _rate:=100 _publish_clock:=false _body_frame:=rewritten_top _contact_frame:=rewritten_contact";
  ros::param::del("/rewritten");
  EXPECT_EQ(run_node("rewritten", "_scene_file:=" + first + common, 2).exit_code, 124);
  double gravity = 0.0, spin = 0.0;
  EXPECT_TRUE(ros::param::get("/rewritten/gravity", gravity));
  EXPECT_EQ(gravity, 5.0);
  EXPECT_EQ(run_node("rewritten", "_scene_file:=" + second + " _initial/spin:=90.0" + common, 2).exit_code, 124);
  EXPECT_TRUE(ros::param::get("/rewritten/gravity", gravity));
  EXPECT_EQ(gravity, 7.0) << "the first run's write-back overrode the second file";
  EXPECT_TRUE(ros::param::get("/rewritten/initial/spin", spin));
  EXPECT_EQ(spin, 90.0) << "an explicit private parameter overrides the file";
  EXPECT_TRUE(ros::param::get("/rewritten/scene_file_values/initial/spin", spin));
  EXPECT_EQ(spin, 150.0) << "what the file gives";
  unlink(first.c_str());
  unlink(second.c_str());
  ros::param::del("/rewritten");
}

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
