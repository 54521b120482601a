// The yardstick of bench/node_scale.py --bare (issue 19, item 5): the least a roscpp node does for
// a ~spawn of spinning_top_node, and nothing of the simulation. Each call advertises the top's
// topics (~spawn_topics, the node's message types, queues and latches; none by default) and its
// ~<name>/reset service (~spawn_reset_services, false by default), and sets its
// ~<name>/robot_description: the calls to the master
// that a spawn makes. No simulation, no /tf_static, no diagnostics, no log line. What the node's
// spawn costs beyond this, as the count grows, is the node's own.
#include <geometry_msgs/PointStamped.h>
#include <geometry_msgs/TwistStamped.h>
#include <geometry_msgs/WrenchStamped.h>
#include <ros/ros.h>
#include <std_msgs/String.h>
#include <std_srvs/Trigger.h>
#include <visualization_msgs/MarkerArray.h>

#include <string>
#include <vector>

#include "spinning_top/Spawn.h"
#include "spinning_top/TopEvent.h"
#include "spinning_top/TopState.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "bare_spawner");
  ros::NodeHandle private_nh("~");
  std::vector<std::string> top_topics;
  // roscpp's command line sets `_spawn_topics:=[state,event]` as a string; a list from a file or
  // rosparam is a list.
  std::string top_topics_text;
  if (private_nh.getParam("spawn_topics", top_topics_text)) {
    top_topics.clear();
    std::string name;
    for (const char c : top_topics_text + ",") {
      if (c == ',') {
        if (!name.empty()) top_topics.push_back(name);
        name.clear();
      } else if (c != '[' && c != ']' && c != ' ') {
        name += c;
      }
    }
  } else {
    private_nh.param("spawn_topics", top_topics, top_topics);
  }
  bool top_reset_services = false;
  private_nh.param("spawn_reset_services", top_reset_services, top_reset_services);
  std::vector<ros::Publisher> publishers;
  std::vector<ros::ServiceServer> services;
  const boost::function<bool(std_srvs::Trigger::Request&, std_srvs::Trigger::Response&)> reset =
      [](std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response) {
        response.success = true;
        return true;
      };
  const boost::function<bool(spinning_top::Spawn::Request&, spinning_top::Spawn::Response&)> spawn =
      [&](spinning_top::Spawn::Request& request, spinning_top::Spawn::Response& response) {
        ros::NodeHandle top(private_nh, request.name);
        for (const std::string& topic : top_topics) {
          if (topic == "contact_point")
            publishers.push_back(top.advertise<geometry_msgs::PointStamped>(topic, 1000));
          else if (topic == "normal_force")
            publishers.push_back(top.advertise<geometry_msgs::WrenchStamped>(topic, 1000));
          else if (topic == "twist")
            publishers.push_back(top.advertise<geometry_msgs::TwistStamped>(topic, 1000));
          else if (topic == "state")
            publishers.push_back(top.advertise<spinning_top::TopState>(topic, 1000));
          else if (topic == "markers")
            publishers.push_back(top.advertise<visualization_msgs::MarkerArray>(topic, 10));
          else if (topic == "event")
            publishers.push_back(top.advertise<std_msgs::String>(topic, 100, /*latch=*/true));
          else if (topic == "event_stamped")
            publishers.push_back(top.advertise<spinning_top::TopEvent>(topic, 100, /*latch=*/true));
        }
        if (top_reset_services)
          services.push_back(top.advertiseService("reset", reset));
        top.setParam("robot_description", "<?xml version=\"1.0\"?>\n<robot name=\"spinning_top\"><link name=\"" +
                                              request.name + "/body\"/></robot>\n");
        response.success = true;
        response.message = "registered " + request.name;
        return true;
      };
  ros::ServiceServer server = private_nh.advertiseService("spawn", spawn);
  ros::spin();
  return 0;
}
