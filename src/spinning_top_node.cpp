// spinning_top_node: the ROS front end of the spinning-top simulator (see README.md, "The ROS node").
#include <ros/ros.h>

#include <csignal>

#include "spinning_top/ros/spinning_top_node.hpp"

namespace {

void on_sigint(int) {
  using spinning_top::ros_front_end::SpinningTopNode;
  SpinningTopNode::request_stop();
  if (!SpinningTopNode::started()) ros::requestShutdown();  // as roscpp's handler: ends a wait for the master too
}

}  // namespace

int main(int argc, char** argv) {
  using spinning_top::ros_front_end::SpinningTopNode;
  // Our own SIGINT handler (roscpp's would start its shutdown at once, in another thread): the
  // start stops between two steps, and a running node unregisters its topics in one call to the
  // master while ROS shuts down (under a second with 1,000 tops instead of seconds).
  ros::init(argc, argv, "spinning_top", ros::init_options::NoSigintHandler);
  std::signal(SIGINT, on_sigint);
  // Held outside the try: destroying the last NodeHandle shuts ROS (and its logging) down,
  // and the fatal message below must still be printed. Every callback of the node (the handles
  // made from these inherit the queue) goes through its own queue.
  spinning_top::ros_front_end::NodeCallbackQueue queue;
  ros::NodeHandle nh, private_nh("~");
  nh.setCallbackQueue(&queue);
  private_nh.setCallbackQueue(&queue);
  try {
    SpinningTopNode node(nh, private_nh);
    // ros::spin(), ending at SIGINT as well as at a shutdown from elsewhere (rosnode kill).
    while (ros::ok() && !SpinningTopNode::stop_requested()) node.spin_once();
    if (SpinningTopNode::stop_requested() && ros::ok())
      node.shut_down_at_sigint();
    else
      ros::shutdown();
  } catch (const spinning_top::InvalidParameter& error) {
    ROS_FATAL("spinning_top: invalid parameter ~%s (%s)", error.parameter().c_str(), error.what());
    return 1;
  } catch (const spinning_top::ros_front_end::StartupInterrupted& interrupted) {
    // SIGINT (or rosnode kill) during the start: nothing more is advertised or published.
    ROS_INFO("spinning_top: %s; exiting", interrupted.what());
    return 0;
  }
  return 0;
}
