// The ROS 1 front end's world (turtlesim's turtle_frame.cpp): what exists once — the tick
// clock and its pacing, /clock, tf, the services that start, stop, spawn and kill tops,
// dynamic_reconfigure and the pacing diagnostics. Each top (top_instance.hpp) has its own
// simulator, frames, topics and markers. All physics comes from the core (simulator.hpp).
#pragma once

#include <diagnostic_updater/diagnostic_updater.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>
#include <std_srvs/Trigger.h>

#include <atomic>
#include <condition_variable>
#include <csignal>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "spinning_top/GetState.h"
#include "spinning_top/Kill.h"
#include "spinning_top/SetState.h"
#include "spinning_top/Spawn.h"
#include "spinning_top/SpinningTopConfig.h"
#include "spinning_top/ros/node_settings.hpp"
#include "spinning_top/ros/reconfigure_server.hpp"
#include "spinning_top/ros/ros_parameters.hpp"
#include "spinning_top/ros/top_instance.hpp"
#include "spinning_top/tick_clock.hpp"

namespace spinning_top {
namespace ros_front_end {

/// Thrown by the constructor when ROS shuts down (SIGINT, rosnode kill) before the start is
/// complete: main exits cleanly, nothing more is advertised or published.
class StartupInterrupted : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The node's callback queue (main gives it to the node handles): it can tell whether callbacks
/// other than the running one wait, which CallbackQueue::isEmpty() cannot (it counts the running
/// one), so that a timer callback behind the wall clock lets a waiting service call go first.
class NodeCallbackQueue : public ros::CallbackQueue {
 public:
  bool others_waiting() {
    boost::mutex::scoped_lock lock(mutex_);
    return !callbacks_.empty();
  }
};

/// The tick timer: run by main's loop (SpinningTopNode::spin_once), which waits on the callback
/// queue until the next tick is due, rather than by roscpp's timer thread, which wakes up and
/// hands each tick to the queue's thread: one thread wake-up per tick instead of two, the bulk
/// of the node's CPU at 1 kHz (bench/node_cpu.py). The interface of the ros::WallTimer it
/// replaces, and its rule for late calls (ros::TimerManager::updateNext).
class TickTimer {
 public:
  bool isValid() const { return valid_; }
  void setPeriod(ros::WallDuration period) {
    period_ = period;
    valid_ = true;
  }
  void start() {
    if (running_) return;
    running_ = true;
    next_ = ros::WallTime::now() + period_;
  }
  void stop() { running_ = false; }
  bool running() const { return running_; }
  /// Wall time until the next call is due (0 if due), at most `longest`.
  ros::WallDuration until_due(ros::WallDuration longest) const {
    if (!running_) return longest;
    const ros::WallDuration left = next_ - ros::WallTime::now();
    return left < ros::WallDuration(0) ? ros::WallDuration(0) : (left < longest ? left : longest);
  }
  /// Whether a call is due now; if so, the next one is scheduled (a period after the one due,
  /// or now if the loop fell more than a period behind).
  bool take_due() {
    const ros::WallTime now = ros::WallTime::now();
    if (!running_ || now < next_) return false;
    next_ += period_;
    if (next_ + period_ < now) next_ = now;
    return true;
  }

 private:
  bool valid_ = false, running_ = false;
  ros::WallDuration period_;
  ros::WallTime next_;
};

/// The node's own scene keys (those its tops inherit) and where they came from.
struct NodeKeys {
  ParameterMap keys;        ///< the keys in force: the files' (defaults included), then explicit ~<key>
  ParameterMap from_files;  ///< every key as ~scene_file and ~overrides_file give it, defaults included
  bool files = false;       ///< ~scene_file or ~overrides_file is set
};

class SpinningTopNode {
 public:
  /// Reads and validates every parameter before advertising anything: throws
  /// InvalidParameter (naming the key) so that main can exit with nothing published, or
  /// StartupInterrupted when ROS shuts down during the start.
  SpinningTopNode(ros::NodeHandle nh, ros::NodeHandle private_nh);
  /// Stops the thread that asks the master who publishes /clock (~publish_clock auto).
  ~SpinningTopNode();
  SpinningTopNode(const SpinningTopNode&) = delete;
  SpinningTopNode& operator=(const SpinningTopNode&) = delete;

  /// SIGINT (main's handler; async-signal-safe: a lock-free atomic, also read by main's
  /// watchdog thread): the start stops at its next step, the spin at its next callback.
  static void request_stop() noexcept { stop_requested_ = 1; }
  static bool stop_requested() noexcept { return stop_requested_ != 0; }
  /// Whether a start interrupted by SIGINT is unregistering what it advertised (in one call to
  /// the master, as shut_down_at_sigint() does): main's watchdog then leaves ROS alone.
  static bool stopping_the_start() noexcept { return stopping_the_start_ != 0; }

  /// One turn of main's loop: serves the callback queue until the next tick is due (at most
  /// 0.1 s), then takes the ticks due (see TickTimer).
  void spin_once();

  /// At SIGINT, instead of ros::shutdown() alone (which it calls): the node's topics (but
  /// /rosout) unregistered from the master in one call (XML-RPC system.multicall) and dropped, so
  /// that roscpp's shutdown does not unregister them one call each (~0.3 ms each: 2.5 s for the
  /// 7,000 topics of 1,000 tops); roscpp's unregistration of the services and its own shutdown
  /// run beside that call. A master that does not take the call gets one call per topic.
  void shut_down_at_sigint();

 private:
  /// The advertised topics but /rosout: the node's own first, then each top's, in the order of
  /// their registration.
  std::vector<std::string> topics_in_registration_order() const;
  /// Unregisters `topics` of this node from the master: whether the master confirmed each.
  static bool unregister_publishers(const std::vector<std::string>& topics);
  /// The node's own scene keys: ~scene_file and ~overrides_file read by the core's scene-file
  /// reader (as `simulate --config` reads them), then the private parameters ~<key> that are
  /// not the node's own write-back of the files' values (~scene_file_values). Without the files,
  /// the private parameters alone (e.g. `rosparam load`). Throws InvalidParameter.
  NodeKeys read_node_keys(const ParameterTree& own) const;
  /// The configurations of the tops the parameters describe (the node's own, or ~tops), from one
  /// fetch of the private namespace, and the node's own keys.
  std::vector<std::pair<std::string, SceneConfig>> read_tops(const ParameterTree& tree, NodeKeys& node_keys) const;
  /// A named top's tip position at the start, ~<name>/x and ~<name>/y [m] (throws
  /// InvalidParameter naming <name>/x or <name>/y); the origin for the node's own top.
  Eigen::Vector2d read_tip_position(const ParameterTree& tree, const std::string& name) const;
  /// With scene files: the keys in force written back to ~<key> (so that `rosparam get ~mass`
  /// says what runs) and the files' values to ~scene_file_values/<key> (so that a later read
  /// tells the node's write-back from an explicit ~<key>). Live keys are the reconfigure server's.
  void write_back(const NodeKeys& node_keys);
  /// Throws StartupInterrupted if ROS is shutting down or SIGINT came (checked between the steps
  /// of the start); then what was advertised so far is unregistered and ROS shut down first.
  void stop_if_shutting_down(const char* step);
  static std::atomic<int> stop_requested_, stopping_the_start_;
  static_assert(std::atomic<int>::is_always_lock_free, "set from a signal handler");
  /// `reset_service`: the top (a named one) advertises ~<name>/reset (~top_reset_services,
  /// ~spawn_reset_services).
  void add_top(std::unique_ptr<TopInstance> top, bool reset_service);
  /// A new top's topics and its events' way to ~events: ~top_topics at the start, ~spawn_topics
  /// for a spawned top.
  std::unique_ptr<TopInstance> make_top(const std::string& name, const SceneConfig& config,
                                        const Eigen::Vector2d& tip_xy, const std::vector<std::string>& topics);
  TopInstance* find_top(const std::string& name);

  void on_timer(const ros::WallTimerEvent& event);
  void on_diagnostics_timer(const ros::WallTimerEvent&);
  /// One tick: every top advances exactly 1/rate of simulated time, then everything is
  /// published with one stamp. The integration stops at `deadline`: then the tick is unfinished
  /// (false, nothing published) and the next call goes on with it, so the published samples do
  /// not depend on where it stopped.
  bool tick(ros::WallTime deadline);
  /// tick() with its wall cost counted for the diagnostics; `now` moves to its end.
  bool timed_tick(ros::WallTime deadline, ros::WallTime& now);
  void publish(const ros::Time& stamp);
  void send_static_transforms();
  /// diagnostics' hardware id: spinning_top/<scene> of the tops (each status has its own top's).
  void update_hardware_id();
  void restart_timer();
  void report(const std::string& status);
  /// A top's stamps for its events: as the ticks' (stamp_at, read when used).
  TopInstance::StampOf stamp_of() const {
    return [this](double world_time) { return stamp_at(world_time); };
  }
  /// The tick clock now, for a top's exact time since its start.
  TopInstance::WorldClock world_clock() const {
    return [this] { return WorldTime{clock_.time(), clock_.ticks(), clock_.rate_since(), clock_.rate()}; };
  }
  /// The stamp of a world time: stamp_origin_.base + (world_time - stamp_origin_.world_base).
  ros::Time stamp_at(double world_time) const { return stamp_origin_.at(world_time); }

  // --- The clock (~publish_clock). auto: at start the node asks the master (getSystemState)
  // who publishes /clock; if nobody does, it advertises /clock and asks again, and of the
  // ~publish_clock auto nodes publishing then the first registered one keeps publishing (every
  // node reads the same list, so exactly one does; the others stop before their first tick).
  // A publisher that is no such node (rosbag play --clock, Gazebo, ~publish_clock true) is
  // always followed. A thread asks again every second (clock_arbiter_loop), so that a clock
  // appearing later is followed and a clock that disappears is taken over.
  enum class ClockRole { kPublish, kFollow, kOwnPace };
  struct ClockVerdict {
    bool publish = true;
    std::string source;  ///< the publisher followed (when !publish)
  };
  /// What an auto node does, given the publishers of /clock in the master's order (ourselves
  /// among them if registered). Reads the others' ~publish_clock (master calls; any thread).
  static ClockVerdict judge_clock(const std::vector<std::string>& publishers);
  void start_clock();
  void clock_arbiter_loop();
  void on_clock_role_timer(const ros::WallTimerEvent&);
  void publish_own_clock(const std::string& why);
  void follow_clock(const std::string& source, const std::string& why);
  void on_clock(const rosgraph_msgs::Clock::ConstPtr& message);
  /// Following: the ticks stamped at most external_time_, within the tick budget; a backlog
  /// goes on at the timer.
  void follow_to(ros::WallTime start);
  /// From now on the world's current time is stamped `stamp` (the next tick one period later).
  void anchor_stamps(const ros::Time& stamp);
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
  bool on_get_state(GetState::Request& request, GetState::Response& response);

  ros::NodeHandle nh_, private_nh_;
  NodeSettings settings_;
  TickClock clock_;
  std::vector<std::unique_ptr<TopInstance>> tops_;
  std::vector<ros::ServiceServer> top_reset_services_;  // ~<name>/reset, one per named top

  // Stamps are stamp_origin_ + simulated time: the world's time never goes back (a reset
  // restarts the tops' times, not the world's), so stamps never repeat or go back, unless an
  // external clock the node follows goes back (its source was reset): then they follow it.
  struct StampOrigin {
    ros::Time base;           ///< the stamp of world time world_base
    double world_base = 0.0;  ///< [s] (a ros::Time cannot be negative: following a clock, the
                              ///< external time may be smaller than the world's)
    ros::Time at(double world_time) const {
      const double offset = world_time - world_base;
      if (offset < 0.0 && base.toSec() + offset <= 0.0) return ros::Time(0, 1);  // never 0 or negative
      return base + ros::Duration(offset);
    }
    /// `origin + ros::Duration(world_time)`: the stamp of that world time.
    ros::Time operator+(const ros::Duration& world_time) const { return at(world_time.toSec()); }
    StampOrigin& operator+=(const ros::Duration& shift) {
      base += shift;
      return *this;
    }
    StampOrigin& operator=(const ros::Time& stamp) {  // stamp of world time 0
      base = stamp;
      world_base = 0.0;
      return *this;
    }
  };
  StampOrigin stamp_origin_;
  ros::Time last_stamp_;

  ClockRole clock_role_ = ClockRole::kOwnPace;
  std::string clock_source_;     // the node whose /clock is followed
  ros::Subscriber clock_subscriber_;
  bool external_anchored_ = false;  // following: the first /clock message came
  ros::Time external_time_;         // following: the last /clock received
  ros::WallTime external_wall_;     // ... and when
  long clock_role_changes_ = 0, external_jumps_back_ = 0;
  std::thread clock_arbiter_;
  std::mutex arbiter_mutex_;
  std::condition_variable arbiter_wake_;
  bool arbiter_stop_ = false;
  bool verdict_ready_ = false;  // a verdict the main thread has not applied yet
  ClockVerdict verdict_;
  ros::WallTimer clock_role_timer_;
  bool paused_ = false;
  bool waiting_for_subscriber_ = false;  // ~wait_for_subscriber: no tick yet, nobody listening yet
  bool tick_unfinished_ = false;  // the current tick ran out of its budget; the next call goes on
  long ticks_per_clock_ = 1, ticks_per_tf_ = 1, ticks_per_marker_ = 1, ticks_per_states_ = 1;

  // Pacing and cost, reported in diagnostics (per 1 s window and in total).
  long catch_up_run_ = 0;                                   // late ticks in a row, back to back
  long long_catch_ups_ = 0, long_catch_ups_at_window_start_ = 0;  // runs longer than kSubscriberQueueHint
  long late_ticks_ = 0, late_ticks_at_window_start_ = 0;        // taken after their slot (catch-up)
  long given_up_ticks_ = 0, given_up_ticks_at_window_start_ = 0;  // beyond ~max_lag
  long budget_exhaustions_ = 0, budget_exhaustions_at_window_start_ = 0;
  double sim_time_in_window_ = 0.0;  // [s] simulated
  long ticks_in_window_ = 0;
  double tick_cost_sum_ = 0.0, tick_cost_max_ = 0.0;  // [s] wall
  ros::WallTime window_wall_start_;
  double last_lag_ = 0.0;  // [wall s] behind the wall clock after the last callback

  ros::Publisher clock_publisher_, status_publisher_;
  // ~states (every top's TopState in one TopStateArray a tick, when subscribed) and ~events (every
  // top's TopEvent): one registration each however many tops, so a top needs none of its own.
  ros::Publisher states_publisher_, events_publisher_;
  std::shared_ptr<std::atomic<int>> states_listeners_ = std::make_shared<std::atomic<int>>(0);
  // /tf and /tf_static (tf2_msgs/TFMessage) as tf2_ros's broadcasters publish them, on our own
  // publishers: their validity can be checked (tf2_ros traps on an invalid one during a shutdown),
  // and the latched /tf_static message is exactly the pivots that exist now.
  ros::Publisher tf_publisher_, static_publisher_;
  std::vector<geometry_msgs::TransformStamped> static_sent_;  // the latched /tf_static message's frames
  SceneType node_scene_ = SceneType::kFixedTip;  // the scene of the node's own keys (~scene)
  ros::ServiceServer reset_service_, reload_service_, pause_service_, resume_service_, step_service_,
      spawn_service_, kill_service_, set_state_service_, get_state_service_;
  TickTimer timer_;
  ros::WallTimer diagnostics_timer_;
  std::unique_ptr<diagnostic_updater::Updater> diagnostics_;
  std::unique_ptr<ReconfigureServer> reconfigure_server_;
  SpinningTopConfig applied_config_;
  bool reconfigure_initialized_ = false;
};

}  // namespace ros_front_end
}  // namespace spinning_top
