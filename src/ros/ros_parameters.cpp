#include "spinning_top/ros/ros_parameters.hpp"

#include "spinning_top/ros/node_settings.hpp"

#include <xmlrpcpp/XmlRpcValue.h>

#include <ros/master.h>
#include <ros/param.h>
#include <ros/this_node.h>
#include <xmlrpcpp/XmlRpcClient.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <functional>

namespace spinning_top {
namespace ros_front_end {
namespace {

const char* type_name(XmlRpc::XmlRpcValue::Type type) {
  switch (type) {
    case XmlRpc::XmlRpcValue::TypeBoolean: return "a boolean";
    case XmlRpc::XmlRpcValue::TypeInt: return "an integer";
    case XmlRpc::XmlRpcValue::TypeDouble: return "a number";
    case XmlRpc::XmlRpcValue::TypeString: return "a string";
    case XmlRpc::XmlRpcValue::TypeArray: return "a list";
    case XmlRpc::XmlRpcValue::TypeStruct: return "a dictionary";
    default: return "of an unsupported type";
  }
}

/// Whether a key's documented default is a number (then the key takes numbers).
bool is_number(const char* text) {
  char* end = nullptr;
  std::strtod(text, &end);
  return end != text && *end == '\0';
}

/// For a string that reads as a number: why it is a string. YAML 1.1 (rosparam, roslaunch's
/// <rosparam>) takes 1e-8 without a dot for text, so `step: 1e-8` arrives as "1e-8".
std::string numeric_text_hint(const XmlRpc::XmlRpcValue& value) {
  if (value.getType() != XmlRpc::XmlRpcValue::TypeString) return "";
  const std::string text = static_cast<std::string>(const_cast<XmlRpc::XmlRpcValue&>(value));
  if (!is_number(text.c_str())) return "";
  std::string hint = "; '" + excerpt(text) + "' is text";
  if (text.find_first_of("eE") != std::string::npos && text.find('.') == std::string::npos)
    hint += " because YAML 1.1 (rosparam) reads an exponent without a dot as a string: write it with a dot, "
            "e.g. 1.0e-8";
  return hint;
}

using Lookup = std::function<bool(const std::string& key, XmlRpc::XmlRpcValue& value)>;

ParameterMap read_scene_parameters(const Lookup& get) {
  ParameterMap values;
  // A group of keys (initial/...) given as anything but a dictionary (`initial: 5`) would hide
  // its keys, which would then silently take their defaults.
  for (const ParameterSpec& spec : parameter_specs()) {
    const std::string key = spec.key;
    const std::size_t slash = key.find('/');
    if (slash == std::string::npos) continue;
    const std::string group = key.substr(0, slash);
    XmlRpc::XmlRpcValue value;
    if (get(group, value) && value.getType() != XmlRpc::XmlRpcValue::TypeStruct)
      throw InvalidParameter(group, std::string("is ") + type_name(value.getType()) + ", expected a dictionary of " +
                                        group + "/... keys (e.g. " + key + ")");
  }
  for (const ParameterSpec& spec : parameter_specs()) {
    XmlRpc::XmlRpcValue value;
    if (!get(spec.key, value)) continue;
    const bool is_text = !takes_number(spec);  // scene, integrator: names
    switch (value.getType()) {
      case XmlRpc::XmlRpcValue::TypeDouble:
        if (!is_text) { values[spec.key] = number_text(static_cast<double>(value)); continue; }
        break;
      case XmlRpc::XmlRpcValue::TypeInt:
        if (!is_text) { values[spec.key] = std::to_string(static_cast<int>(value)); continue; }
        break;
      case XmlRpc::XmlRpcValue::TypeString:
        // Names only: a number given as a string ("9.8") is a string, refused like any other type.
        if (is_text) { values[spec.key] = static_cast<std::string>(value); continue; }
        break;
      default:
        break;
    }
    throw InvalidParameter(spec.key, std::string("is ") + type_name(value.getType()) + ", expected " +
                                         (is_text ? "a string" : "a number") + " (" + spec.description + ")" +
                                         (is_text ? "" : numeric_text_hint(value)));
  }
  return values;
}

double number_of(const std::string& key, const XmlRpc::XmlRpcValue& given) {
  XmlRpc::XmlRpcValue& value = const_cast<XmlRpc::XmlRpcValue&>(given);
  if (value.getType() == XmlRpc::XmlRpcValue::TypeDouble) return static_cast<double>(value);
  if (value.getType() == XmlRpc::XmlRpcValue::TypeInt) return static_cast<int>(value);
  throw InvalidParameter(key, std::string("is ") + type_name(value.getType()) + ", expected a number" +
                                  numeric_text_hint(value));
}

}  // namespace

std::string number_text(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.17g", value);  // round-trips every double exactly
  return buffer;
}

bool takes_number(const ParameterSpec& spec) { return is_number(spec.default_value.c_str()); }

ParameterTree ParameterTree::fetch(const std::string& ns) {
  ParameterTree tree;
  XmlRpc::XmlRpcValue value;
  if (ros::param::get(ns, value) && value.getType() == XmlRpc::XmlRpcValue::TypeStruct) tree.root_ = value;
  return tree;
}

ParameterTree ParameterTree::fetch_members(const std::string& ns, const std::vector<std::string>& names) {
  ParameterTree tree;
  // One call to the master for all of them (XML-RPC system.multicall): a spawn reads ~30
  // members, and a call each cost ~0.2 ms. A master that does not take it gets a call each.
  XmlRpc::XmlRpcValue calls, parameters, results;
  for (std::size_t i = 0; i < names.size(); ++i) {
    XmlRpc::XmlRpcValue& call = calls[static_cast<int>(i)];
    call["methodName"] = std::string("getParam");
    call["params"][0] = ros::this_node::getName();
    call["params"][1] = ns + "/" + names[i];
  }
  parameters[0] = calls;
  XmlRpc::XmlRpcClient client(ros::master::getHost().c_str(), static_cast<int>(ros::master::getPort()), "/");
  const bool done = !names.empty() && client.execute("system.multicall", parameters, results) &&
                    !client.isFault() && results.getType() == XmlRpc::XmlRpcValue::TypeArray &&
                    results.size() == static_cast<int>(names.size());
  client.close();
  if (done) {
    for (std::size_t i = 0; i < names.size(); ++i) {
      // A call's answer is [[code, status, value]] (code 1: set), or a fault (a struct).
      XmlRpc::XmlRpcValue& wrapped = results[static_cast<int>(i)];
      if (wrapped.getType() != XmlRpc::XmlRpcValue::TypeArray || wrapped.size() != 1) continue;
      XmlRpc::XmlRpcValue& answer = wrapped[0];
      if (answer.getType() == XmlRpc::XmlRpcValue::TypeArray && answer.size() == 3 &&
          answer[0].getType() == XmlRpc::XmlRpcValue::TypeInt && static_cast<int>(answer[0]) == 1)
        tree.root_[names[i]] = answer[2];
    }
    return tree;
  }
  for (const std::string& name : names) {
    XmlRpc::XmlRpcValue value;
    if (ros::param::get(ns + "/" + name, value)) tree.root_[name] = value;
  }
  return tree;
}

bool ParameterTree::get(const std::string& key, XmlRpc::XmlRpcValue& value) const {
  // Walked by pointer: a copy of an XmlRpcValue copies its whole tree. operator[] is not const,
  // but on a member that exists it only looks it up.
  XmlRpc::XmlRpcValue* node = const_cast<XmlRpc::XmlRpcValue*>(&root_);
  std::size_t begin = 0;
  while (begin <= key.size()) {
    const std::size_t slash = std::min(key.find('/', begin), key.size());
    const std::string part = key.substr(begin, slash - begin);
    if (node->getType() != XmlRpc::XmlRpcValue::TypeStruct || !node->hasMember(part)) return false;
    node = &(*node)[part];
    begin = slash + 1;
  }
  value = *node;
  return true;
}

ParameterTree ParameterTree::sub(const std::string& key) const {
  ParameterTree tree;
  XmlRpc::XmlRpcValue value;
  if (get(key, value) && value.getType() == XmlRpc::XmlRpcValue::TypeStruct) tree.root_ = value;
  return tree;
}

ParameterMap read_scene_parameters(const ros::NodeHandle& private_nh) {
  return read_scene_parameters([&](const std::string& key, XmlRpc::XmlRpcValue& value) {
    return private_nh.getParam(key, value);
  });
}

ParameterMap read_scene_parameters(const ParameterTree& tree) {
  return read_scene_parameters([&](const std::string& key, XmlRpc::XmlRpcValue& value) { return tree.get(key, value); });
}

double read_number(const ros::NodeHandle& private_nh, const std::string& key, double default_value) {
  XmlRpc::XmlRpcValue value;
  return private_nh.getParam(key, value) ? number_of(key, value) : default_value;
}

double read_number(const ParameterTree& tree, const std::string& key, double default_value) {
  XmlRpc::XmlRpcValue value;
  return tree.get(key, value) ? number_of(key, value) : default_value;
}

std::string read_string(const ros::NodeHandle& private_nh, const std::string& key,
                        const std::string& default_value) {
  XmlRpc::XmlRpcValue value;
  if (!private_nh.getParam(key, value)) return default_value;
  if (value.getType() == XmlRpc::XmlRpcValue::TypeString) return static_cast<std::string>(value);
  throw InvalidParameter(key, std::string("is ") + type_name(value.getType()) + ", expected a string");
}

bool read_bool(const ros::NodeHandle& private_nh, const std::string& key, bool default_value) {
  XmlRpc::XmlRpcValue value;
  if (!private_nh.getParam(key, value)) return default_value;
  if (value.getType() == XmlRpc::XmlRpcValue::TypeBoolean) return static_cast<bool>(value);
  throw InvalidParameter(key, std::string("is ") + type_name(value.getType()) + ", expected true or false");
}

}  // namespace ros_front_end
}  // namespace spinning_top
