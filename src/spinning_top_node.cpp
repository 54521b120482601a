// spinning_top_node: the ROS front end of the spinning-top simulator (see README.md, "The ROS node").
#include <ros/ros.h>

#include "spinning_top/ros/spinning_top_node.hpp"

int main(int argc, char** argv) {
  ros::init(argc, argv, "spinning_top");
  // Held outside the try: destroying the last NodeHandle shuts ROS (and its logging) down,
  // and the fatal message below must still be printed.
  ros::NodeHandle nh, private_nh("~");
  try {
    spinning_top::ros_front_end::SpinningTopNode node(nh, private_nh);
    ros::spin();
  } catch (const spinning_top::InvalidParameter& error) {
    ROS_FATAL("spinning_top: invalid parameter ~%s (%s)", error.parameter().c_str(), error.what());
    return 1;
  }
  return 0;
}
