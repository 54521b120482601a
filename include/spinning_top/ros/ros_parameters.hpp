// Reading the core's configuration keys (config.hpp, parameter_specs()) from a ROS node's
// private namespace, so that `rosparam load config/<scene>.yaml ~` and the batch
// simulator's --config file describe the same top.
#pragma once

#include <ros/node_handle.h>

#include <string>

#include "spinning_top/config.hpp"

namespace spinning_top {
namespace ros_front_end {

/// Every key of parameter_specs() present in `private_nh` as text for parse_scene_config:
/// doubles and ints as numbers, strings as they are. Any other XmlRpc type (bool, list,
/// struct) throws InvalidParameter naming the key. Absent keys are left out, so that the
/// documented defaults apply.
ParameterMap read_scene_parameters(const ros::NodeHandle& private_nh);

/// A number-valued private parameter with a default; a value that is neither double nor
/// int throws InvalidParameter naming the key.
double read_number(const ros::NodeHandle& private_nh, const std::string& key, double default_value);

/// A string-valued private parameter with a default; a non-string throws InvalidParameter.
std::string read_string(const ros::NodeHandle& private_nh, const std::string& key,
                        const std::string& default_value);

/// A bool-valued private parameter with a default; a non-bool throws InvalidParameter.
bool read_bool(const ros::NodeHandle& private_nh, const std::string& key, bool default_value);

}  // namespace ros_front_end
}  // namespace spinning_top
