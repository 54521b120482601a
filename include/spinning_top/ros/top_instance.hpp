// One simulated top in the node (turtlesim's turtle.cpp): its simulator, its place on the
// floor, its frames, topics, markers, event and diagnostics. The world (spinning_top_node.hpp)
// owns the clock and calls advance() and publish() at every tick for every top.
#pragma once

#include <diagnostic_updater/DiagnosticStatusWrapper.h>
#include <geometry_msgs/TransformStamped.h>
#include <ros/ros.h>

#include <atomic>
#include <deque>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "spinning_top/TopEvent.h"
#include "spinning_top/TopState.h"
#include "spinning_top/ros/node_settings.hpp"
#include "spinning_top/simulator.hpp"

namespace spinning_top {
namespace ros_front_end {

/// The world's time at a tick, as the tick clock has it (TickClock): its value, and the tick
/// counts by which a top's own time is exact (the same number of ticks since its start gives
/// the same time, bit for bit, wherever that start was: a state set back runs again alike).
struct WorldTime {
  double time = 0.0;    ///< [s] TickClock::time()
  long tick = 0;        ///< TickClock::ticks()
  long rate_since = 0;  ///< TickClock::rate_since()
  double rate = 1.0;    ///< [Hz] TickClock::rate()
};

/// A top's state in the fields of ~set_state (SetState.srv), as ~get_state returns it.
struct SettableState {
  InitialConditions initial;
  Eigen::Vector2d tip = Eigen::Vector2d::Zero();  ///< [m] the tip on the floor (x, y)
};

class TopInstance {
 public:
  /// The world's stamp of a world time (the node's stamp origin + t): events are stamped with
  /// their own instant, which lies between two ticks.
  using StampOf = std::function<ros::Time(double world_time)>;
  /// The world's tick clock now (WorldTime): a start at its time() is at its tick.
  using WorldClock = std::function<WorldTime()>;
  /// Where every event of the top goes besides its own ~event_stamped: the node's ~events.
  using EventSink = std::function<void(const spinning_top::TopEvent&)>;

  /// `name` "" is the node's own top: frames <body_frame>, <contact_frame> and topics ~/...;
  /// a named top has frames <name>/<body_frame>, <name>/<contact_frame> and topics ~<name>/...
  /// (frames prefixed with the node's namespace unless given explicitly: top_frame()).
  /// Its URDF goes on ~robot_description (~<name>/robot_description).
  /// Its simulated time 0 is the world's `world_time`; its tip starts at `tip_xy` on the floor.
  /// It advertises `topics` (of per_top_topic_names(): ~top_topics, or ~spawn_topics for a
  /// spawned top) and passes each event to `event_sink` too.
  /// Throws InvalidParameter (nothing advertised) if the configuration is invalid.
  TopInstance(std::string name, const SceneConfig& config, const Eigen::Vector2d& tip_xy,
              const NodeSettings& settings, const std::vector<std::string>& topics, ros::NodeHandle private_nh,
              double world_time, StampOf stamp_of, WorldClock world_clock, EventSink event_sink);
  ~TopInstance();
  TopInstance(const TopInstance&) = delete;
  TopInstance& operator=(const TopInstance&) = delete;

  const std::string& name() const { return name_; }
  const Simulator& simulator() const { return *simulator_; }
  /// What ~reset and ~<name>/reset come back to (the last start, set_state or reload).
  const SceneConfig& start_config() const { return start_config_; }
  const std::string& body_frame() const { return body_frame_; }
  const std::string& contact_frame() const { return contact_frame_; }

  /// Advances to the world's simulated time; false if the budget ran out first (call again
  /// with the same time). Every transition passed on the way (lift_off, take_off, landing) and
  /// the event that ends the run are published on ~event and ~event_stamped, in time order.
  bool advance(double world_time, const WorkBudget& budget);
  /// The tick's transforms world -> body (and world -> contact unless it is static).
  void append_transforms(const ros::Time& stamp, std::vector<geometry_msgs::TransformStamped>& out) const;
  /// A pivot that can never move goes once on /tf_static: a fixed tip that may not leave the
  /// floor (after_lift_off: stop). Where the tip can fly, it lands elsewhere: /tf, every tick.
  bool contact_is_static() const {
    return start_config_.scene == SceneType::kFixedTip && start_config_.after_lift_off == AfterLiftOff::kStop;
  }
  geometry_msgs::TransformStamped contact_transform(const ros::Time& stamp) const;
  /// The tick's topics: contact point, floor force, twist, state (and markers when asked); after
  /// the event that ended the run, the final pose at rest (shown()). With `all_states`, the
  /// state is appended there too (the node's ~states).
  /// Returns false (nothing published) for a non-finite state, which the core promises never happens.
  bool publish(const ros::Time& stamp, bool with_markers, std::vector<spinning_top::TopState>* all_states = nullptr);

  /// Back to start_config() at the world's time (its simulated time restarts at 0).
  void reset(double world_time);
  /// A new start (set_state, reload): validated first; throws InvalidParameter and changes nothing.
  void restart(const SceneConfig& config, const Eigen::Vector2d& tip_xy, double world_time);
  /// The state now in ~set_state's fields. At the top's time 0 (just started, reset or set) they
  /// are those it started from, exactly (so that ~set_state of them gives them back bit for
  /// bit); later the attitude, rates and tip of the state now (G's velocity in the viscous scene
  /// only; elsewhere 0, which ~set_state requires). Throws InvalidParameter("name", why) when
  /// ~set_state could not start from it: the tip off the floor, or the run ended.
  SettableState settable_state() const;
  /// Live changes of the model (the live keys of level kModel, live_keys.def) and of the
  /// integrator settings, keeping the state (Simulator::update).
  /// Throws InvalidParameter and changes nothing; returns true if auto switched its method.
  bool update(const TopParameters& top, const IntegratorSettings& integrator);
  /// A live change of the body (m, A, C, h), of the spin omega_Z and of the model and integrator
  /// settings with them, prepared: the new model from the current state, built and checked.
  struct BodyChange {
    std::unique_ptr<Simulator> simulator;
    SceneConfig start;  ///< what ~reset comes back to afterwards
    TopParameters top;
    Eigen::Vector2d tip = Eigen::Vector2d::Zero();
    double time_base = 0.0, origin = 0.0;
  };
  /// Refused (throws InvalidParameter, nothing changes) for an invalid body or state, a state the
  /// new body cannot go on from (an event at once: R < 0 with after_lift_off: stop), after the
  /// event that ended the run, or while the tip is off the floor (require_on_the_floor()).
  /// `key`: the changed key a refusal names.
  BodyChange prepare_body(const TopParameters& top, const IntegratorSettings& integrator, double spin,
                          const std::string& key) const;
  /// Applies a prepared change: the attitude, the other rates, the tip's place and the simulated
  /// time go on. Cannot fail.
  void change_body(BodyChange change);
  /// [s] the top's simulated time: since its start, reset or set_state (live body changes go on).
  double time() const;
  /// The state at time(), taken once per change of it (every publication of a tick reads it).
  const Snapshot& snapshot() const { return now_; }
  /// What the topics show: snapshot(), or after the event that ended the run the final pose at
  /// rest (rates, velocities and floor forces 0), not the motion the run had at its end.
  Snapshot shown() const;
  /// The core takes no live change while the tip is off the floor (Simulator::update refuses it
  /// in flight and while skimming): throws InvalidParameter(key, why) then, so that the node can
  /// refuse a change for every top before it changes any.
  void require_on_the_floor(const std::string& key) const;

  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) const;
  Event event() const { return simulator_->event(); }
  /// Whether ~contact_point and ~state both have a subscriber, those of them the top has
  /// (~top_topics; read_node_settings requires one with ~wait_for_subscriber; true for a top
  /// without either).
  bool subscribed() const {
    return (!contact_point_publisher_ || listeners_->contact_point > 0) && (!state_publisher_ || listeners_->state > 0);
  }
  /// The top's topics (~top_topics or ~spawn_topics), resolved, in the order they were advertised (the master
  /// lists a node's registrations in that order; see SpinningTopNode::unregister_at_exit).
  std::vector<std::string> advertised_topics() const;

 private:
  /// Replaces the simulator (validated first) and rebaselines the energy.
  void start(const SceneConfig& config, double time_base, double world_time);
  /// `origin_tick`: the tick of the simulator's time 0, -1 if it lies between ticks.
  void start(std::unique_ptr<Simulator> simulator, double time_base, double world_time, long origin_tick);
  /// The core's origin on the floor such that the current contact point is at tip_xy.
  void place_tip_at(const Eigen::Vector2d& tip_xy);
  void handle_event(Event event);
  /// A run that ended where it started (R < 0 at the release with after_lift_off: stop, or a
  /// start the core ends at once): reported as any event, once (advance() does it).
  bool start_event_reported_ = false;
  /// `event` on ~event (its name) and ~event_stamped (with the state `at`, the simulator's).
  void publish_event(const char* event, const Snapshot& at, bool terminal);
  void rebaseline_energy();
  /// The core's position in the world frame (the top's place on the floor added).
  Vector3 world(const Vector3& core_position) const { return core_position + offset_; }

  std::string name_;
  NodeSettings settings_;
  std::string body_frame_, contact_frame_;
  SceneConfig start_config_;
  Eigen::Vector2d start_tip_xy_ = Eigen::Vector2d::Zero();
  std::unique_ptr<Simulator> simulator_;
  Snapshot now_;  // simulator_->snapshot(), refreshed whenever the simulator changes
  Vector3 offset_ = Vector3::Zero();  // the core's origin in the world frame (on the floor)
  Vector3 pivot_ = Vector3::Zero();   // fixed tip: where the tip pivots (core frame): its start or last landing
  double origin_ = 0.0;     // [s] world time of the simulator's time 0
  long origin_tick_ = -1;   // its tick (-1: between ticks, after a live body change)
  double time_base_ = 0.0;  // [s] the top's time at the simulator's time 0 (live body changes)
  double energy_baseline_ = 0.0;
  StampOf stamp_of_;
  WorldClock world_clock_;
  EventSink event_sink_;
  std::deque<Vector3> trace_;
  ros::NodeHandle nh_;  // ~ or ~<name>
  /// Subscribers of each per-tick topic, counted by the publishers' connect and disconnect
  /// callbacks. A topic without one is not published: roscpp finds a topic's publication by a
  /// linear search among all of the node's (in publish() and getNumSubscribers()), so with n tops
  /// every publication of a tick cost O(n), and a tick O(n^2) (1,000 tops: 7,000 publications).
  struct Listeners {
    std::atomic<int> contact_point{0}, normal_force{0}, twist{0}, state{0}, markers{0};
  };
  std::shared_ptr<Listeners> listeners_ = std::make_shared<Listeners>();
  ros::Publisher contact_point_publisher_, normal_force_publisher_, twist_publisher_, state_publisher_,
      marker_publisher_, event_publisher_, event_stamped_publisher_;
};

}  // namespace ros_front_end
}  // namespace spinning_top
