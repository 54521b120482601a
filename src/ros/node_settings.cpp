#include "spinning_top/ros/node_settings.hpp"

#include <xmlrpcpp/XmlRpcValue.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <set>

#include "spinning_top/parameters.hpp"
#include "spinning_top/ros/ros_parameters.hpp"

namespace spinning_top {
namespace ros_front_end {
namespace {

constexpr double kMaxRate = 100000.0;  // [Hz] beyond this the tick cost alone exceeds the period
// [Hz] below it a tick is more than 100 s of simulated time, and with the smallest real-time
// factor its wall period (1 / (rate x factor)) leaves ros::WallDuration's range (1e-300 Hz threw
// from the timer's set-up).
constexpr double kMinRate = 0.01;
constexpr double kMinRealTimeFactor = 1e-3;  // besides 0 (as fast as possible)
// Beyond it the timer period 1 / (rate x factor) falls below 0.1 us at 1 kHz: "as fast as
// possible" is 0, and a huge finite factor (1e300) asked for a period of 1e-303 s.
constexpr double kMaxRealTimeFactor = 1e4;

std::string format(const char* pattern, double value) {
  char buffer[160];
  std::snprintf(buffer, sizeof buffer, pattern, value);
  return buffer;
}

void require(bool condition, const std::string& key, const std::string& reason) {
  if (!condition) throw InvalidParameter(key, reason);
}

bool name_characters(const std::string& name, bool allow_slash) {
  if (name.empty() || !std::isalpha(static_cast<unsigned char>(name[0]))) return false;
  for (const char c : name)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || (allow_slash && c == '/'))) return false;
  return true;
}

/// A publication rate key: 0 (every tick) or a positive rate.
double read_publication_rate(const ros::NodeHandle& nh, const std::string& key, double value) {
  value = read_number(nh, key, value);
  require(std::isfinite(value) && value >= 0.0, key, "must be >= 0 Hz (0: every tick)");
  return value;
}

/// ~publish_clock: true, false or "auto" (also the strings "true" and "false", as a command line
/// `_publish_clock:=auto` gives text).
ClockMode read_clock_mode(const ros::NodeHandle& nh, ClockMode value) {
  XmlRpc::XmlRpcValue given;
  if (!nh.getParam("publish_clock", given)) return value;
  if (given.getType() == XmlRpc::XmlRpcValue::TypeBoolean)
    return static_cast<bool>(given) ? ClockMode::kPublish : ClockMode::kOff;
  if (given.getType() == XmlRpc::XmlRpcValue::TypeString) {
    const std::string text = static_cast<std::string>(given);
    if (text == "auto") return ClockMode::kAuto;
    if (text == "true") return ClockMode::kPublish;
    if (text == "false") return ClockMode::kOff;
    throw InvalidParameter("publish_clock", "'" + excerpt(text) + "' is not auto, true or false");
  }
  throw InvalidParameter("publish_clock", "must be auto, true or false");
}

/// A list of names (~tops, ~top_topics): a YAML list, or roscpp's command-line text
/// (`_tops:=[slow,fast]`); `example` shows the form in the refusal.
std::vector<std::string> read_name_list(const ros::NodeHandle& nh, const std::string& key, const std::string& example,
                                        bool* given = nullptr) {
  XmlRpc::XmlRpcValue value;
  std::vector<std::string> names;
  const bool found = nh.getParam(key, value);
  if (given != nullptr) *given = found;
  if (!found) return names;
  if (value.getType() == XmlRpc::XmlRpcValue::TypeString) {
    // roscpp's command line (`_tops:=[slow,fast]`) gives text, not a list: names between
    // brackets, commas and spaces.
    std::string name;
    for (const char c : static_cast<std::string>(value) + ",") {
      if (c == '[' || c == ']' || c == ',' || c == ' ') {
        if (!name.empty()) names.push_back(name);
        name.clear();
      } else {
        name += c;
      }
    }
  } else {
    require(value.getType() == XmlRpc::XmlRpcValue::TypeArray, key, "must be a list of names, e.g. " + example);
    for (int i = 0; i < value.size(); ++i) {
      require(value[i].getType() == XmlRpc::XmlRpcValue::TypeString, key, "must be a list of names, e.g. " + example);
      names.push_back(static_cast<std::string>(value[i]));
    }
  }
  return names;
}

std::vector<std::string> read_top_names(const ros::NodeHandle& nh) {
  const std::vector<std::string> names = read_name_list(nh, "tops", "[slow, fast]");
  std::set<std::string> seen;
  for (const std::string& name : names) {
    require_top_name("tops", name);
    require(seen.insert(name).second, "tops", "'" + name + "' is listed twice");  // valid: short
  }
  return names;
}

/// ~top_topics (~spawn_topics): names of per_top_topic_names(), each once, kept in the order a
/// top advertises them (so that the master lists them alike whatever order the list gave).
std::vector<std::string> read_top_topics(const ros::NodeHandle& nh, const std::string& key,
                                         const std::vector<std::string>& fallback) {
  bool given = false;
  const std::vector<std::string> names = read_name_list(nh, key, "[state, event_stamped]", &given);
  const std::vector<std::string>& all = per_top_topic_names();
  if (!given) return fallback;
  std::string known;
  for (const std::string& topic : all) known += (known.empty() ? "" : ", ") + topic;
  std::set<std::string> seen;
  for (const std::string& name : names) {
    require(std::find(all.begin(), all.end(), name) != all.end(), key,
            "'" + excerpt(name) + "' is not a top's topic (" + known + ")");
    require(seen.insert(name).second, key, "'" + name + "' is listed twice");  // valid: short
  }
  std::vector<std::string> ordered;
  for (const std::string& topic : all)
    if (seen.count(topic) != 0) ordered.push_back(topic);
  return ordered;
}

}  // namespace

const std::vector<std::string>& per_top_topic_names() {
  static const std::vector<std::string> names = {"contact_point", "normal_force", "twist", "state",
                                                 "markers", "event", "event_stamped"};
  return names;
}

const std::vector<std::string>& node_setting_keys() {
  static const std::vector<std::string> keys = {
      "rate", "real_time_factor", "max_lag", "tick_budget", "publish_clock", "clock_rate", "tf_rate", "states_rate",
      "start_paused", "wait_for_subscriber", "world_frame", "frame_prefix", "body_frame", "contact_frame",
      "marker_rate", "trace_length",
      "trace_resolution", "force_scale", "energy_drift_warning", "energy_drift_error", "quaternion_norm_error",
      "constraint_error", "late_tick_warning", "real_time_factor_warning", "tops", "top_topics",
      "top_reset_services", "spawn_topics", "spawn_reset_services", "reset_reads_parameters",
      "scene_file", "overrides_file"};
  return keys;
}

std::string frame_prefix_of(const std::string& private_namespace) {
  const std::size_t last = private_namespace.rfind('/');
  std::string ns = last == std::string::npos ? "" : private_namespace.substr(0, last);
  while (!ns.empty() && ns.front() == '/') ns.erase(0, 1);
  return ns;
}

std::string top_frame(const NodeSettings& settings, const std::string& top_name, bool body) {
  const bool explicit_frame = body ? settings.body_frame_explicit : settings.contact_frame_explicit;
  std::string frame = top_name.empty() ? "" : top_name + "/";
  frame += body ? settings.body_frame : settings.contact_frame;
  if (explicit_frame || settings.frame_prefix.empty()) return frame;
  return settings.frame_prefix + "/" + frame;
}

void validate_pacing(double rate, double real_time_factor) {
  require(std::isfinite(rate) && rate >= kMinRate && rate <= kMaxRate, "rate",
          format("must lie in [%g, ", kMinRate) + format("%g] Hz", kMaxRate) + format(", got %.6g", rate));
  require(std::isfinite(real_time_factor) &&
              (real_time_factor == 0.0 || (real_time_factor >= kMinRealTimeFactor && real_time_factor <= kMaxRealTimeFactor)),
          "real_time_factor",
          format("must be 0 (as fast as possible) or lie in [%g, ", kMinRealTimeFactor) +
              format("%g]", kMaxRealTimeFactor) + format(", got %.6g", real_time_factor));
}

void require_frame(const std::string& key, const std::string& frame) {
  require(!frame.empty(), key, "must not be empty");
  require(frame[0] != '/', key, "'" + excerpt(frame) + "' must not start with '/' (tf2 frame ids have no leading slash)");
  // ROS names' characters (a letter first, then letters, digits, '_' and '/' between names): what
  // tf2, URDF and rviz handle everywhere; a space or a '-' breaks tools that parse frame lists.
  require(name_characters(frame, true) && frame.back() != '/' && frame.find("//") == std::string::npos, key,
          "'" + excerpt(frame) + "' is not a valid frame id: a letter, then letters, digits, '_' and '/' "
          "between names (REP-105 names such as world, top)");
}

void require_top_name(const std::string& key, const std::string& name) {
  require(name.size() <= kMaxTopNameLength, key,
          "'" + excerpt(name) + "' is not a valid top name: at most " + std::to_string(kMaxTopNameLength) +
              " characters (it prefixes the top's frames, topics and services)");
  require(name_characters(name, false), key,
          "'" + excerpt(name) + "' is not a valid top name: a letter, then letters, digits and '_' (it prefixes the "
          "top's frames, topics and services)");
}

std::string excerpt(const std::string& text, std::size_t limit) {
  std::string shown = text.substr(0, limit);
  for (char& c : shown)
    if (std::iscntrl(static_cast<unsigned char>(c))) c = '?';
  if (text.size() > limit) shown += "... (" + std::to_string(text.size()) + " characters)";
  return shown;
}

NodeSettings read_node_settings(const ros::NodeHandle& nh) {
  NodeSettings s;
  s.rate = read_number(nh, "rate", s.rate);
  s.real_time_factor = read_number(nh, "real_time_factor", s.real_time_factor);
  validate_pacing(s.rate, s.real_time_factor);
  s.max_lag = read_number(nh, "max_lag", s.max_lag);
  require(std::isfinite(s.max_lag) && s.max_lag >= 0.0 && s.max_lag <= 3600.0, "max_lag",
          "must lie in [0, 3600] wall s (how far behind the wall clock missed ticks are still taken)");
  s.tick_budget = read_number(nh, "tick_budget", s.tick_budget);
  require(std::isfinite(s.tick_budget) && s.tick_budget >= 1e-4 && s.tick_budget <= 1.0, "tick_budget",
          "must lie in [1e-4, 1] s (the wall time one callback may integrate before the node serves "
          "services, parameter updates and SIGINT again)");
  s.publish_clock = read_clock_mode(nh, s.publish_clock);
  s.clock_rate = read_publication_rate(nh, "clock_rate", s.clock_rate);
  s.tf_rate = read_publication_rate(nh, "tf_rate", s.tf_rate);
  s.states_rate = read_publication_rate(nh, "states_rate", s.states_rate);
  s.start_paused = read_bool(nh, "start_paused", s.start_paused);
  s.wait_for_subscriber = read_bool(nh, "wait_for_subscriber", s.wait_for_subscriber);
  s.world_frame = read_string(nh, "world_frame", s.world_frame);
  s.frame_prefix = read_string(nh, "frame_prefix", frame_prefix_of(nh.getNamespace()));
  s.body_frame_explicit = nh.hasParam("body_frame");
  s.contact_frame_explicit = nh.hasParam("contact_frame");
  s.body_frame = read_string(nh, "body_frame", s.body_frame);
  s.contact_frame = read_string(nh, "contact_frame", s.contact_frame);
  require_frame("world_frame", s.world_frame);
  if (!s.frame_prefix.empty()) require_frame("frame_prefix", s.frame_prefix);  // "": no prefix
  require_frame("body_frame", s.body_frame);
  require_frame("contact_frame", s.contact_frame);
  const std::string body = top_frame(s, "", true), contact = top_frame(s, "", false);
  require(body != s.world_frame && contact != s.world_frame && contact != body, "body_frame",
          "world_frame, body_frame and contact_frame must differ (now " + excerpt(s.world_frame) + ", " +
              excerpt(body) + ", " + excerpt(contact) + ")");
  s.marker_rate = read_number(nh, "marker_rate", s.marker_rate);
  require(std::isfinite(s.marker_rate) && s.marker_rate > 0.0, "marker_rate", "must be > 0 Hz");
  const double trace_length = read_number(nh, "trace_length", s.trace_length);
  require(trace_length >= 0.0 && trace_length <= 1e6 && trace_length == std::floor(trace_length), "trace_length",
          "must be a whole number of points in [0, 1e6]");
  s.trace_length = static_cast<int>(trace_length);
  s.trace_resolution = read_number(nh, "trace_resolution", s.trace_resolution);
  require(std::isfinite(s.trace_resolution) && s.trace_resolution >= 0.0, "trace_resolution", "must be >= 0 m");
  s.force_scale = read_number(nh, "force_scale", s.force_scale);
  require(std::isfinite(s.force_scale) && s.force_scale > 0.0, "force_scale", "must be > 0 m/N");
  s.energy_drift_warning = read_number(nh, "energy_drift_warning", s.energy_drift_warning);
  s.energy_drift_error = read_number(nh, "energy_drift_error", s.energy_drift_error);
  require(s.energy_drift_warning > 0.0 && std::isfinite(s.energy_drift_warning), "energy_drift_warning", "must be > 0");
  require(s.energy_drift_error >= s.energy_drift_warning && std::isfinite(s.energy_drift_error), "energy_drift_error",
          "must be finite and >= energy_drift_warning");
  s.quaternion_norm_error = read_number(nh, "quaternion_norm_error", s.quaternion_norm_error);
  require(s.quaternion_norm_error > 0.0, "quaternion_norm_error", "must be > 0");
  s.constraint_error = read_number(nh, "constraint_error", s.constraint_error);
  require(s.constraint_error > 0.0, "constraint_error", "must be > 0 m");
  s.late_tick_warning = read_number(nh, "late_tick_warning", s.late_tick_warning);
  require(s.late_tick_warning >= 0.0 && s.late_tick_warning <= 1.0, "late_tick_warning",
          "must lie in [0, 1] (a fraction of the ticks in a 1 s window)");
  s.real_time_factor_warning = read_number(nh, "real_time_factor_warning", s.real_time_factor_warning);
  require(s.real_time_factor_warning >= 0.0 && s.real_time_factor_warning <= 1.0, "real_time_factor_warning",
          "must lie in [0, 1] (a fraction of the requested real-time factor)");
  s.tops = read_top_names(nh);
  s.top_topics = read_top_topics(nh, "top_topics", per_top_topic_names());
  s.top_reset_services = read_bool(nh, "top_reset_services", s.top_reset_services);
  s.spawn_topics = read_top_topics(nh, "spawn_topics", {});
  s.spawn_reset_services = read_bool(nh, "spawn_reset_services", s.spawn_reset_services);
  const auto has_topic = [&s](const char* topic) {
    return std::find(s.top_topics.begin(), s.top_topics.end(), topic) != s.top_topics.end();
  };
  require(!s.wait_for_subscriber || has_topic("contact_point") || has_topic("state"), "wait_for_subscriber",
          "waits for a subscriber of ~contact_point or ~state: ~top_topics must list one of them");
  return s;
}

}  // namespace ros_front_end
}  // namespace spinning_top
