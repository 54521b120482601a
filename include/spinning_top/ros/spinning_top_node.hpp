// The ROS 1 front end: steps the core's Simulator at a fixed rate and publishes what a ROS
// user watches (tf2, contact point, floor force, markers, /clock, diagnostics). All physics
// comes from the core (simulator.hpp); this class only paces, stamps and converts.
#pragma once

#include <diagnostic_updater/diagnostic_updater.h>
#include <dynamic_reconfigure/server.h>
#include <ros/ros.h>
#include <std_srvs/Trigger.h>
#include <tf2_ros/transform_broadcaster.h>

#include <deque>
#include <memory>
#include <string>

#include "spinning_top/SpinningTopConfig.h"
#include "spinning_top/simulator.hpp"

namespace spinning_top {
namespace ros_front_end {

/// The node's own settings (private parameters that are not scene keys).
struct NodeSettings {
  double rate = 1000.0;             ///< ticks per simulated second [Hz]
  double real_time_factor = 1.0;    ///< simulated s per wall s; 0 = as fast as possible
  bool publish_clock = true;        ///< publish /clock (for use_sim_time users)
  bool start_paused = false;
  std::string world_frame = "world";
  std::string body_frame = "top";
  std::string contact_frame = "contact";
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
};

/// Reads and validates NodeSettings; throws InvalidParameter naming the key.
NodeSettings read_node_settings(const ros::NodeHandle& private_nh);

class SpinningTopNode {
 public:
  /// Reads and validates every parameter before advertising anything: throws
  /// InvalidParameter (naming the key) so that main can exit with nothing published.
  SpinningTopNode(ros::NodeHandle nh, ros::NodeHandle private_nh);

 private:
  void on_timer(const ros::WallTimerEvent& event);
  void on_diagnostics_timer(const ros::WallTimerEvent&);
  /// Advances exactly 1/rate of simulated time and publishes; the stamp moves on even
  /// after an event (the frozen pose is republished with fresh stamps). The integration stops
  /// at `deadline`: then the tick is unfinished (false, nothing published) and the next call
  /// goes on with it, so the published samples do not depend on where it stopped.
  bool tick(ros::WallTime deadline);
  /// The core's budget for a wall-time deadline.
  static WorkBudget budget_until(ros::WallTime deadline);
  void publish(const Snapshot& snapshot, const ros::Time& stamp);
  void publish_markers(const Snapshot& snapshot, const ros::Time& stamp);
  void handle_event(Event event);
  void restart_timer();
  void rebaseline_energy();
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);
  void reconfigure(SpinningTopConfig& config, uint32_t level);

  bool on_reset(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response);
  bool on_pause(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response);
  bool on_resume(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response);
  bool on_step(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response);

  ros::NodeHandle nh_, private_nh_;
  NodeSettings settings_;
  std::unique_ptr<Simulator> simulator_;

  // Simulated time: tick n after the anchor is at anchor_time_ + n / rate (no accumulated
  // rounding); stamps are stamp_origin_ + simulated time, and the origin moves forward on
  // reset so that stamps never repeat or go back.
  double anchor_time_ = 0.0;
  long ticks_since_anchor_ = 0;
  double target_time_ = 0.0;
  ros::Time stamp_origin_;
  ros::Time last_stamp_;
  bool paused_ = false;
  long ticks_per_marker_ = 1;
  long tick_count_ = 0;
  bool tick_unfinished_ = false;  // the current tick ran out of its budget; the next call goes on

  // Energy balance E + W - E0 (W: work against friction), rebaselined on reset and on
  // live parameter changes (a new g changes E by m (g' - g) z_G).
  double energy_baseline_ = 0.0;
  double dissipated_at_baseline_ = 0.0;

  Event reported_event_ = Event::kNone;
  double event_time_ = 0.0;

  // Pacing and cost, reported in diagnostics.
  long overruns_ = 0;
  long overruns_at_window_start_ = 0;
  long budget_exhaustions_ = 0;  // callbacks that ended with the tick unfinished
  long budget_exhaustions_at_window_start_ = 0;
  double sim_time_in_window_ = 0.0;  // [s] simulated
  long ticks_in_window_ = 0;
  double tick_cost_sum_ = 0.0, tick_cost_max_ = 0.0;  // [s] wall
  ros::WallTime window_wall_start_;

  std::deque<Vector3> trace_;

  ros::Publisher clock_publisher_, contact_point_publisher_, normal_force_publisher_,
      marker_publisher_, event_publisher_;
  // Built after validation: their constructors advertise.
  std::unique_ptr<tf2_ros::TransformBroadcaster> tf_broadcaster_;
  ros::ServiceServer reset_service_, pause_service_, resume_service_, step_service_;
  ros::WallTimer timer_, diagnostics_timer_;
  std::unique_ptr<diagnostic_updater::Updater> diagnostics_;
  std::unique_ptr<dynamic_reconfigure::Server<SpinningTopConfig>> reconfigure_server_;
  SpinningTopConfig applied_config_;
  bool reconfigure_initialized_ = false;
};

}  // namespace ros_front_end
}  // namespace spinning_top
