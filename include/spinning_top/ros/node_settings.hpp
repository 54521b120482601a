// The node's own private parameters (not scene keys): pacing, frames, publication rates,
// diagnostics thresholds. One table of keys with their defaults and checks (node_settings.cpp).
#pragma once

#include <ros/node_handle.h>

#include <string>
#include <vector>

#include "spinning_top/defaults.hpp"

namespace spinning_top {
namespace ros_front_end {

/// ~publish_clock: who gives the node its time.
enum class ClockMode {
  kAuto,     ///< publish /clock unless another node does; then follow that /clock
  kPublish,  ///< always publish /clock (true)
  kOff,      ///< never publish /clock; pace by the wall clock (false)
};

struct NodeSettings {
  double rate = defaults::kRate;  ///< ticks per simulated second [Hz]
  double real_time_factor = defaults::kRealTimeFactor;  ///< simulated s per wall s; 0 = as fast as possible
  /// [wall s] missed ticks are taken late (catch-up) up to this lag; beyond it they are given
  /// up (reported), so that an overloaded machine does not fall ever further behind
  double max_lag = 1.0;
  ClockMode publish_clock = ClockMode::kAuto;  ///< ~publish_clock: auto (default), true or false
  double clock_rate = 0.0;          ///< /clock messages per simulated second [Hz]; 0 = every tick
  double tf_rate = 0.0;             ///< /tf messages per simulated second [Hz]; 0 = every tick
  double states_rate = 0.0;         ///< ~states messages per simulated second [Hz]; 0 = every tick
  bool start_paused = false;
  /// Hold the first tick until the first top's ~contact_point and ~state (and /clock, when
  /// published) have a subscriber, e.g. `rosbag record`, so that a recording starts at time 0
  bool wait_for_subscriber = false;
  std::string world_frame = "world";
  /// The node's namespace without its leading '/' ("r1"; "" in the root namespace), or
  /// ~frame_prefix: it prefixes the default frames (r1/top, r1/contact, r1/<top>/top), so that
  /// nodes in two namespaces broadcast different frames under the shared world (REP-105)
  std::string frame_prefix;
  /// ~body_frame, ~contact_frame as given (the defaults "top", "contact" when not set): an
  /// explicit one is used as it is, without the prefix
  std::string body_frame = "top";
  std::string contact_frame = "contact";
  bool body_frame_explicit = false, contact_frame_explicit = false;
  /// [s] wall time one timer callback (or ~step) may integrate; a tick that needs more goes on
  /// in the next callback, and diagnostics report it (ERROR)
  double tick_budget = 0.05;
  double marker_rate = 30.0;        ///< markers per simulated second [Hz]
  int trace_length = 2000;          ///< points kept in the tip's trace
  double trace_resolution = 1e-4;   ///< [m] the trace gets a point when the tip moved this far
  double force_scale = 0.05;        ///< [m/N] arrow length per newton
  double energy_drift_warning = 1e-6;  ///< relative |E + W - E0| / |E0| for WARN
  double energy_drift_error = 1e-3;    ///< ... and for ERROR
  double quaternion_norm_error = 1e-9; ///< | |q| - 1 | for ERROR
  double constraint_error = 1e-9;      ///< [m] contact constraint residual for ERROR
  /// Pacing diagnostics over each 1 s window: WARN when more than this fraction of the ticks
  /// were taken late (catch-up), or when the achieved real-time factor is below
  /// real_time_factor_warning x the requested one
  double late_tick_warning = 0.1;
  double real_time_factor_warning = 0.9;
  /// Names of the tops to start with, each reading its keys from ~<name>/ over the node's own
  /// (~tops: [slow, fast]); empty: one top from the node's own keys, with the unprefixed names
  std::vector<std::string> tops;
  /// ~top_topics: the topics every top advertises (under ~ or ~<name>/), in advertisement order;
  /// default all of per_top_topic_names(). Each is one registration with the master per top, and
  /// roscpp's and rosmaster's bookkeeping of a node's registrations grows with their count: with
  /// hundreds of tops, fewer per top keep a spawn's cost flat and the shutdown short.
  std::vector<std::string> top_topics;
  /// ~top_reset_services: each named top advertises ~<name>/reset (one more registration per top,
  /// and one more call to the master at shutdown: roscpp unregisters services one by one)
  bool top_reset_services = true;
  /// ~spawn_topics and ~spawn_reset_services: the same for a top added by ~spawn; default none.
  /// rosmaster keeps a node's registrations in lists it searches linearly, so each registration
  /// costs more as the node has more: with none, the 1,000th spawn costs what the first did and
  /// the exit stays short. A spawned top is on ~states, ~events, tf, diagnostics and ~get_state.
  std::vector<std::string> spawn_topics;
  bool spawn_reset_services = false;
};

/// The per-top topics in the order a top advertises them: contact_point, normal_force, twist,
/// state, markers, event, event_stamped (the default of ~top_topics).
const std::vector<std::string>& per_top_topic_names();

/// The body frame (body true) or the contact frame of the top `top_name` ("" for the node's own
/// top): [<frame_prefix>/][<top_name>/]top by default; an explicit ~body_frame (~contact_frame)
/// as it is, [<top_name>/]<body_frame>.
std::string top_frame(const NodeSettings& settings, const std::string& top_name, bool body);

/// The node's namespace of a private namespace ("/r1/spinning_top" -> "r1", "/spinning_top" -> "").
std::string frame_prefix_of(const std::string& private_namespace);

/// Every private key the node itself reads (besides the scene keys of parameter_specs()).
const std::vector<std::string>& node_setting_keys();

/// Reads and validates NodeSettings; throws InvalidParameter naming the key.
NodeSettings read_node_settings(const ros::NodeHandle& private_nh);

/// The pacing keys, checked alike at start and by dynamic_reconfigure: throws InvalidParameter.
void validate_pacing(double rate, double real_time_factor);

/// A frame id tf2, URDF and rviz all handle: throws InvalidParameter naming `key`.
void require_frame(const std::string& key, const std::string& frame);

/// The longest top name: it prefixes the top's frames, topics, services and parameters.
constexpr std::size_t kMaxTopNameLength = 64;

/// A top's name: one ROS name segment (a letter, then letters, digits, '_'), at most
/// kMaxTopNameLength characters; throws InvalidParameter naming `key`.
void require_top_name(const std::string& key, const std::string& name);

/// `text` as a message may quote it: one line (control characters shown as '?'), at most
/// `limit` characters, then "... (N characters)".
std::string excerpt(const std::string& text, std::size_t limit = 40);

}  // namespace ros_front_end
}  // namespace spinning_top
