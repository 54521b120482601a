// spinning_top_node: the ROS front end of the spinning-top simulator (see doc/node.md).
#include <ros/ros.h>

#include "spinning_top/ros/spinning_top_node.hpp"

int main(int argc, char** argv) {
  ros::init(argc, argv, "spinning_top");
  try {
    spinning_top::ros_front_end::SpinningTopNode node(ros::NodeHandle(), ros::NodeHandle("~"));
    ros::spin();
  } catch (const spinning_top::InvalidParameter& error) {
    ROS_FATAL("spinning_top: invalid parameter ~%s (%s)", error.parameter().c_str(), error.what());
    return 1;
  }
  return 0;
}
