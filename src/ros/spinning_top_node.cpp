#include "spinning_top/ros/spinning_top_node.hpp"

#include <rosgraph_msgs/Clock.h>
#include <std_msgs/String.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "spinning_top/ros/live_keys.hpp"
#include "spinning_top/ros/ros_parameters.hpp"
#include "spinning_top/scene_file.hpp"

namespace spinning_top {
namespace ros_front_end {
namespace {

constexpr double kAsFastAsPossibleSlice = 1e-3;  // [s] wall time per timer callback when rtf = 0

std::string format(const char* pattern, double value) {
  char buffer[160];
  std::snprintf(buffer, sizeof buffer, pattern, value);
  return buffer;
}

/// The core's budget for a wall-time deadline.
WorkBudget budget_until(ros::WallTime deadline) {
  const double remaining = std::max(0.0, (deadline - ros::WallTime::now()).toSec());
  return WorkBudget::until(WorkBudget::Clock::now() +
                           std::chrono::duration_cast<WorkBudget::Clock::duration>(std::chrono::duration<double>(remaining)));
}

long ticks_per(double rate, double publication_rate) {
  return publication_rate > 0.0 ? std::max(1L, std::lround(rate / publication_rate)) : 1L;
}

/// Keys of our private namespace that nobody reads (typos such as ~mas): warned about, not
/// fatal, since other tools may store things there.
void warn_about_unknown_keys(const ros::NodeHandle& private_nh, const std::vector<std::string>& top_names) {
  std::vector<std::string> known = parameter_keys();
  for (const std::string& key : node_setting_keys()) known.push_back(key);
  for (const LiveKey& key : live_keys()) known.push_back(key.name);  // e.g. spin (the scene's: initial/spin)
  known.push_back("robot_description");  // the node writes it (a URDF of the top)
  for (const std::string& name : top_names) {
    for (const std::string& key : parameter_keys()) known.push_back(name + "/" + key);
    known.push_back(name + "/x");
    known.push_back(name + "/y");
    known.push_back(name + "/robot_description");
  }
  std::vector<std::string> names;
  if (!ros::param::getParamNames(names)) return;
  const std::string prefix = private_nh.getNamespace() + "/";
  for (const std::string& name : names) {
    if (name.compare(0, prefix.size(), prefix) != 0) continue;
    const std::string key = name.substr(prefix.size());
    if (std::find(known.begin(), known.end(), key) != known.end()) continue;
    const std::string nearest = nearest_name(key, known);
    if (nearest.empty())
      ROS_WARN("spinning_top: ignoring unknown parameter %s", name.c_str());
    else
      ROS_WARN("spinning_top: ignoring unknown parameter %s (did you mean ~%s?)", name.c_str(), nearest.c_str());
  }
}

/// The first changed live key that a top keeps (what a refusal of the change names).
std::string first_changed_key(const SpinningTopConfig& config, const SpinningTopConfig& old) {
  for (const LiveKey& key : live_keys())
    if (key.in_top != nullptr && config.*key.field != old.*key.field) return key.name;
  return "gravity";
}

/// The reason of an InvalidParameter without its "key: " prefix.
std::string reason_of(const InvalidParameter& error) {
  const std::string what = error.what();
  const std::size_t skip = error.parameter().size() + 2;
  return what.size() >= skip ? what.substr(skip) : what;
}

}  // namespace

SpinningTopNode::SpinningTopNode(ros::NodeHandle nh, ros::NodeHandle private_nh)
    : nh_(nh), private_nh_(private_nh), settings_(read_node_settings(private_nh)),
      clock_(settings_.rate, settings_.real_time_factor) {
  // Everything is read and validated before anything is advertised (a TopInstance validates its
  // configuration before it advertises).
  const std::vector<std::pair<std::string, SceneConfig>> configs = read_tops();
  std::vector<Eigen::Vector2d> positions;
  for (const auto& named : configs) positions.push_back(read_tip_position(named.first));
  warn_about_unknown_keys(private_nh_, settings_.tops);
  paused_ = settings_.start_paused;
  waiting_for_subscriber_ = settings_.wait_for_subscriber;
  // Under use_sim_time our own /clock is the time base and starts at the first tick (never
  // 0); otherwise stamps start at the wall time of the start, so that tf users on wall time
  // see current transforms at real_time_factor 1.
  stamp_origin_ = ros::Time::isSimTime() ? ros::Time(0, 0) : ros::Time::now();
  last_stamp_ = stamp_origin_;

  // dynamic_reconfigure starts from what is on the parameter server: put the effective
  // values there (the scene's documented defaults included), so its first callback
  // changes nothing. With several tops, the first one's.
  SceneConfig first = configs.front().second;
  for (const LiveKey& key : live_keys())
    private_nh_.setParam(key.name, key.in_top != nullptr ? *key.in_top(first) : *key.in_node(settings_));

  // A /clock subscriber (every sim-time node) may fall behind by a few callbacks at 1 kHz.
  if (settings_.publish_clock) clock_publisher_ = nh_.advertise<rosgraph_msgs::Clock>("/clock", 100);
  status_publisher_ = private_nh_.advertise<std_msgs::String>("status", 1, /*latch=*/true);
  tf_broadcaster_ = std::make_unique<tf2_ros::TransformBroadcaster>();
  diagnostics_ = std::make_unique<diagnostic_updater::Updater>(nh_, private_nh_);
  diagnostics_->setHardwareID("spinning_top/" + std::string(to_string(first.scene)));
  diagnostics_->add("simulation", this, &SpinningTopNode::diagnose);

  for (std::size_t i = 0; i < configs.size(); ++i)
    add_top(std::make_unique<TopInstance>(configs[i].first, configs[i].second, positions[i], settings_, private_nh_,
                                          clock_.time(), stamp_of()));

  reset_service_ = private_nh_.advertiseService("reset", &SpinningTopNode::on_reset, this);
  reload_service_ = private_nh_.advertiseService("reload", &SpinningTopNode::on_reload, this);
  pause_service_ = private_nh_.advertiseService("pause", &SpinningTopNode::on_pause, this);
  resume_service_ = private_nh_.advertiseService("resume", &SpinningTopNode::on_resume, this);
  step_service_ = private_nh_.advertiseService("step", &SpinningTopNode::on_step, this);
  spawn_service_ = private_nh_.advertiseService("spawn", &SpinningTopNode::on_spawn, this);
  kill_service_ = private_nh_.advertiseService("kill", &SpinningTopNode::on_kill, this);
  set_state_service_ = private_nh_.advertiseService("set_state", &SpinningTopNode::on_set_state, this);

  reconfigure_server_ = std::make_unique<dynamic_reconfigure::Server<SpinningTopConfig>>(private_nh_);
  reconfigure_server_->setCallback([this](SpinningTopConfig& c, uint32_t level) { reconfigure(c, level); });

  // The pacing and the wall-clock stamps start together, after the set-up above (advertising
  // and the reconfigure server take tens of ms): tick n is due at the wall time it is stamped.
  window_wall_start_ = ros::WallTime::now();
  clock_.anchor(window_wall_start_.toSec());
  if (!ros::Time::isSimTime()) last_stamp_ = stamp_origin_ = ros::Time(window_wall_start_.sec, window_wall_start_.nsec);
  restart_timer();
  diagnostics_timer_ = nh_.createWallTimer(ros::WallDuration(1.0), &SpinningTopNode::on_diagnostics_timer, this);
  for (const auto& top : tops_)
    ROS_INFO("spinning_top: %s%sscene %s, integrator %s", top->name().c_str(), top->name().empty() ? "" : ": ",
             to_string(top->simulator().config().scene), top->simulator().integrator_description().c_str());
  ROS_INFO("spinning_top: %zu top%s, %g Hz, real-time factor %g%s", tops_.size(), tops_.size() == 1 ? "" : "s",
           settings_.rate, settings_.real_time_factor, paused_ ? " (paused)" : "");
}

std::vector<std::pair<std::string, SceneConfig>> SpinningTopNode::read_tops() const {
  const ParameterMap own = read_scene_parameters(private_nh_);
  std::vector<std::pair<std::string, SceneConfig>> configs;
  if (settings_.tops.empty()) {
    configs.emplace_back("", parse_scene_config(own, /*require_all=*/false));
    return configs;
  }
  for (const std::string& name : settings_.tops) {
    ParameterMap keys = own;  // ~<name>/key over ~key
    try {
      for (const auto& [key, value] : read_scene_parameters(ros::NodeHandle(private_nh_, name))) keys[key] = value;
      configs.emplace_back(name, parse_scene_config(keys, /*require_all=*/false));
    } catch (const InvalidParameter& error) {
      throw InvalidParameter(name + "/" + error.parameter(), reason_of(error));
    }
  }
  return configs;
}

Eigen::Vector2d SpinningTopNode::read_tip_position(const std::string& name) const {
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();
  if (name.empty()) return xy;  // the node's own top starts at the origin
  const ros::NodeHandle top_nh(private_nh_, name);
  const char* const keys[] = {"x", "y"};
  for (int i = 0; i < 2; ++i) {
    const std::string key = name + "/" + keys[i];
    try {
      xy[i] = read_number(top_nh, keys[i], 0.0);
    } catch (const InvalidParameter& error) {
      throw InvalidParameter(key, reason_of(error));
    }
    if (!(std::abs(xy[i]) <= 1e6)) throw InvalidParameter(key, "must be finite and within 1e6 m of the origin");
  }
  return xy;
}

void SpinningTopNode::add_top(std::unique_ptr<TopInstance> top) {
  TopInstance* added = top.get();
  tops_.push_back(std::move(top));
  if (!added->name().empty()) {
    diagnostics_->add(added->name(), [added](diagnostic_updater::DiagnosticStatusWrapper& status) {
      status.summary(diagnostic_msgs::DiagnosticStatus::OK, "running");
      added->diagnose(status);
    });
    const std::string name = added->name();
    boost::function<bool(std_srvs::Trigger::Request&, std_srvs::Trigger::Response&)> reset =
        [this, name](std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response) {
          TopInstance* top = find_top(name);
          if (top == nullptr) return false;
          top->reset(clock_.time());
          send_static_transforms();
          response.success = true;
          response.message = "top " + name + " reset to its start; its simulated time 0 is stamped " +
                             format("%.9f", (stamp_origin_ + ros::Duration(clock_.time())).toSec());
          return true;
        };
    top_reset_services_.push_back(private_nh_.advertiseService(name + "/reset", reset));
  }
  send_static_transforms();
}

TopInstance* SpinningTopNode::find_top(const std::string& name) {
  for (const auto& top : tops_)
    if (top->name() == name) return top.get();
  return nullptr;
}

void SpinningTopNode::send_static_transforms() {
  std::vector<geometry_msgs::TransformStamped> transforms;
  for (const auto& top : tops_)
    if (top->contact_is_static()) transforms.push_back(top->contact_transform(last_stamp_));
  // A fresh broadcaster: tf2_ros's keeps every frame it was ever sent in its latched message, so
  // a killed top's pivot would reach later subscribers (tf2 cannot remove a static frame from
  // a listener that already has it).
  if (transforms.empty() && !static_sent_) return;  // nothing static, now or before
  auto broadcaster = std::make_unique<tf2_ros::StaticTransformBroadcaster>();
  broadcaster->sendTransform(transforms);
  static_broadcaster_ = std::move(broadcaster);
  static_sent_ = true;
}

void SpinningTopNode::restart_timer() {
  const double period = settings_.real_time_factor > 0.0 ? 1.0 / (settings_.rate * settings_.real_time_factor)
                                                         : kAsFastAsPossibleSlice;
  ticks_per_marker_ = ticks_per(settings_.rate, settings_.marker_rate);
  ticks_per_clock_ = ticks_per(settings_.rate, settings_.clock_rate);
  ticks_per_tf_ = ticks_per(settings_.rate, settings_.tf_rate);
  if (timer_.isValid()) {
    timer_.setPeriod(ros::WallDuration(period));
  } else {
    timer_ = nh_.createWallTimer(ros::WallDuration(period), &SpinningTopNode::on_timer, this);
  }
}

void SpinningTopNode::on_timer(const ros::WallTimerEvent&) {
  if (paused_) return;
  const ros::WallTime start = ros::WallTime::now();
  if (waiting_for_subscriber_) {
    const bool clock_heard = !settings_.publish_clock || clock_publisher_.getNumSubscribers() > 0;
    if (!clock_heard || tops_.empty() || !tops_.front()->subscribed()) return;
    // The first subscriber is there: pacing (and wall-clock stamps) start now, at tick 1.
    waiting_for_subscriber_ = false;
    clock_.anchor(start.toSec());
    if (!ros::Time::isSimTime()) last_stamp_ = stamp_origin_ = ros::Time(start.sec, start.nsec);
    ROS_INFO("spinning_top: a subscriber is there; the simulation starts");
  }
  // As fast as possible (factor 0): ticks back to back for one slice, then back to the callback
  // queue so that services and dynamic_reconfigure are served.
  // Real-time pacing: every tick whose slot has come is taken, late ones too (a busy machine
  // delayed the timer), within this callback's work budget; the simulated time thus keeps up
  // with the wall clock. Beyond ~max_lag the overload is given up (reported), and with wall-
  // clock stamps their origin moves on by what was given up, so stamps stay near the wall clock.
  const bool paced = settings_.real_time_factor > 0.0;
  const long given_up = paced ? clock_.give_up_beyond(start.toSec(), settings_.max_lag) : 0;
  if (given_up > 0) {
    given_up_ticks_ += given_up;
    if (!ros::Time::isSimTime()) stamp_origin_ += ros::Duration(static_cast<double>(given_up) / settings_.rate);
    ROS_WARN_THROTTLE(5.0, "spinning_top: more than ~max_lag = %g s behind the wall clock: %ld ticks given up "
                           "(the machine cannot keep up with %g Hz at real-time factor %g)",
                      settings_.max_lag, given_up, settings_.rate, settings_.real_time_factor);
  }
  const ros::WallTime deadline =
      start + ros::WallDuration(paced ? settings_.tick_budget : std::min(kAsFastAsPossibleSlice, settings_.tick_budget));
  ros::WallTime now = start;
  while (!paused_ && now < deadline) {
    if (paced && !tick_unfinished_) {
      const long due = clock_.due(now.toSec());
      if (due == 0) break;
      if (due > 1) ++late_ticks_;
    }
    const bool finished = tick(deadline);
    const ros::WallTime end = ros::WallTime::now();
    tick_cost_sum_ += (end - now).toSec();
    tick_cost_max_ = std::max(tick_cost_max_, (end - now).toSec());
    now = end;
    if (!finished) break;
    ++ticks_in_window_;
  }
  if (paced) last_lag_ = clock_.lag(now.toSec());
}

bool SpinningTopNode::tick(ros::WallTime deadline) {
  if (!tick_unfinished_) {
    clock_.take();
    sim_time_in_window_ += 1.0 / settings_.rate;
  }
  const double world_time = clock_.time();
  const WorkBudget budget = budget_until(deadline);
  long events_before = 0, events_after = 0;
  bool finished = true;
  for (const auto& top : tops_) {
    events_before += top->event() != Event::kNone;
    finished = top->advance(world_time, budget) && finished;
    events_after += top->event() != Event::kNone;
  }
  tick_unfinished_ = !finished;
  if (tick_unfinished_) {
    // Out of budget: the physics needs more work per tick than the budget allows (a tiny
    // step, a very fast motion). Back to the callback queue (services, parameter updates and
    // SIGINT are served); the next callback goes on with the same tick.
    ++budget_exhaustions_;
    ROS_ERROR_THROTTLE(5.0,
                       "spinning_top: a tick needs more than its %g s work budget (~tick_budget): at t = %.9g s; "
                       "the simulation runs slower than requested",
                       settings_.tick_budget, world_time);
    return false;
  }
  if (events_after != events_before && diagnostics_) diagnostics_->force_update();
  const ros::Time stamp = stamp_origin_ + ros::Duration(world_time);
  if (stamp <= last_stamp_) return true;  // never twice the same stamp (tf2 TF_REPEATED_DATA)
  last_stamp_ = stamp;
  publish(stamp);
  return true;
}

void SpinningTopNode::publish(const ros::Time& stamp) {
  const long tick = clock_.ticks();
  if (settings_.publish_clock && tick % ticks_per_clock_ == 0) {
    rosgraph_msgs::Clock clock;
    clock.clock = stamp;
    clock_publisher_.publish(clock);
  }
  if (tick % ticks_per_tf_ == 0) {
    std::vector<geometry_msgs::TransformStamped> transforms;
    for (const auto& top : tops_) top->append_transforms(stamp, transforms);
    if (!transforms.empty()) tf_broadcaster_->sendTransform(transforms);  // none once every top is killed
  }
  const bool markers = tick % ticks_per_marker_ == 0;
  for (const auto& top : tops_) top->publish(stamp, markers);
}

void SpinningTopNode::report(const std::string& status) {
  std_msgs::String message;
  message.data = status;
  status_publisher_.publish(message);
}

void SpinningTopNode::on_diagnostics_timer(const ros::WallTimerEvent&) { diagnostics_->force_update(); }

void SpinningTopNode::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
  using diagnostic_msgs::DiagnosticStatus;
  const ros::WallTime now = ros::WallTime::now();
  const double wall = (now - window_wall_start_).toSec();
  const double achieved_rtf = wall > 0.0 ? sim_time_in_window_ / wall : 0.0;
  const double mean_cost = ticks_in_window_ > 0 ? tick_cost_sum_ / ticks_in_window_ : 0.0;
  const long late_in_window = late_ticks_ - late_ticks_at_window_start_;
  const long given_up_in_window = given_up_ticks_ - given_up_ticks_at_window_start_;
  const long exhaustions_in_window = budget_exhaustions_ - budget_exhaustions_at_window_start_;
  const double late_fraction = ticks_in_window_ > 0 ? static_cast<double>(late_in_window) / ticks_in_window_ : 0.0;
  const double requested = settings_.real_time_factor;

  status.summary(DiagnosticStatus::OK, paused_ ? "paused" : "running");
  // Pacing: a single late tick is normal on a shared machine (it is taken, late); a sustained
  // fraction of them, a real-time factor below the threshold or ticks given up are not.
  if (!paused_ && late_fraction > settings_.late_tick_warning)
    status.mergeSummaryf(DiagnosticStatus::WARN, "%.0f%% of the ticks late in the last %.1f s", 100.0 * late_fraction,
                         wall);
  if (!paused_ && requested > 0.0 && wall >= 0.5 && achieved_rtf < settings_.real_time_factor_warning * requested)
    status.mergeSummaryf(DiagnosticStatus::WARN, "real-time factor %.3f of %g requested", achieved_rtf, requested);
  if (given_up_in_window > 0)
    status.mergeSummaryf(DiagnosticStatus::WARN, "%ld ticks given up beyond ~max_lag = %g s", given_up_in_window,
                         settings_.max_lag);
  if (exhaustions_in_window > 0)
    status.mergeSummaryf(DiagnosticStatus::ERROR, "ticks ran out of their %g s work budget %ld times in the last %.1f s",
                         settings_.tick_budget, exhaustions_in_window, wall);
  // The node's own top reports here, as it always has; named tops have a status of their own.
  if (TopInstance* own = find_top("")) own->diagnose(status);
  status.add("tops", static_cast<int>(tops_.size()));
  status.addf("world time [s]", "%.9g", clock_.time());
  status.addf("rate [Hz]", "%g", settings_.rate);
  status.addf("requested real-time factor", "%g", requested);
  status.addf("achieved real-time factor", "%.3f", achieved_rtf);
  status.addf("lag behind the wall clock [s]", "%.6f", last_lag_);
  status.add("late ticks (total)", late_ticks_);
  status.add("late ticks (window)", late_in_window);
  status.add("ticks given up (total)", given_up_ticks_);
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
  late_ticks_at_window_start_ = late_ticks_;
  given_up_ticks_at_window_start_ = given_up_ticks_;
  budget_exhaustions_at_window_start_ = budget_exhaustions_;
}

void SpinningTopNode::reconfigure(SpinningTopConfig& config, uint32_t /*level*/) {
  if (!reconfigure_initialized_) applied_config_ = config;  // the values we put on the server
  reconfigure_initialized_ = true;
  auto refuse = [&](const std::string& why) {
    ROS_ERROR("spinning_top: dynamic_reconfigure update refused: %s. The previous configuration stays.",
              why.c_str());
    report("refused: " + why);
    config = applied_config_;  // sent back to the client as the current configuration
  };
  try {
    validate_pacing(config.rate, config.real_time_factor);
  } catch (const InvalidParameter& error) {
    return refuse(error.what());
  }
  const SpinningTopConfig& old = applied_config_;
  const std::uint32_t changed = changed_levels(config, old);
  const bool step_changed = (changed & (kModel | kIntegrator)) != 0;
  const bool body_changed = (changed & kBody) != 0;
  // Only what changed applies, to every top (tops spawned with another body keep theirs).
  if (step_changed || body_changed) {
    // Every top is checked before any changes, so that a refusal leaves all of them as they were.
    for (const auto& top : tops_) {
      // Its start with its current body and integrator, and the changes (the spin's included).
      SceneConfig candidate = top->start_config();
      candidate.top = top->simulator().config().top;
      candidate.integrator = top->simulator().config().integrator;
      candidate = with_changes(candidate, config, old);
      try {
        validate(candidate);
        if (body_changed && top->event() != Event::kNone)
          throw InvalidParameter(config.spin != old.spin ? "spin" : "mass",
                                 std::string("top '") + top->name() + "' stopped at its " + to_string(top->event()) +
                                     " event: reset it before changing its body");
        top->require_on_the_floor(first_changed_key(config, old));
      } catch (const InvalidParameter& error) {
        return refuse(std::string(error.what()) + (top->name().empty() ? "" : " (top " + top->name() + ")"));
      }
    }
    for (const auto& top : tops_) {
      try {
        const SceneConfig changed_config = with_changes(top->simulator().config(), config, old);
        const TopParameters& new_top = changed_config.top;
        const IntegratorSettings& new_integrator = changed_config.integrator;
        if (body_changed) {
          const double spin = config.spin != old.spin ? config.spin : top->snapshot().body_rates.z();
          top->update(top->simulator().config().top, new_integrator);
          top->change_body(new_top, spin);
        } else if (top->update(new_top, new_integrator)) {
          // auto chose again for the current state (exact may refuse it now, or accept it again).
          ROS_WARN("spinning_top: the update switched the integrator of %s at t = %.9g s: now %s",
                   top->name().empty() ? "the top" : top->name().c_str(), top->time(),
                   top->simulator().integrator_description().c_str());
        }
      } catch (const InvalidParameter& error) {
        // The state itself refused the new body (checked per top above only for the start).
        return refuse(std::string(error.what()) + (top->name().empty() ? "" : " (top " + top->name() + ")"));
      }
    }
    send_static_transforms();
  }
  bool pacing_changed = false;
  for (const LiveKey& key : live_keys()) {
    if (key.in_node == nullptr || *key.in_node(settings_) == config.*key.field) continue;
    *key.in_node(settings_) = config.*key.field;
    pacing_changed = true;
  }
  if (pacing_changed) {
    // Re-anchor so that the next tick is exactly one new period after the last one.
    clock_.set_pace(settings_.rate, settings_.real_time_factor, ros::WallTime::now().toSec());
    restart_timer();
  }
  applied_config_ = config;
  std::string summary;  // "applied: friction 0, gravity 9.80665, ...", every live key
  for (const LiveKey& key : live_keys())
    summary += (summary.empty() ? "applied: " : ", ") + std::string(key.name) + " " + format("%g", config.*key.field);
  report(summary);
  ROS_INFO("spinning_top: %s", summary.c_str());
}

bool SpinningTopNode::on_reset(std_srvs::Trigger::Request& request, std_srvs::Trigger::Response& response) {
  // ~reset_reads_parameters (read at each call, so `rosparam set` switches it): ~reset is ~reload.
  bool reads_parameters = false;
  try {
    reads_parameters = read_bool(private_nh_, "reset_reads_parameters", false);
  } catch (const InvalidParameter& error) {
    response.success = false;
    response.message = std::string("reset refused: ~") + error.what();
    return true;
  }
  if (reads_parameters) return on_reload(request, response);
  // Every top restarts at its start; the world's time (and so the stamps) goes on, so tf2
  // listeners see time go on (no jump back, no dropped buffers).
  for (const auto& top : tops_) top->reset(clock_.time());
  tick_unfinished_ = false;
  send_static_transforms();
  response.success = true;
  response.message = "reset to the initial state; simulated time 0 is stamped " +
                     format("%.9f", (stamp_origin_ + ros::Duration(clock_.time())).toSec()) +
                     (paused_ ? " (still paused)" : "");
  ROS_INFO("spinning_top: %s", response.message.c_str());
  return true;
}

bool SpinningTopNode::on_reload(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response) {
  // The scene keys are read again and validated for every top the parameters describe before
  // any top changes; tops spawned by ~spawn are reset.
  std::vector<std::pair<std::string, SceneConfig>> configs;
  std::vector<Eigen::Vector2d> positions;
  try {
    configs = read_tops();
    for (const auto& [name, config] : configs) {
      if (find_top(name) == nullptr)
        throw InvalidParameter("tops", "'" + name + "' is not running: ~tops is read at start only");
      positions.push_back(read_tip_position(name));
      try {
        make_simulator(config);  // what restart() will build: it must not refuse half-way
      } catch (const InvalidParameter& error) {
        throw InvalidParameter((name.empty() ? "" : name + "/") + error.parameter(), reason_of(error));
      }
    }
  } catch (const InvalidParameter& error) {
    response.success = false;
    response.message = std::string("reload refused, nothing changed: ~") + error.what();
    report("refused: " + response.message);
    return true;
  }
  for (const auto& top : tops_) {
    const auto it = std::find_if(configs.begin(), configs.end(), [&](const auto& c) { return c.first == top->name(); });
    if (it == configs.end())
      top->reset(clock_.time());
    else
      top->restart(it->second, positions[it - configs.begin()], clock_.time());
  }
  tick_unfinished_ = false;
  send_static_transforms();
  response.success = true;
  response.message = "parameters read again; every top restarted at simulated time 0";
  report("applied: " + response.message);
  ROS_INFO("spinning_top: %s", response.message.c_str());
  return true;
}

bool SpinningTopNode::on_pause(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response) {
  response.success = true;
  response.message = paused_ ? "already paused" : format("paused at t = %.9g s", clock_.time());
  paused_ = true;
  return true;
}

bool SpinningTopNode::on_resume(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response) {
  response.success = true;
  response.message = paused_ ? format("resumed at t = %.9g s", clock_.time()) : "already running";
  if (paused_) clock_.anchor(ros::WallTime::now().toSec());  // the pause is not made up for
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
                       format(" to reach t = %.9g s; call ~step again to go on", clock_.time());
    return true;
  }
  response.success = true;
  response.message = format("stepped to t = %.9g s", clock_.time());
  return true;
}

bool SpinningTopNode::on_spawn(Spawn::Request& request, Spawn::Response& response) {
  response.success = false;
  try {
    require_top_name("name", request.name);
    if (find_top(request.name) != nullptr) throw InvalidParameter("name", "a top named '" + request.name + "' exists");
    ParameterMap keys;
    if (request.scene_file.empty()) {
      keys = read_scene_parameters(private_nh_);  // the node's own keys
    } else {
      try {
        keys = read_scene_file(request.scene_file);
      } catch (const SceneFileError& error) {
        throw InvalidParameter("scene_file", error.what());
      }
    }
    for (const std::string& assignment : request.keys) {
      const std::size_t equals = assignment.find('=');
      if (equals == std::string::npos || equals == 0)
        throw InvalidParameter("keys", "'" + assignment + "' is not key=value (e.g. initial/spin=80)");
      keys[assignment.substr(0, equals)] = assignment.substr(equals + 1);
    }
    const SceneConfig config = parse_scene_config(keys, /*require_all=*/false);
    add_top(std::make_unique<TopInstance>(request.name, config, Eigen::Vector2d(request.x, request.y), settings_,
                                          private_nh_, clock_.time(), stamp_of()));
  } catch (const InvalidParameter& error) {
    response.message = std::string("spawn refused: ") + error.what();
    ROS_WARN("spinning_top: %s", response.message.c_str());
    return true;
  }
  const TopInstance& top = *tops_.back();
  response.success = true;
  response.message = "top " + top.name() + ": scene " + to_string(top.simulator().config().scene) + ", " +
                     top.simulator().integrator_description() + "; frames " + top.body_frame() + ", " +
                     top.contact_frame();
  ROS_INFO("spinning_top: spawned %s", response.message.c_str());
  return true;
}

bool SpinningTopNode::on_kill(Kill::Request& request, Kill::Response& response) {
  const auto it = std::find_if(tops_.begin(), tops_.end(), [&](const auto& top) { return top->name() == request.name; });
  if (request.name.empty() || it == tops_.end()) {
    response.success = false;
    response.message = request.name.empty() ? "kill: give the name of a spawned top"
                                            : "kill: no top named '" + request.name + "'";
    return true;
  }
  diagnostics_->removeByName(request.name);
  const std::string service = private_nh_.resolveName(request.name + "/reset");
  top_reset_services_.erase(std::remove_if(top_reset_services_.begin(), top_reset_services_.end(),
                                           [&](const ros::ServiceServer& s) { return s.getService() == service; }),
                            top_reset_services_.end());
  tops_.erase(it);
  send_static_transforms();
  response.success = true;
  response.message = "killed " + request.name;
  ROS_INFO("spinning_top: %s", response.message.c_str());
  return true;
}

bool SpinningTopNode::on_set_state(SetState::Request& request, SetState::Response& response) {
  TopInstance* top = find_top(request.name);
  response.success = false;
  if (top == nullptr) {
    response.message = "set_state: no top named '" + request.name + "'";
    return true;
  }
  SceneConfig config = top->start_config();
  config.initial.tilt = request.tilt;
  config.initial.heading = request.heading;
  config.initial.spin_angle = request.spin_angle;
  config.initial.precession_rate = request.precession_rate;
  config.initial.nutation_rate = request.nutation_rate;
  config.initial.spin = request.spin;
  config.initial.velocity_x = request.velocity_x;
  config.initial.velocity_y = request.velocity_y;
  try {
    top->restart(config, Eigen::Vector2d(request.x, request.y), clock_.time());  // the core validates
  } catch (const InvalidParameter& error) {
    response.message = std::string("set_state refused, nothing changed: ") + error.what();
    return true;
  }
  send_static_transforms();
  response.success = true;
  response.message = format("state set; the top's simulated time 0 is stamped %.9f",
                            (stamp_origin_ + ros::Duration(clock_.time())).toSec());
  return true;
}

}  // namespace ros_front_end
}  // namespace spinning_top
