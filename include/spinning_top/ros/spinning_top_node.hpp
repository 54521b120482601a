// The ROS 1 front end's world (turtlesim's turtle_frame.cpp): what exists once — the tick
// clock and its pacing, /clock, tf, the services that start, stop, spawn and kill tops,
// dynamic_reconfigure and the pacing diagnostics. Each top (top_instance.hpp) has its own
// simulator, frames, topics and markers. All physics comes from the core (simulator.hpp).
#pragma once

#include <diagnostic_updater/diagnostic_updater.h>
#include <dynamic_reconfigure/server.h>
#include <ros/ros.h>
#include <std_srvs/Trigger.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_broadcaster.h>

#include <memory>
#include <string>
#include <vector>

#include "spinning_top/Kill.h"
#include "spinning_top/SetState.h"
#include "spinning_top/Spawn.h"
#include "spinning_top/SpinningTopConfig.h"
#include "spinning_top/ros/node_settings.hpp"
#include "spinning_top/ros/top_instance.hpp"
#include "spinning_top/tick_clock.hpp"

namespace spinning_top {
namespace ros_front_end {

class SpinningTopNode {
 public:
  /// Reads and validates every parameter before advertising anything: throws
  /// InvalidParameter (naming the key) so that main can exit with nothing published.
  SpinningTopNode(ros::NodeHandle nh, ros::NodeHandle private_nh);

 private:
  /// The configurations of the tops the parameters describe (the node's own, or ~tops).
  std::vector<std::pair<std::string, SceneConfig>> read_tops() const;
  /// A named top's tip position at the start, ~<name>/x and ~<name>/y [m] (throws
  /// InvalidParameter naming <name>/x or <name>/y); the origin for the node's own top.
  Eigen::Vector2d read_tip_position(const std::string& name) const;
  void add_top(std::unique_ptr<TopInstance> top);
  TopInstance* find_top(const std::string& name);

  void on_timer(const ros::WallTimerEvent& event);
  void on_diagnostics_timer(const ros::WallTimerEvent&);
  /// One tick: every top advances exactly 1/rate of simulated time, then everything is
  /// published with one stamp. The integration stops at `deadline`: then the tick is unfinished
  /// (false, nothing published) and the next call goes on with it, so the published samples do
  /// not depend on where it stopped.
  bool tick(ros::WallTime deadline);
  void publish(const ros::Time& stamp);
  void send_static_transforms();
  void restart_timer();
  void report(const std::string& status);
  /// A top's stamps for its events: stamp_origin_ + world time (as the ticks', read when used).
  TopInstance::StampOf stamp_of() const {
    return [this](double world_time) { return stamp_origin_ + ros::Duration(world_time); };
  }
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);
  void reconfigure(SpinningTopConfig& config, uint32_t level);

  bool on_reset(std_srvs::Trigger::Request& request, std_srvs::Trigger::Response& response);
  bool on_reload(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response);
  bool on_pause(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response);
  bool on_resume(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response);
  bool on_step(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response);
  bool on_spawn(Spawn::Request& request, Spawn::Response& response);
  bool on_kill(Kill::Request& request, Kill::Response& response);
  bool on_set_state(SetState::Request& request, SetState::Response& response);

  ros::NodeHandle nh_, private_nh_;
  NodeSettings settings_;
  TickClock clock_;
  std::vector<std::unique_ptr<TopInstance>> tops_;
  std::vector<ros::ServiceServer> top_reset_services_;  // ~<name>/reset, one per named top

  // Stamps are stamp_origin_ + simulated time: the world's time never goes back (a reset
  // restarts the tops' times, not the world's), so stamps never repeat or go back.
  ros::Time stamp_origin_;
  ros::Time last_stamp_;
  bool paused_ = false;
  bool waiting_for_subscriber_ = false;  // ~wait_for_subscriber: no tick yet, nobody listening yet
  bool tick_unfinished_ = false;  // the current tick ran out of its budget; the next call goes on
  long ticks_per_clock_ = 1, ticks_per_tf_ = 1, ticks_per_marker_ = 1;

  // Pacing and cost, reported in diagnostics (per 1 s window and in total).
  long late_ticks_ = 0, late_ticks_at_window_start_ = 0;        // taken after their slot (catch-up)
  long given_up_ticks_ = 0, given_up_ticks_at_window_start_ = 0;  // beyond ~max_lag
  long budget_exhaustions_ = 0, budget_exhaustions_at_window_start_ = 0;
  double sim_time_in_window_ = 0.0;  // [s] simulated
  long ticks_in_window_ = 0;
  double tick_cost_sum_ = 0.0, tick_cost_max_ = 0.0;  // [s] wall
  ros::WallTime window_wall_start_;
  double last_lag_ = 0.0;  // [wall s] behind the wall clock after the last callback

  ros::Publisher clock_publisher_, status_publisher_;
  std::unique_ptr<tf2_ros::TransformBroadcaster> tf_broadcaster_;
  std::unique_ptr<tf2_ros::StaticTransformBroadcaster> static_broadcaster_;
  bool static_sent_ = false;  // /tf_static has been published (then it is kept up to date)
  ros::ServiceServer reset_service_, reload_service_, pause_service_, resume_service_, step_service_,
      spawn_service_, kill_service_, set_state_service_;
  ros::WallTimer timer_, diagnostics_timer_;
  std::unique_ptr<diagnostic_updater::Updater> diagnostics_;
  std::unique_ptr<dynamic_reconfigure::Server<SpinningTopConfig>> reconfigure_server_;
  SpinningTopConfig applied_config_;
  bool reconfigure_initialized_ = false;
};

}  // namespace ros_front_end
}  // namespace spinning_top
