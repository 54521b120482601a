#include "spinning_top/ros/top_instance.hpp"

#include <geometry_msgs/PointStamped.h>
#include <geometry_msgs/TwistStamped.h>
#include <geometry_msgs/WrenchStamped.h>
#include <std_msgs/String.h>
#include <visualization_msgs/MarkerArray.h>

#include <algorithm>
#include <cmath>

#include "spinning_top/kinematics.hpp"
#include "spinning_top/ros/conversions.hpp"
#include "spinning_top/ros/live_keys.hpp"
#include "spinning_top/ros/markers.hpp"

namespace spinning_top {
namespace ros_front_end {
namespace {

bool finite(const Snapshot& s) {
  const ModelOutputs& o = s.outputs;
  return std::isfinite(s.time) && s.attitude.coeffs().allFinite() && s.body_rates.allFinite() &&
         o.center_of_mass.allFinite() && o.center_of_mass_velocity.allFinite() && o.contact_point.allFinite() &&
         o.contact_force.allFinite() && std::isfinite(o.normal_force) && std::isfinite(o.energy) &&
         std::isfinite(o.dissipated_energy);
}

/// What diagnostics and the state message report of the numerics.
struct Monitors {
  double energy_balance, quaternion_norm_error, constraint_residual;
};

/// `pivot`: where a fixed tip pivots (the core's frame).
Monitors monitors(const Snapshot& s, const SceneConfig& config, double energy_baseline, const Vector3& pivot) {
  const ModelOutputs& out = s.outputs;
  Monitors m;
  // Energy balance E + W - E0 (W: work against friction and the energy lost in landings).
  m.energy_balance = (out.energy + out.dissipated_energy - energy_baseline) / std::max(std::abs(energy_baseline), 1e-300);
  m.quaternion_norm_error = std::abs(s.attitude.norm() - 1.0);
  // The tip P = G - h e_Z, whose height the core reports as the contact point's z (0 on the
  // floor); on the floor also the contact constraint z_P = 0 (PHYSICS.md) and, for a fixed tip,
  // P at its pivot. In flight P is free: only the first holds.
  const Vector3 axis = s.attitude * Vector3::UnitZ();
  double constraint = std::abs(out.center_of_mass.z() - config.top.tip_distance * axis.z() - out.contact_point.z());
  if (s.phase != Phase::kFlight) {
    constraint = std::max(constraint, std::abs(out.contact_point.z()));
    if (config.scene == SceneType::kFixedTip)
      constraint = std::max(constraint, (out.contact_point.head<2>() - pivot.head<2>()).norm());
  }
  m.constraint_residual = constraint;
  return m;
}

std::string event_name(Event event) { return event == Event::kNone ? "" : to_string(event); }

/// A top whose run has ended, as the topics show it: where it stopped, at rest. The core's last
/// state still moves (a fall is located while the top swings down, a flight ends at the rim's
/// touch); publishing its rates and forces for ever would show a top frozen in mid-motion.
Snapshot at_rest(Snapshot s) {
  s.body_rates.setZero();
  s.outputs.center_of_mass_velocity.setZero();
  s.outputs.normal_force = 0.0;
  s.outputs.contact_force.setZero();
  return s;
}

}  // namespace

TopInstance::TopInstance(std::string name, const SceneConfig& config, const Eigen::Vector2d& tip_xy,
                         const NodeSettings& settings, const std::vector<std::string>& topics,
                         ros::NodeHandle private_nh, double world_time, StampOf stamp_of, WorldClock world_clock,
                         EventSink event_sink)
    : name_(std::move(name)),
      settings_(settings),
      body_frame_(top_frame(settings, name_, true)),
      contact_frame_(top_frame(settings, name_, false)),
      stamp_of_(std::move(stamp_of)),
      world_clock_(std::move(world_clock)),
      event_sink_(std::move(event_sink)),
      nh_(name_.empty() ? private_nh : ros::NodeHandle(private_nh, name_)) {
  restart(config, tip_xy, world_time);  // validates before anything is advertised
  // Each per-tick topic with its count of subscribers (Listeners): the callbacks hold the counts,
  // not the top, so a callback queued before a ~kill finds them still there.
  const auto counted = [this](const std::string& topic, uint32_t queue, std::atomic<int> Listeners::*count,
                              auto message) {
    const std::shared_ptr<Listeners> listeners = listeners_;
    return nh_.advertise<decltype(message)>(
        topic, queue, [listeners, count](const ros::SingleSubscriberPublisher&) { ++((*listeners).*count); },
        [listeners, count](const ros::SingleSubscriberPublisher&) { --((*listeners).*count); });
  };
  // Only the topics asked for (~top_topics or ~spawn_topics), in their (the advertisement) order:
  // an empty ros::Publisher (false) is one the top does not have; nothing is published on it.
  for (const std::string& topic : topics) {
    if (topic == "contact_point")
      contact_point_publisher_ = counted(topic, 1000, &Listeners::contact_point, geometry_msgs::PointStamped());
    else if (topic == "normal_force")
      normal_force_publisher_ = counted(topic, 1000, &Listeners::normal_force, geometry_msgs::WrenchStamped());
    else if (topic == "twist")
      twist_publisher_ = counted(topic, 1000, &Listeners::twist, geometry_msgs::TwistStamped());
    else if (topic == "state")
      state_publisher_ = counted(topic, 1000, &Listeners::state, spinning_top::TopState());
    else if (topic == "markers")
      marker_publisher_ = counted(topic, 10, &Listeners::markers, visualization_msgs::MarkerArray());
    // Several events can come within one tick (a landing and the lift-off at the same instant):
    // a queue, so that a subscriber gets each; latched, a late one gets the last.
    else if (topic == "event")
      event_publisher_ = nh_.advertise<std_msgs::String>(topic, 100, /*latch=*/true);
    else if (topic == "event_stamped")
      event_stamped_publisher_ = nh_.advertise<spinning_top::TopEvent>(topic, 100, /*latch=*/true);
  }
  nh_.setParam("robot_description", top_urdf(start_config_.top, body_frame_));
}

std::vector<std::string> TopInstance::advertised_topics() const {
  std::vector<std::string> topics;
  for (const ros::Publisher* publisher : {&contact_point_publisher_, &normal_force_publisher_, &twist_publisher_,
                                          &state_publisher_, &marker_publisher_, &event_publisher_,
                                          &event_stamped_publisher_})
    if (*publisher) topics.push_back(publisher->getTopic());
  return topics;
}

// A killed top's URDF is deleted by ~kill; at shutdown the parameters stay (as every node's do;
// the launch file clears the namespace at the next start), which spares a call to the master per
// top while the node exits.
TopInstance::~TopInstance() = default;

void TopInstance::start(const SceneConfig& config, double time_base, double world_time) {
  const WorldTime now = world_clock_();
  // validates; throws InvalidParameter. A start at the world's time is at its tick.
  start(make_simulator(config), time_base, world_time, now.time == world_time ? now.tick : -1);
}

void TopInstance::start(std::unique_ptr<Simulator> simulator, double time_base, double world_time, long origin_tick) {
  simulator_ = std::move(simulator);
  start_event_reported_ = false;
  time_base_ = time_base;
  origin_ = world_time;
  origin_tick_ = origin_tick;
  now_ = simulator_->snapshot();
  pivot_ = now_.outputs.contact_point;
  rebaseline_energy();
}

void TopInstance::place_tip_at(const Eigen::Vector2d& tip_xy) {
  offset_ = Vector3(tip_xy.x() - now_.outputs.contact_point.x(), tip_xy.y() - now_.outputs.contact_point.y(), 0.0);
}

void TopInstance::restart(const SceneConfig& config, const Eigen::Vector2d& tip_xy, double world_time) {
  for (int i = 0; i < 2; ++i)
    if (!(std::abs(tip_xy[i]) <= 1e6))
      throw InvalidParameter(i == 0 ? "x" : "y", "the tip's position must be finite and within 1e6 m of the origin");
  const bool had_event = simulator_ && simulator_->event() != Event::kNone;
  start(config, 0.0, world_time);
  start_config_ = config;
  start_tip_xy_ = tip_xy;
  place_tip_at(tip_xy);
  trace_.clear();
  if (had_event) publish_event("", now_, false);  // "": no event (the core's spelling of none)
}

void TopInstance::reset(double world_time) { restart(start_config_, start_tip_xy_, world_time); }

SettableState TopInstance::settable_state() const {
  if (simulator_->event() != Event::kNone)
    throw InvalidParameter("name", std::string("the top stopped at its ") + to_string(simulator_->event()) +
                                       " event: ~set_state cannot start from there (call ~reset)");
  SettableState state;
  if (time_base_ == 0.0 && now_.time == 0.0) {
    // Where it started (start, reset, ~set_state, ~reload), as it was given: the attitude and
    // rates read back from the quaternion would differ in the last bits.
    state.initial = start_config_.initial;
    state.tip = start_tip_xy_;
    return state;
  }
  require_on_the_floor("name");  // ~set_state starts on the floor
  const EulerState e = euler_state(now_.attitude, now_.body_rates);
  state.initial.tilt = e.tilt;
  state.initial.heading = e.heading;
  state.initial.spin_angle = e.spin_angle;
  state.initial.precession_rate = e.precession_rate;
  state.initial.nutation_rate = e.nutation_rate;
  state.initial.spin = e.spin;
  state.initial.velocity_x = state.initial.velocity_y = 0.0;
  if (start_config_.scene == SceneType::kViscous) {  // as a live body change takes it (prepare_body)
    state.initial.velocity_x = now_.outputs.center_of_mass_velocity.x();
    state.initial.velocity_y = now_.outputs.center_of_mass_velocity.y();
  }
  state.tip = world(now_.outputs.contact_point).head<2>();
  return state;
}

bool TopInstance::update(const TopParameters& top, const IntegratorSettings& integrator) {
  const bool switched = simulator_->update(top, integrator);  // validates; changes nothing if it throws
  now_ = simulator_->snapshot();  // a new g or k changes R and the floor force of the same state
  // ~reset starts again with what the update changed: the model's live keys (level kModel of
  // live_keys.def) and the integrator settings.
  SceneConfig updated = start_config_;
  updated.top = top;
  for (const LiveKey& key : live_keys())
    if (key.level == kModel && key.in_top != nullptr) *key.in_top(start_config_) = *key.in_top(updated);
  start_config_.integrator = integrator;
  rebaseline_energy();
  return switched;
}

void TopInstance::require_on_the_floor(const std::string& key) const {
  const Phase phase = simulator_->phase();
  if (phase != Phase::kContact)
    throw InvalidParameter(key, std::string("cannot change while the tip is off the floor (") + to_string(phase) +
                                    "); try again when it has landed");
}

TopInstance::BodyChange TopInstance::prepare_body(const TopParameters& top, const IntegratorSettings& integrator,
                                                  double spin, const std::string& key) const {
  if (simulator_->event() != Event::kNone)
    throw InvalidParameter(key, std::string("the top stopped at its ") + to_string(simulator_->event()) +
                                    " event: reset it before changing its body");
  // A new contact model from a flying state would put the top back on the floor.
  require_on_the_floor(key);
  const Snapshot now = now_;
  const EulerState e = euler_state(now.attitude, now.body_rates);
  SceneConfig config = simulator_->config();
  config.top = top;
  config.integrator = integrator;
  config.initial = InitialConditions{};
  config.initial.heading = e.heading;
  config.initial.tilt = e.tilt;
  config.initial.spin_angle = e.spin_angle;
  config.initial.precession_rate = e.precession_rate;
  config.initial.nutation_rate = e.nutation_rate;
  config.initial.spin = spin;
  if (config.scene == SceneType::kViscous) {
    config.initial.velocity_x = now.outputs.center_of_mass_velocity.x();
    config.initial.velocity_y = now.outputs.center_of_mass_velocity.y();
  }
  BodyChange change;
  change.start = start_config_;
  change.start.top = top;
  change.start.integrator = integrator;
  change.start.initial.spin = spin;
  validate(change.start);  // ~reset must still work with the new body
  change.tip = world(now.outputs.contact_point).head<2>();
  // The new model starts where the old one is: at the world time of its state (an unfinished
  // tick has not reached the world's time yet).
  change.simulator = make_simulator(config);  // validates the state
  if (change.simulator->event() != Event::kNone)
    throw InvalidParameter(key, std::string("with the new body the run would end at once at the current state (") +
                                    to_string(change.simulator->event()) + "): refused, the run goes on");
  change.top = top;
  change.time_base = time_base_ + simulator_->time();
  change.origin = origin_ + simulator_->time();
  return change;
}

void TopInstance::change_body(BodyChange change) {
  start(std::move(change.simulator), change.time_base, change.origin, -1);  // between ticks
  start_config_ = change.start;
  nh_.setParam("robot_description", top_urdf(change.top, body_frame_));
  place_tip_at(change.tip);  // the tip stays where it is: the new model's origin moves under it
}

bool TopInstance::advance(double world_time, const WorkBudget& budget) {
  if (simulator_->event() != Event::kNone) {
    // A run the core ended where it started (R < 0 at the release with after_lift_off: stop):
    // reported as any other event, once (the transitions of its start first, in time order).
    if (!start_event_reported_) {
      start_event_reported_ = true;
      for (const Transition& transition : simulator_->take_transitions())
        publish_event(to_string(transition.event), transition.state, false);
      handle_event(simulator_->event());
    }
    return true;  // stopped: the final pose goes on being published
  }
  // The top's time: the ticks since its start / rate where the rate has not changed since (one
  // rounding: a start at another world time runs alike, bit for bit); else the difference.
  const WorldTime now = world_clock_();
  const double target = origin_tick_ >= 0 && origin_tick_ >= now.rate_since && now.time == world_time
                            ? static_cast<double>(now.tick - origin_tick_) / now.rate
                            : world_time - origin_;
  const Event event = simulator_->advance_to(target, budget);
  // The transitions passed, also by a call that ran out of budget (the next one goes on after them).
  for (const Transition& transition : simulator_->take_transitions()) {
    if (transition.event == Event::kLanding) pivot_ = transition.state.outputs.contact_point;  // a fixed tip sticks there
    ROS_DEBUG("spinning_top: %s%s at t = %.9g s (simulated), now %s", name_.empty() ? "" : (name_ + ": ").c_str(),
              to_string(transition.event), time_base_ + transition.state.time, to_string(transition.state.phase));
    publish_event(to_string(transition.event), transition.state, false);
  }
  if (event == Event::kNone && simulator_->time() < target) return false;  // out of budget
  now_ = simulator_->snapshot();
  if (event != Event::kNone) {
    start_event_reported_ = true;
    handle_event(event);
  }
  return true;
}

double TopInstance::time() const { return time_base_ + now_.time; }

void TopInstance::handle_event(Event event) {
  ROS_ERROR("spinning_top: %s%s%s at t = %.9g s (simulated): integration stopped; the last valid pose is "
            "kept, at rest. Call ~reset (or ~set_state) to start again.",
            name_.empty() ? "" : "top ", name_.empty() ? "" : (name_ + ": ").c_str(), to_string(event), time());
  publish_event(to_string(event), now_, true);
}

void TopInstance::publish_event(const char* event, const Snapshot& at, bool terminal) {
  if (event_publisher_) {
    std_msgs::String text;
    text.data = event;
    event_publisher_.publish(text);
  }
  if (!event_stamped_publisher_ && !event_sink_) return;
  spinning_top::TopEvent stamped;
  stamped.header.stamp = stamp_of_(origin_ + at.time);
  stamped.header.frame_id = settings_.world_frame;
  stamped.name = name_;
  stamped.event = event;
  stamped.terminal = terminal;
  stamped.time = time_base_ + at.time;
  stamped.phase = to_string(at.phase);
  stamped.contact_point = to_point(world(at.outputs.contact_point));
  if (event_stamped_publisher_) event_stamped_publisher_.publish(stamped);
  if (event_sink_) event_sink_(stamped);
}

Snapshot TopInstance::shown() const { return simulator_->event() == Event::kNone ? now_ : at_rest(now_); }

void TopInstance::rebaseline_energy() {
  energy_baseline_ = now_.outputs.energy + now_.outputs.dissipated_energy;
}

void TopInstance::append_transforms(const ros::Time& stamp, std::vector<geometry_msgs::TransformStamped>& out) const {
  const Snapshot& s = now_;
  geometry_msgs::TransformStamped body;
  body.header.stamp = stamp;
  body.header.frame_id = settings_.world_frame;
  body.child_frame_id = body_frame_;
  const Vector3 g = world(s.outputs.center_of_mass);
  body.transform.translation = to_vector(g);
  body.transform.rotation.w = s.attitude.w();
  body.transform.rotation.x = s.attitude.x();
  body.transform.rotation.y = s.attitude.y();
  body.transform.rotation.z = s.attitude.z();
  out.push_back(body);
  if (!contact_is_static()) out.push_back(contact_transform(stamp));
}

geometry_msgs::TransformStamped TopInstance::contact_transform(const ros::Time& stamp) const {
  // The contact frame: at the tip (in the air too), axes parallel to the world's, so that the
  // floor force (in world components) is drawn by rviz where it acts.
  geometry_msgs::TransformStamped contact;
  contact.header.stamp = stamp;
  contact.header.frame_id = settings_.world_frame;
  contact.child_frame_id = contact_frame_;
  contact.transform.translation = to_vector(world(now_.outputs.contact_point));
  contact.transform.rotation.w = 1.0;
  return contact;
}

bool TopInstance::publish(const ros::Time& stamp, bool with_markers, std::vector<spinning_top::TopState>* all_states) {
  Snapshot s = shown();
  if (!finite(s)) {  // the core promises this never happens; never pass it on
    ROS_ERROR_ONCE("spinning_top: non-finite state at t = %.9g s not published", s.time);
    return false;
  }
  if (s.outputs.normal_force < 0.0) {  // the core promises R >= 0; the floor cannot pull the tip
    ROS_ERROR_ONCE("spinning_top: R = %.6g N < 0 at t = %.9g s published as 0 (the floor cannot pull)",
                   s.outputs.normal_force, s.time);
    s.outputs.normal_force = 0.0;
    s.outputs.contact_force.setZero();
  }
  const ModelOutputs& out = s.outputs;
  const Vector3 contact = world(out.contact_point);
  const Vector3 force(out.contact_force.x(), out.contact_force.y(), out.normal_force);

  geometry_msgs::PointStamped point;
  point.header.stamp = stamp;
  point.header.frame_id = settings_.world_frame;
  point.point = to_point(contact);
  if (listeners_->contact_point > 0) contact_point_publisher_.publish(point);

  geometry_msgs::WrenchStamped wrench;
  wrench.header.stamp = stamp;
  wrench.header.frame_id = contact_frame_;
  wrench.wrench.force = to_vector(force);  // pivot reaction or friction; 0 when frictionless; all 0 in flight
  if (listeners_->normal_force > 0) normal_force_publisher_.publish(wrench);  // torque about the tip: 0 (a point contact)

  // The body's twist in the world frame: omega = q omega_body, and G's velocity.
  const Vector3 omega = s.attitude * s.body_rates;
  geometry_msgs::TwistStamped twist;
  twist.header = point.header;
  twist.twist.linear = to_vector(out.center_of_mass_velocity);
  twist.twist.angular = to_vector(omega);
  if (listeners_->twist > 0) twist_publisher_.publish(twist);

  if (listeners_->state > 0 || all_states != nullptr) {
    const EulerState e = euler_state(s.attitude, s.body_rates);
    // The monitors judge the integration: those of the core's state (also after the end).
    const Monitors m = monitors(now_, simulator_->config(), energy_baseline_, pivot_);
    spinning_top::TopState state;
    state.header = point.header;
    state.name = name_;
    state.time = time();
    state.tilt = e.tilt;
    state.heading = e.heading;
    state.spin_angle = e.spin_angle;
    state.precession_rate = e.precession_rate;
    state.nutation_rate = e.nutation_rate;
    state.spin = e.spin;
    state.angular_velocity = to_vector(omega);
    state.center_of_mass = to_point(world(out.center_of_mass));
    state.center_of_mass_velocity = to_vector(out.center_of_mass_velocity);
    state.contact_point = to_point(contact);
    state.normal_force = out.normal_force;
    state.contact_force = to_vector(out.contact_force);
    state.energy = out.energy;
    state.dissipated_energy = out.dissipated_energy;
    state.energy_balance = m.energy_balance;
    state.quaternion_norm_error = m.quaternion_norm_error;
    state.constraint_residual = m.constraint_residual;
    state.event = event_name(simulator_->event());
    state.phase = to_string(s.phase);
    if (listeners_->state > 0) state_publisher_.publish(state);
    if (all_states != nullptr) all_states->push_back(std::move(state));
  }

  if (settings_.trace_length > 0 &&
      (trace_.empty() || (trace_.back() - contact).norm() >= settings_.trace_resolution)) {
    trace_.push_back(contact);
    while (static_cast<int>(trace_.size()) > settings_.trace_length) trace_.pop_front();
  }
  if (with_markers && listeners_->markers > 0)
    marker_publisher_.publish(top_markers(simulator_->config().top, contact, force, trace_,
                                          {settings_.world_frame, body_frame_}, settings_.force_scale, stamp));
  return true;
}

void TopInstance::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) const {
  using diagnostic_msgs::DiagnosticStatus;
  const Snapshot& s = now_;
  const ModelOutputs& out = s.outputs;
  const Monitors m = monitors(s, simulator_->config(), energy_baseline_, pivot_);
  // Hops (lift_off, take_off, landing) are the motion, not faults: only the event that ended
  // the run is an ERROR.
  if (std::abs(m.energy_balance) > settings_.energy_drift_error)
    status.mergeSummaryf(DiagnosticStatus::ERROR, "energy drift %.3g", m.energy_balance);
  else if (std::abs(m.energy_balance) > settings_.energy_drift_warning)
    status.mergeSummaryf(DiagnosticStatus::WARN, "energy drift %.3g", m.energy_balance);
  if (m.quaternion_norm_error > settings_.quaternion_norm_error)
    status.mergeSummaryf(DiagnosticStatus::ERROR, "quaternion norm off by %.3g", m.quaternion_norm_error);
  if (m.constraint_residual > settings_.constraint_error)
    status.mergeSummaryf(DiagnosticStatus::ERROR, "contact constraint residual %.3g m", m.constraint_residual);
  const Event stopped = simulator_->event();  // the run ends at the event: time() is its time
  if (stopped != Event::kNone)
    status.mergeSummaryf(DiagnosticStatus::ERROR, "event %s at t = %.9g s", to_string(stopped), time());

  if (!name_.empty()) status.add("top", name_);
  status.hardware_id = std::string("spinning_top/") + to_string(simulator_->config().scene);
  status.add("scene", to_string(simulator_->config().scene));
  // What runs and why (auto: its choice, and exact's refusal where it fell back).
  const IntegratorChoice choice = simulator_->integrator_choice();
  status.add("integrator", simulator_->integrator_description());
  status.add("integrator method", to_string(choice.method));
  if (choice.fallback) status.add("integrator fallback reason", choice.reason);
  status.add("integrator steps since reset", simulator_->steps());
  status.addf("simulated time [s]", "%.9g", time());
  status.add("event", stopped == Event::kNone ? "none" : to_string(stopped));
  if (stopped != Event::kNone) status.addf("event time [s]", "%.9g", time());
  status.addf("energy [J]", "%.12g", out.energy);
  status.addf("dissipated energy [J]", "%.12g", out.dissipated_energy);
  status.addf("energy balance (E + W - E0) / |E0|", "%.3g", m.energy_balance);
  status.addf("quaternion norm error", "%.3g", m.quaternion_norm_error);
  status.addf("constraint residual [m]", "%.3g", m.constraint_residual);
  status.addf("normal force [N]", "%.9g", std::max(0.0, shown().outputs.normal_force));
  const HopSummary hops = simulator_->hops();
  status.add("phase", to_string(s.phase));
  status.addf("tip height [m]", "%.9g", out.contact_point.z());
  status.add("lift-offs", hops.lift_offs);
  status.add("take-offs", hops.take_offs);
  status.add("landings", hops.landings);
  status.addf("highest hop [m]", "%.9g", hops.max_hop_height);
  status.addf("energy lost in landings [J]", "%.9g", hops.impact_loss);
}

}  // namespace ros_front_end
}  // namespace spinning_top
