// Reading the core's configuration keys (config.hpp, parameter_specs()) from a ROS node's
// private namespace, so that `rosparam load config/<scene>.yaml ~` and the batch
// simulator's --config file describe the same top.
#pragma once

#include <ros/node_handle.h>
#include <xmlrpcpp/XmlRpcValue.h>

#include <string>
#include <vector>

#include "spinning_top/config.hpp"

namespace spinning_top {
namespace ros_front_end {

/// A namespace of parameters fetched in one call (ros::param::get of the namespace: a tree of
/// XmlRpc structs), read without a call to the master per key: at start the node reads every
/// top's keys from one fetch of its private namespace.
class ParameterTree {
 public:
  ParameterTree() = default;
  /// The namespace `ns` (e.g. private_nh.getNamespace()); empty if it holds nothing.
  static ParameterTree fetch(const std::string& ns);
  /// Only the members `names` of the namespace `ns` (one call to the master for all): for a
  /// namespace that also holds much else (every top's URDF).
  static ParameterTree fetch_members(const std::string& ns, const std::vector<std::string>& names);
  /// The value at `key` ("initial/tilt"), false if absent.
  bool get(const std::string& key, XmlRpc::XmlRpcValue& value) const;
  /// The subtree at `key` (e.g. a top's name); empty if absent or not a dictionary.
  ParameterTree sub(const std::string& key) const;

 private:
  XmlRpc::XmlRpcValue root_;
};

/// Every key of parameter_specs() present in `private_nh` as text for parse_scene_config:
/// doubles and ints as numbers, strings as they are. Any other XmlRpc type (bool, list,
/// struct) throws InvalidParameter naming the key. Absent keys are left out, so that the
/// documented defaults apply.
ParameterMap read_scene_parameters(const ros::NodeHandle& private_nh);
ParameterMap read_scene_parameters(const ParameterTree& tree);

/// A number as read_scene_parameters() gives it (text that parses back to the same double).
std::string number_text(double value);

/// Whether a scene key takes a number (its documented default is one), else a name.
bool takes_number(const ParameterSpec& spec);

/// A number-valued private parameter with a default; a value that is neither double nor
/// int throws InvalidParameter naming the key.
double read_number(const ros::NodeHandle& private_nh, const std::string& key, double default_value);
double read_number(const ParameterTree& tree, const std::string& key, double default_value);

/// A string-valued private parameter with a default; a non-string throws InvalidParameter.
std::string read_string(const ros::NodeHandle& private_nh, const std::string& key,
                        const std::string& default_value);

/// A bool-valued private parameter with a default; a non-bool throws InvalidParameter.
bool read_bool(const ros::NodeHandle& private_nh, const std::string& key, bool default_value);

}  // namespace ros_front_end
}  // namespace spinning_top
