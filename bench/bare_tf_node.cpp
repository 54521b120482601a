// The yardstick of bench/node_cpu.py (issue 20, item 10): the least a roscpp node does that
// broadcasts one body pose at 1 kHz, a 1 kHz WallTimer publishing one transform on /tf and
// nothing else (no /clock, no markers, no diagnostics). Run beside spinning_top_node on the same
// master, launched the same way, so that what the simulator adds to ROS's own cost shows.
#include <geometry_msgs/TransformStamped.h>
#include <ros/ros.h>
#include <tf2_msgs/TFMessage.h>

#include <cmath>

int main(int argc, char** argv) {
  ros::init(argc, argv, "bare_tf_node");
  ros::NodeHandle nh, private_nh("~");
  double rate = 1000.0;
  private_nh.param("rate", rate, rate);
  ros::Publisher tf = nh.advertise<tf2_msgs::TFMessage>("/tf", 100);
  long tick = 0;
  tf2_msgs::TFMessage message;
  message.transforms.resize(1);
  geometry_msgs::TransformStamped& pose = message.transforms[0];
  pose.header.frame_id = "world";
  pose.child_frame_id = "bare_top";
  const ros::WallTime start = ros::WallTime::now();
  ros::WallTimer timer = nh.createWallTimer(ros::WallDuration(1.0 / rate), [&](const ros::WallTimerEvent&) {
    ++tick;
    const double angle = 0.001 * static_cast<double>(tick);
    pose.header.stamp = ros::Time(start.sec, start.nsec) + ros::Duration(static_cast<double>(tick) / rate);
    pose.transform.rotation.z = std::sin(0.5 * angle);
    pose.transform.rotation.w = std::cos(0.5 * angle);
    tf.publish(message);
  });
  ros::spin();
  return 0;
}
