// `rosrun spinning_top simulate` and `rosrun spinning_top spinning_top_node`, exactly as the
// README documents them, from the environment `make run_tests` gives (build/devel sourced).
// Debian's rosrun drops every path under <package>/build/; this checks the package's devel link.
#include <geometry_msgs/PointStamped.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <string>

#include "node_test_helpers.hpp"

namespace {

using node_test::Outcome;

using node_test::run_command;

TEST(Rosrun, BatchSimulator) {
  const Outcome help = run_command("rosrun spinning_top simulate --help");
  EXPECT_EQ(help.exit_code, 0) << help.output;
  EXPECT_NE(help.output.find("--config"), std::string::npos) << help.output;
  // A run: 0.01 s of the default scene, a comment, a header and rows of CSV.
  const Outcome csv = run_command("rosrun spinning_top simulate --config \"$(rospack find spinning_top)/config/fixed_tip.yaml\" --duration 0.01 --output-rate 1000");
  EXPECT_EQ(csv.exit_code, 0) << csv.output;
  EXPECT_NE(csv.output.find("t,qw,qx,qy,qz"), std::string::npos) << csv.output;
}

TEST(Rosrun, Node) {
  ros::NodeHandle nh;
  node_test::Recorder<geometry_msgs::PointStamped> points(nh, "/via_rosrun/contact_point");
  // The node runs until `timeout` ends it (SIGTERM, exit 124); it must have published by then.
  const Outcome node = run_command("timeout 6 rosrun spinning_top spinning_top_node __name:=via_rosrun _publish_clock:=false");
  EXPECT_EQ(node.exit_code, 124) << "the node exited by itself:\n" << node.output;
  EXPECT_EQ(node.output.find("Couldn't find executable"), std::string::npos) << node.output;
  EXPECT_GT(points.size(), 100u) << node.output;
}

}  // namespace

int main(int argc, char** argv) { return node_test::run_node_tests(argc, argv, "test_rosrun", 1); }
