#include "spinning_top/ros/spinning_top_node.hpp"

#include <geometry_msgs/PointStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <geometry_msgs/WrenchStamped.h>
#include <rosgraph_msgs/Clock.h>
#include <std_msgs/String.h>
#include <visualization_msgs/MarkerArray.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <chrono>
#include <cstdio>

#include "spinning_top/ros/ros_parameters.hpp"

namespace spinning_top {
namespace ros_front_end {
namespace {

constexpr double kMaxRate = 100000.0;  // [Hz] beyond this the tick cost alone exceeds the period
constexpr double kAsFastAsPossibleSlice = 1e-3;  // [s] wall time per timer callback when rtf = 0
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

void require_frame(const std::string& key, const std::string& frame) {
  require(!frame.empty(), key, "must not be empty");
  require(frame[0] != '/', key, "'" + frame + "' must not start with '/' (tf2 frame ids have no leading slash)");
  // ROS names' characters (a letter first, then letters, digits, '_' and '/' between names): what
  // tf2, URDF and rviz handle everywhere; a space or a '-' breaks tools that parse frame lists.
  bool valid = std::isalpha(static_cast<unsigned char>(frame[0])) != 0 && frame.back() != '/' &&
               frame.find("//") == std::string::npos;
  for (const char c : frame) valid = valid && (std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '/');
  require(valid, key, "'" + frame + "' is not a valid frame id: a letter, then letters, digits, '_' and '/' "
                      "between names (REP-105 names such as world, top)");
}

/// The pacing keys, checked alike at start and by dynamic_reconfigure: throws InvalidParameter.
void validate_pacing(double rate, double real_time_factor) {
  require(std::isfinite(rate) && rate > 0.0 && rate <= kMaxRate, "rate", format("must lie in (0, %g] Hz", kMaxRate));
  require(std::isfinite(real_time_factor) && real_time_factor >= 0.0 && real_time_factor <= kMaxRealTimeFactor,
          "real_time_factor", format("must lie in [0, %g] (0 = as fast as possible)", kMaxRealTimeFactor));
}

bool finite(const Vector3& v) { return v.allFinite(); }

bool finite(const Snapshot& s) {
  const ModelOutputs& o = s.outputs;
  return std::isfinite(s.time) && s.attitude.coeffs().allFinite() && finite(o.center_of_mass) &&
         finite(o.contact_point) && finite(o.contact_force) && std::isfinite(o.normal_force);
}

geometry_msgs::Point to_point(const Vector3& v) {
  geometry_msgs::Point p;
  p.x = v.x();
  p.y = v.y();
  p.z = v.z();
  return p;
}

std_msgs::ColorRGBA color(float r, float g, float b, float a = 1.0f) {
  std_msgs::ColorRGBA c;
  c.r = r;
  c.g = g;
  c.b = b;
  c.a = a;
  return c;
}

/// The body drawn by rviz: a solid cone with its apex at the tip and its centroid at G
/// (height H = 4h/3, since a cone's centroid lies 3/4 of the way from the apex), whose
/// inertia ratio C/A about G is the top's: for a cone C = 3/10 m R^2 and
/// A = 3/20 m R^2 + 3/80 m H^2, so C/A = rho gives R^2 = rho H^2 / (4 (2 - rho)).
/// A real top is denser at the rim, so this is the shape, not the mass distribution.
/// rho -> 2 (a flat disc) or h = 0 has no such cone: the radius is then capped at 2H, and
/// for h = 0 it is the radius of the uniform cylinder with the same m and C, sqrt(2C/m).
struct BodyShape {
  double height, radius;
};

BodyShape body_shape(const TopParameters& top) {
  const double height = 4.0 * top.tip_distance / 3.0;
  const double rho = top.inertia_axial / top.inertia_transverse;
  double radius = rho < 2.0 ? 0.5 * height * std::sqrt(rho / (2.0 - rho)) : 2.0 * height;
  radius = std::min(radius, 2.0 * height);
  if (!(radius > 0.0)) radius = std::sqrt(2.0 * top.inertia_axial / top.mass);
  return {std::max(height, 1e-3), radius};
}

/// Keys of our private namespace that nobody reads (typos such as ~mas): warned about, not
/// fatal, since other tools may store things there.
void warn_about_unknown_keys(const ros::NodeHandle& private_nh) {
  static const char* const node_keys[] = {
      "rate", "real_time_factor", "tick_budget", "publish_clock", "start_paused", "world_frame", "body_frame",
      "contact_frame", "marker_rate", "trace_length", "trace_resolution", "force_scale",
      "energy_drift_warning", "energy_drift_error", "quaternion_norm_error", "constraint_error"};
  std::vector<std::string> names;
  if (!ros::param::getParamNames(names)) return;
  const std::string prefix = private_nh.getNamespace() + "/";
  for (const std::string& name : names) {
    if (name.compare(0, prefix.size(), prefix) != 0) continue;
    const std::string key = name.substr(prefix.size());
    bool known = false;
    for (const ParameterSpec& spec : parameter_specs()) known = known || key == spec.key;
    for (const char* node_key : node_keys) known = known || key == node_key;
    if (known) continue;
    std::vector<std::string> candidates = parameter_keys();
    candidates.insert(candidates.end(), std::begin(node_keys), std::end(node_keys));
    const std::string nearest = nearest_name(key, candidates);
    if (nearest.empty())
      ROS_WARN("spinning_top: ignoring unknown parameter %s", name.c_str());
    else
      ROS_WARN("spinning_top: ignoring unknown parameter %s (did you mean ~%s?)", name.c_str(), nearest.c_str());
  }
}

}  // namespace

NodeSettings read_node_settings(const ros::NodeHandle& nh) {
  NodeSettings s;
  s.rate = read_number(nh, "rate", s.rate);
  s.real_time_factor = read_number(nh, "real_time_factor", s.real_time_factor);
  validate_pacing(s.rate, s.real_time_factor);
  s.tick_budget = read_number(nh, "tick_budget", s.tick_budget);
  require(std::isfinite(s.tick_budget) && s.tick_budget >= 1e-4 && s.tick_budget <= 1.0, "tick_budget",
          "must lie in [1e-4, 1] s (the wall time one callback may integrate before the node serves "
          "services, parameter updates and SIGINT again)");
  s.publish_clock = read_bool(nh, "publish_clock", s.publish_clock);
  s.start_paused = read_bool(nh, "start_paused", s.start_paused);
  s.world_frame = read_string(nh, "world_frame", s.world_frame);
  s.body_frame = read_string(nh, "body_frame", s.body_frame);
  s.contact_frame = read_string(nh, "contact_frame", s.contact_frame);
  require_frame("world_frame", s.world_frame);
  require_frame("body_frame", s.body_frame);
  require_frame("contact_frame", s.contact_frame);
  require(s.body_frame != s.world_frame && s.contact_frame != s.world_frame && s.contact_frame != s.body_frame,
          "body_frame", "world_frame, body_frame and contact_frame must differ");
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
  return s;
}

SpinningTopNode::SpinningTopNode(ros::NodeHandle nh, ros::NodeHandle private_nh)
    : nh_(nh), private_nh_(private_nh) {
  // Everything is read and validated before anything is advertised.
  settings_ = read_node_settings(private_nh_);
  simulator_ = make_simulator(parse_scene_config(read_scene_parameters(private_nh_), /*require_all=*/false));
  warn_about_unknown_keys(private_nh_);
  paused_ = settings_.start_paused;
  // Under use_sim_time our own /clock is the time base and starts at the first tick (never
  // 0); otherwise stamps start at the wall time of the start, so that tf users on wall time
  // see current transforms at real_time_factor 1.
  stamp_origin_ = ros::Time::isSimTime() ? ros::Time(0, 0) : ros::Time::now();
  last_stamp_ = stamp_origin_;
  rebaseline_energy();

  // dynamic_reconfigure starts from what is on the parameter server: put the effective
  // values there (the scene's documented defaults included), so its first callback
  // changes nothing.
  const SceneConfig& config = simulator_->config();
  private_nh_.setParam("friction", config.top.friction);
  private_nh_.setParam("gravity", config.top.gravity);
  private_nh_.setParam("tolerance", config.integrator.tolerance);
  private_nh_.setParam("step", config.integrator.step);
  private_nh_.setParam("rate", settings_.rate);
  private_nh_.setParam("real_time_factor", settings_.real_time_factor);

  if (settings_.publish_clock) clock_publisher_ = nh_.advertise<rosgraph_msgs::Clock>("/clock", 10);
  contact_point_publisher_ = private_nh_.advertise<geometry_msgs::PointStamped>("contact_point", 100);
  normal_force_publisher_ = private_nh_.advertise<geometry_msgs::WrenchStamped>("normal_force", 100);
  marker_publisher_ = private_nh_.advertise<visualization_msgs::MarkerArray>("markers", 10);
  event_publisher_ = private_nh_.advertise<std_msgs::String>("event", 1, /*latch=*/true);
  tf_broadcaster_ = std::make_unique<tf2_ros::TransformBroadcaster>();

  reset_service_ = private_nh_.advertiseService("reset", &SpinningTopNode::on_reset, this);
  pause_service_ = private_nh_.advertiseService("pause", &SpinningTopNode::on_pause, this);
  resume_service_ = private_nh_.advertiseService("resume", &SpinningTopNode::on_resume, this);
  step_service_ = private_nh_.advertiseService("step", &SpinningTopNode::on_step, this);

  diagnostics_ = std::make_unique<diagnostic_updater::Updater>(nh_, private_nh_);
  diagnostics_->setHardwareID(std::string("spinning_top/") + to_string(config.scene));
  diagnostics_->add("simulation", this, &SpinningTopNode::diagnose);

  reconfigure_server_ = std::make_unique<dynamic_reconfigure::Server<SpinningTopConfig>>(private_nh_);
  reconfigure_server_->setCallback(
      [this](SpinningTopConfig& c, uint32_t level) { reconfigure(c, level); });

  window_wall_start_ = ros::WallTime::now();
  restart_timer();
  diagnostics_timer_ = nh_.createWallTimer(ros::WallDuration(1.0), &SpinningTopNode::on_diagnostics_timer, this);
  ROS_INFO("spinning_top: scene %s, integrator %s, %g Hz, real-time factor %g%s", to_string(config.scene),
           simulator_->integrator_description().c_str(), settings_.rate, settings_.real_time_factor,
           paused_ ? " (paused)" : "");
}

void SpinningTopNode::restart_timer() {
  const double period = settings_.real_time_factor > 0.0 ? 1.0 / (settings_.rate * settings_.real_time_factor)
                                                         : kAsFastAsPossibleSlice;
  ticks_per_marker_ = std::max(1L, std::lround(settings_.rate / settings_.marker_rate));
  if (timer_.isValid()) {
    timer_.setPeriod(ros::WallDuration(period));
  } else {
    timer_ = nh_.createWallTimer(ros::WallDuration(period), &SpinningTopNode::on_timer, this);
  }
}

void SpinningTopNode::on_timer(const ros::WallTimerEvent& event) {
  if (paused_) return;
  if (settings_.real_time_factor == 0.0) {
    // As fast as possible: ticks back to back for one slice, then back to the callback
    // queue so that services and dynamic_reconfigure are served.
    const ros::WallTime start = ros::WallTime::now();
    const ros::WallTime deadline = start + ros::WallDuration(std::min(kAsFastAsPossibleSlice, settings_.tick_budget));
    ros::WallTime now = start;
    while (!paused_ && now < deadline) {
      const bool finished = tick(deadline);
      const ros::WallTime end = ros::WallTime::now();
      const double cost = (end - now).toSec();
      tick_cost_sum_ += cost;
      tick_cost_max_ = std::max(tick_cost_max_, cost);
      now = end;
      if (!finished) break;
      ++ticks_in_window_;
    }
    return;
  }
  // An overrun: this tick started more than a whole period after its slot (the previous
  // one, or the machine, could not keep up). The timer then drops the missed slots, so the
  // achieved real-time factor falls below the requested one; simulated time per tick stays 1/rate.
  const double period = 1.0 / (settings_.rate * settings_.real_time_factor);
  if ((event.current_real - event.current_expected).toSec() > period) ++overruns_;
  const ros::WallTime start = ros::WallTime::now();
  const bool finished = tick(start + ros::WallDuration(settings_.tick_budget));
  const double cost = (ros::WallTime::now() - start).toSec();
  tick_cost_sum_ += cost;
  tick_cost_max_ = std::max(tick_cost_max_, cost);
  if (finished) ++ticks_in_window_;
}

WorkBudget SpinningTopNode::budget_until(ros::WallTime deadline) {
  const double remaining = std::max(0.0, (deadline - ros::WallTime::now()).toSec());
  return WorkBudget::until(WorkBudget::Clock::now() +
                           std::chrono::duration_cast<WorkBudget::Clock::duration>(std::chrono::duration<double>(remaining)));
}

bool SpinningTopNode::tick(ros::WallTime deadline) {
  if (!tick_unfinished_) {
    ++ticks_since_anchor_;
    ++tick_count_;
    const double previous_target = target_time_;
    target_time_ = anchor_time_ + static_cast<double>(ticks_since_anchor_) / settings_.rate;
    sim_time_in_window_ += target_time_ - previous_target;
  }
  if (simulator_->event() == Event::kNone) {
    const Event event = simulator_->advance_to(target_time_, budget_until(deadline));
    tick_unfinished_ = event == Event::kNone && simulator_->time() < target_time_;
    if (tick_unfinished_) {
      // Out of budget: the physics needs more work per tick than the budget allows (a tiny
      // step, a very fast motion). Back to the callback queue (services, parameter updates and
      // SIGINT are served); the next callback goes on with the same tick.
      ++budget_exhaustions_;
      ROS_ERROR_THROTTLE(5.0,
                         "spinning_top: a tick needs more than its %g s work budget (~tick_budget): at t = %.9g s "
                         "of %.9g s, %s; the simulation runs slower than requested",
                         settings_.tick_budget, simulator_->time(), target_time_,
                         simulator_->integrator_description().c_str());
      return false;
    }
    if (event != Event::kNone) handle_event(event);
  }
  const ros::Time stamp = stamp_origin_ + ros::Duration(target_time_);
  if (stamp <= last_stamp_) return true;  // never twice the same stamp (tf2 TF_REPEATED_DATA)
  last_stamp_ = stamp;
  const Snapshot snapshot = simulator_->snapshot();
  if (!finite(snapshot)) {  // the core promises this never happens; never pass it on
    ROS_ERROR_ONCE("spinning_top: non-finite state at t = %.9g s not published", snapshot.time);
    return true;
  }
  publish(snapshot, stamp);
  return true;
}

void SpinningTopNode::publish(const Snapshot& s, const ros::Time& stamp) {
  const ModelOutputs& out = s.outputs;
  if (settings_.publish_clock) {
    rosgraph_msgs::Clock clock;
    clock.clock = stamp;
    clock_publisher_.publish(clock);
  }

  std::vector<geometry_msgs::TransformStamped> transforms(2);
  geometry_msgs::TransformStamped& body = transforms[0];
  body.header.stamp = stamp;
  body.header.frame_id = settings_.world_frame;
  body.child_frame_id = settings_.body_frame;
  body.transform.translation.x = out.center_of_mass.x();
  body.transform.translation.y = out.center_of_mass.y();
  body.transform.translation.z = out.center_of_mass.z();
  body.transform.rotation.w = s.attitude.w();
  body.transform.rotation.x = s.attitude.x();
  body.transform.rotation.y = s.attitude.y();
  body.transform.rotation.z = s.attitude.z();
  // The contact frame: at the tip, axes parallel to the world's, so that the floor force
  // (in world components) is drawn by rviz where it acts.
  geometry_msgs::TransformStamped& contact = transforms[1];
  contact.header = body.header;
  contact.child_frame_id = settings_.contact_frame;
  contact.transform.translation.x = out.contact_point.x();
  contact.transform.translation.y = out.contact_point.y();
  contact.transform.translation.z = out.contact_point.z();
  contact.transform.rotation.w = 1.0;
  tf_broadcaster_->sendTransform(transforms);

  geometry_msgs::PointStamped point;
  point.header = body.header;
  point.point = to_point(out.contact_point);
  contact_point_publisher_.publish(point);

  geometry_msgs::WrenchStamped wrench;
  wrench.header.stamp = stamp;
  wrench.header.frame_id = settings_.contact_frame;
  wrench.wrench.force.x = out.contact_force.x();  // pivot reaction or friction; 0 when frictionless
  wrench.wrench.force.y = out.contact_force.y();
  wrench.wrench.force.z = out.normal_force;
  normal_force_publisher_.publish(wrench);  // torque about the tip: 0 (a point contact)

  if (settings_.trace_length > 0 &&
      (trace_.empty() || (trace_.back() - out.contact_point).norm() >= settings_.trace_resolution)) {
    trace_.push_back(out.contact_point);
    while (static_cast<int>(trace_.size()) > settings_.trace_length) trace_.pop_front();
  }
  if (tick_count_ % ticks_per_marker_ == 0) publish_markers(s, stamp);
}

void SpinningTopNode::publish_markers(const Snapshot& s, const ros::Time& stamp) {
  const ModelOutputs& out = s.outputs;
  const TopParameters& top = simulator_->config().top;
  const BodyShape shape = body_shape(top);
  visualization_msgs::MarkerArray array;

  // The body: the cone from the tip (z = -h in the body frame) to its base, in coloured
  // sectors so that the spin is visible; frame-locked, so rviz moves it with the tf.
  visualization_msgs::Marker body;
  body.header.stamp = stamp;
  body.header.frame_id = settings_.body_frame;
  body.frame_locked = true;
  body.ns = "body";
  body.id = 0;
  body.type = visualization_msgs::Marker::TRIANGLE_LIST;
  body.action = visualization_msgs::Marker::ADD;
  body.pose.orientation.w = 1.0;
  body.scale.x = body.scale.y = body.scale.z = 1.0;
  body.color = color(1.0f, 1.0f, 1.0f);
  const int sectors = 48;
  const double base_z = shape.height - top.tip_distance;
  const Vector3 apex(0.0, 0.0, -top.tip_distance), centre(0.0, 0.0, base_z);
  auto rim = [&](int i) {
    const double angle = 2.0 * M_PI * i / sectors;
    return Vector3(shape.radius * std::cos(angle), shape.radius * std::sin(angle), base_z);
  };
  for (int i = 0; i < sectors; ++i) {
    const std_msgs::ColorRGBA c = (i / 4) % 2 == 0 ? color(0.9f, 0.35f, 0.1f, 0.7f) : color(0.95f, 0.85f, 0.6f, 0.7f);
    // Both windings of every triangle: rviz culls back faces.
    for (const Vector3& v : {apex, rim(i), rim(i + 1), apex, rim(i + 1), rim(i), centre, rim(i + 1), rim(i),
                             centre, rim(i), rim(i + 1)}) {
      body.points.push_back(to_point(v));
      body.colors.push_back(c);
    }
  }
  array.markers.push_back(body);
  // A short handle on top, as on a toy top.
  visualization_msgs::Marker handle = body;
  handle.id = 1;
  handle.type = visualization_msgs::Marker::CYLINDER;
  handle.points.clear();
  handle.colors.clear();
  handle.scale.x = handle.scale.y = 0.15 * shape.radius;
  handle.scale.z = 0.4 * shape.height;
  handle.pose.position.z = base_z + 0.5 * handle.scale.z;
  handle.color = color(0.3f, 0.3f, 0.35f);
  array.markers.push_back(handle);

  // The tip's trace on the floor (world frame, bounded).
  visualization_msgs::Marker trace;
  trace.header.stamp = stamp;
  trace.header.frame_id = settings_.world_frame;
  trace.ns = "trace";
  trace.id = 0;
  trace.type = visualization_msgs::Marker::LINE_STRIP;
  trace.action = visualization_msgs::Marker::ADD;
  trace.pose.orientation.w = 1.0;
  trace.scale.x = 0.0005;  // line width [m]
  trace.color = color(0.1f, 0.5f, 0.9f);
  for (const Vector3& p : trace_) trace.points.push_back(to_point(p));
  trace.points.push_back(to_point(out.contact_point));
  if (trace.points.size() < 2) trace.points.push_back(trace.points.back());
  array.markers.push_back(trace);

  // The floor's force on the tip, from the tip (world frame, force_scale m/N).
  visualization_msgs::Marker arrow = trace;
  arrow.ns = "force";
  arrow.type = visualization_msgs::Marker::ARROW;
  arrow.points.clear();
  const Vector3 force(out.contact_force.x(), out.contact_force.y(), out.normal_force);
  arrow.points.push_back(to_point(out.contact_point));
  arrow.points.push_back(to_point(out.contact_point + settings_.force_scale * force));
  arrow.scale.x = 0.002;  // shaft diameter
  arrow.scale.y = 0.004;  // head diameter
  arrow.scale.z = 0.006;  // head length
  arrow.color = color(0.2f, 0.8f, 0.2f);
  array.markers.push_back(arrow);

  marker_publisher_.publish(array);
}

void SpinningTopNode::handle_event(Event event) {
  reported_event_ = event;
  event_time_ = simulator_->time();
  ROS_ERROR("spinning_top: %s at t = %.9g s (simulated): integration stopped; the last valid pose is "
            "kept. Call ~reset to start again.",
            to_string(event), event_time_);
  std_msgs::String message;
  message.data = to_string(event);
  event_publisher_.publish(message);
  if (diagnostics_) diagnostics_->force_update();
}

void SpinningTopNode::rebaseline_energy() {
  const ModelOutputs out = simulator_->snapshot().outputs;
  energy_baseline_ = out.energy + out.dissipated_energy;
}

void SpinningTopNode::on_diagnostics_timer(const ros::WallTimerEvent&) { diagnostics_->force_update(); }

void SpinningTopNode::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
  using diagnostic_msgs::DiagnosticStatus;
  const Snapshot s = simulator_->snapshot();
  const ModelOutputs& out = s.outputs;
  const TopParameters& top = simulator_->config().top;

  // Energy balance E + W - E0 (W: work done against friction; 0 without friction).
  const double drift = (out.energy + out.dissipated_energy - energy_baseline_) /
                       std::max(std::abs(energy_baseline_), 1e-300);
  const double norm_error = std::abs(s.attitude.norm() - 1.0);
  // Contact constraint z_G = h e_Zz (PHYSICS.md), and the pivot at the origin (fixed tip).
  const Vector3 axis = s.attitude * Vector3::UnitZ();
  double constraint = std::abs(out.center_of_mass.z() - top.tip_distance * axis.z());
  constraint = std::max(constraint, std::abs(out.contact_point.z()));
  if (simulator_->config().scene == SceneType::kFixedTip)
    constraint = std::max(constraint, out.contact_point.head<2>().norm());

  const ros::WallTime now = ros::WallTime::now();
  const double wall = (now - window_wall_start_).toSec();
  const double achieved_rtf = wall > 0.0 ? sim_time_in_window_ / wall : 0.0;
  const double mean_cost = ticks_in_window_ > 0 ? tick_cost_sum_ / ticks_in_window_ : 0.0;
  const long overruns_in_window = overruns_ - overruns_at_window_start_;
  const long exhaustions_in_window = budget_exhaustions_ - budget_exhaustions_at_window_start_;

  status.summary(DiagnosticStatus::OK, paused_ ? "paused" : "running");
  if (overruns_in_window > 0)
    status.mergeSummaryf(DiagnosticStatus::WARN, "%ld overruns in the last %.1f s", overruns_in_window, wall);
  if (exhaustions_in_window > 0)
    status.mergeSummaryf(DiagnosticStatus::ERROR, "ticks ran out of their %g s work budget %ld times in the last %.1f s",
                         settings_.tick_budget, exhaustions_in_window, wall);
  if (std::abs(drift) > settings_.energy_drift_error)
    status.mergeSummaryf(DiagnosticStatus::ERROR, "energy drift %.3g", drift);
  else if (std::abs(drift) > settings_.energy_drift_warning)
    status.mergeSummaryf(DiagnosticStatus::WARN, "energy drift %.3g", drift);
  if (norm_error > settings_.quaternion_norm_error)
    status.mergeSummaryf(DiagnosticStatus::ERROR, "quaternion norm off by %.3g", norm_error);
  if (constraint > settings_.constraint_error)
    status.mergeSummaryf(DiagnosticStatus::ERROR, "contact constraint residual %.3g m", constraint);
  if (reported_event_ != Event::kNone)
    status.mergeSummaryf(DiagnosticStatus::ERROR, "event %s at t = %.9g s", to_string(reported_event_), event_time_);

  status.add("scene", to_string(simulator_->config().scene));
  // What runs and why (auto: its choice, and exact's refusal where it fell back).
  const IntegratorChoice choice = simulator_->integrator_choice();
  status.add("integrator", simulator_->integrator_description());
  status.add("integrator method", to_string(choice.method));
  if (choice.fallback) status.add("integrator fallback reason", choice.reason);
  status.add("integrator steps since reset", simulator_->steps());
  status.addf("simulated time [s]", "%.9g", s.time);
  status.add("event", reported_event_ == Event::kNone ? "none" : to_string(reported_event_));
  if (reported_event_ != Event::kNone) status.addf("event time [s]", "%.9g", event_time_);
  status.addf("energy [J]", "%.12g", out.energy);
  status.addf("dissipated energy [J]", "%.12g", out.dissipated_energy);
  status.addf("energy balance (E + W - E0) / |E0|", "%.3g", drift);
  status.addf("quaternion norm error", "%.3g", norm_error);
  status.addf("constraint residual [m]", "%.3g", constraint);
  status.addf("normal force [N]", "%.9g", out.normal_force);
  status.addf("rate [Hz]", "%g", settings_.rate);
  status.addf("requested real-time factor", "%g", settings_.real_time_factor);
  status.addf("achieved real-time factor", "%.3f", achieved_rtf);
  status.add("overruns (total)", overruns_);
  status.add("overruns (window)", overruns_in_window);
  status.addf("tick budget [s]", "%g", settings_.tick_budget);
  status.add("ticks out of budget (total)", budget_exhaustions_);
  status.add("ticks out of budget (window)", exhaustions_in_window);
  status.addf("tick cost mean [us]", "%.1f", 1e6 * mean_cost);
  status.addf("tick cost max [us]", "%.1f", 1e6 * tick_cost_max_);
  status.add("ticks (window)", ticks_in_window_);

  window_wall_start_ = now;
  sim_time_in_window_ = 0.0;
  ticks_in_window_ = 0;
  tick_cost_sum_ = tick_cost_max_ = 0.0;
  overruns_at_window_start_ = overruns_;
  budget_exhaustions_at_window_start_ = budget_exhaustions_;
}

void SpinningTopNode::reconfigure(SpinningTopConfig& config, uint32_t /*level*/) {
  if (!reconfigure_initialized_) applied_config_ = config;  // the values we put on the server
  reconfigure_initialized_ = true;
  auto refuse = [&](const std::string& why) {
    ROS_ERROR("spinning_top: dynamic_reconfigure update refused: %s. The previous configuration stays.",
              why.c_str());
    config = applied_config_;  // sent back to the client as the current configuration
  };
  try {
    validate_pacing(config.rate, config.real_time_factor);
  } catch (const InvalidParameter& error) {
    return refuse(error.what());
  }

  TopParameters top = simulator_->config().top;
  IntegratorSettings integrator = simulator_->config().integrator;
  top.friction = config.friction;
  top.gravity = config.gravity;
  integrator.tolerance = config.tolerance;
  integrator.step = config.step;
  const TopParameters& old_top = simulator_->config().top;
  const IntegratorSettings& old_integrator = simulator_->config().integrator;
  const bool physics_changed = top.friction != old_top.friction || top.gravity != old_top.gravity ||
                               integrator.tolerance != old_integrator.tolerance ||
                               integrator.step != old_integrator.step;
  if (physics_changed) {
    bool switched = false;
    try {
      switched = simulator_->update(top, integrator);  // validates; changes nothing if it throws
    } catch (const InvalidParameter& error) {
      return refuse(error.what());
    }
    rebaseline_energy();
    // auto chose again for the current state (exact may refuse it now, or accept it again).
    if (switched)
      ROS_WARN("spinning_top: the update switched the integrator at t = %.9g s: now %s", simulator_->time(),
               simulator_->integrator_description().c_str());
  }
  if (config.rate != settings_.rate || config.real_time_factor != settings_.real_time_factor) {
    // Re-anchor so that the next tick is exactly one new period after the last one.
    anchor_time_ = target_time_;
    ticks_since_anchor_ = 0;
    settings_.rate = config.rate;
    settings_.real_time_factor = config.real_time_factor;
    restart_timer();
  }
  applied_config_ = config;
  ROS_INFO("spinning_top: configuration: k %g N s/m, g %g m/s^2, %s, %g Hz, real-time factor %g", config.friction,
           config.gravity, simulator_->integrator_description().c_str(), config.rate, config.real_time_factor);
}

bool SpinningTopNode::on_reset(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response) {
  if (simulator_->reset())  // auto chose again for the initial state
    ROS_WARN("spinning_top: the reset switched the integrator: now %s", simulator_->integrator_description().c_str());
  // Simulated time restarts at 0, stamps do not: the origin moves to the last stamp, so
  // tf2 listeners see time go on (no jump back, no dropped buffers).
  stamp_origin_ = last_stamp_;
  anchor_time_ = target_time_ = 0.0;
  ticks_since_anchor_ = 0;
  tick_unfinished_ = false;
  trace_.clear();
  if (reported_event_ != Event::kNone) {
    std_msgs::String cleared;  // "": no event (the core's spelling of none)
    event_publisher_.publish(cleared);
  }
  reported_event_ = Event::kNone;
  rebaseline_energy();
  response.success = true;
  response.message = "reset to the initial state; simulated time 0 is stamped " +
                     format("%.9f", (stamp_origin_).toSec()) + (paused_ ? " (still paused)" : "");
  ROS_INFO("spinning_top: %s", response.message.c_str());
  return true;
}

bool SpinningTopNode::on_pause(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response) {
  response.success = true;
  response.message = paused_ ? "already paused" : format("paused at t = %.9g s", target_time_);
  paused_ = true;
  return true;
}

bool SpinningTopNode::on_resume(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response) {
  response.success = true;
  response.message = paused_ ? format("resumed at t = %.9g s", target_time_) : "already running";
  paused_ = false;
  return true;
}

bool SpinningTopNode::on_step(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response) {
  if (!paused_) {
    response.success = false;
    response.message = "~step advances one tick while paused: call ~pause first";
    return true;
  }
  if (!tick(ros::WallTime::now() + ros::WallDuration(settings_.tick_budget))) {
    response.success = false;
    response.message = format("the tick needs more than its ~tick_budget of %g s", settings_.tick_budget) +
                       format(": integrated to t = %.9g s", simulator_->time()) +
                       format(" of %.9g s; call ~step again to go on", target_time_);
    return true;
  }
  response.success = true;
  response.message = format("stepped to t = %.9g s", target_time_);
  return true;
}

}  // namespace ros_front_end
}  // namespace spinning_top
