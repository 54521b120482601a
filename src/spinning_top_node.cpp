// spinning_top_node: the ROS front end of the spinning-top simulator (see README.md, "The ROS node").
#include <ros/ros.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <thread>

#include "spinning_top/ros/spinning_top_node.hpp"

namespace {

void on_sigint(int) { spinning_top::ros_front_end::SpinningTopNode::request_stop(); }

/// During the start, SIGINT is taken at the start's next step, which unregisters what it
/// advertised in one call to the master. A start waiting in a call to a master that is gone
/// never gets there: then, 0.3 s after SIGINT, ROS shuts down as roscpp's own handler would
/// (which ends the wait). The destructor ends the watch (the start is over).
class StartupWatchdog {
 public:
  StartupWatchdog()
      : thread_([this] {
          using spinning_top::ros_front_end::SpinningTopNode;
          const auto tick = std::chrono::milliseconds(5);
          while (!done_ && !SpinningTopNode::stop_requested()) std::this_thread::sleep_for(tick);
          for (int i = 0; i < 60 && !done_ && !SpinningTopNode::stopping_the_start(); ++i)
            std::this_thread::sleep_for(tick);
          if (!done_ && !SpinningTopNode::stopping_the_start()) ros::requestShutdown();
        }) {}
  ~StartupWatchdog() { stop(); }
  void stop() {
    done_ = true;
    if (thread_.joinable()) thread_.join();
  }

 private:
  std::atomic<bool> done_{false};
  std::thread thread_;
};

}  // namespace

int main(int argc, char** argv) {
  using spinning_top::ros_front_end::SpinningTopNode;
  // Our own SIGINT handler (roscpp's would start its shutdown at once, in another thread): the
  // start stops between two steps, and a running node unregisters its topics in one call to the
  // master while ROS shuts down (under a second with 1,000 tops instead of seconds).
  ros::init(argc, argv, "spinning_top", ros::init_options::NoSigintHandler);
  std::signal(SIGINT, on_sigint);
  StartupWatchdog watchdog;
  // Held outside the try: destroying the last NodeHandle shuts ROS (and its logging) down,
  // and the fatal message below must still be printed. Every callback of the node (the handles
  // made from these inherit the queue) goes through its own queue.
  spinning_top::ros_front_end::NodeCallbackQueue queue;
  ros::NodeHandle nh, private_nh("~");
  nh.setCallbackQueue(&queue);
  private_nh.setCallbackQueue(&queue);
  try {
    SpinningTopNode node(nh, private_nh);
    watchdog.stop();
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
