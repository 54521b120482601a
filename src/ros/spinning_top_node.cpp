#include "spinning_top/ros/spinning_top_node.hpp"

#include <ros/callback_queue.h>
#include <ros/master.h>
#include <ros/names.h>
#include <ros/publication.h>
#include <ros/service_manager.h>
#include <ros/this_node.h>
#include <ros/topic_manager.h>
#include <ros/xmlrpc_manager.h>
#include <rosgraph_msgs/Clock.h>
#include <xmlrpcpp/XmlRpcClient.h>
#include <std_msgs/String.h>
#include <tf2_msgs/TFMessage.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <set>
#include <thread>
#include <unordered_set>

#include "spinning_top/TopStateArray.h"
#include "spinning_top/ros/live_keys.hpp"
#include "spinning_top/ros/ros_parameters.hpp"
#include "spinning_top/scene_file.hpp"

namespace spinning_top {
namespace ros_front_end {
namespace {

// A subscriber queue as short as rosbag record's (its subscriptions queue 100 messages).
constexpr long kSubscriberQueueHint = 100;
constexpr double kAsFastAsPossibleSlice = 1e-3;  // [s] wall time per timer callback when rtf = 0
// Bounds of a ~spawn request: a path (PATH_MAX), key=value assignments and their values (a
// number or a name; simulate's --set takes the same).
constexpr std::size_t kMaxPathLength = 4096;
constexpr std::size_t kMaxSpawnKeys = 256;
constexpr std::size_t kMaxValueLength = 100;

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
  // At most one publication per 1e9 ticks (a publication rate of 1e-300 Hz is "never" enough).
  return publication_rate > 0.0 ? std::max(1L, std::lround(std::min(rate / publication_rate, 1e9))) : 1L;
}

/// Keys of our private namespace that nobody reads (typos such as ~mas): warned about, not
/// fatal, since other tools may store things there.
void warn_about_unknown_keys(const ros::NodeHandle& private_nh, const std::vector<std::string>& top_names) {
  std::vector<std::string> own = parameter_keys();  // what a near miss is compared with
  for (const std::string& key : node_setting_keys()) own.push_back(key);
  for (const LiveKey& key : live_keys()) own.push_back(key.name);  // e.g. spin (the scene's: initial/spin)
  own.push_back("robot_description");  // the node writes it (a URDF of the top)
  std::set<std::string> known(own.begin(), own.end());
  for (const std::string& key : parameter_keys()) known.insert("scene_file_values/" + key);  // its write-back
  for (const std::string& name : top_names) {
    for (const std::string& key : parameter_keys()) known.insert(name + "/" + key);
    known.insert(name + "/x");
    known.insert(name + "/y");
    known.insert(name + "/robot_description");
  }
  std::vector<std::string> names;
  if (!ros::param::getParamNames(names)) return;
  const std::string prefix = private_nh.getNamespace() + "/";
  for (const std::string& name : names) {
    if (name.compare(0, prefix.size(), prefix) != 0) continue;
    const std::string key = name.substr(prefix.size());
    if (known.count(key) > 0) continue;
    const std::size_t slash = key.find('/');  // ~<top>/<key>: compared with the scene's keys
    const bool of_top = slash != std::string::npos &&
                        std::find(top_names.begin(), top_names.end(), key.substr(0, slash)) != top_names.end();
    const std::string nearest =
        of_top ? nearest_name(key.substr(slash + 1), parameter_keys()) : nearest_name(key, own);
    if (nearest.empty())
      ROS_WARN("spinning_top: ignoring unknown parameter %s", excerpt(name, 200).c_str());
    else
      ROS_WARN("spinning_top: ignoring unknown parameter %s (did you mean ~%s%s?)", excerpt(name, 200).c_str(),
               of_top ? key.substr(0, slash + 1).c_str() : "", nearest.c_str());
  }
}

/// Whether two texts of a scene key's value give the same value (numbers compared as numbers).
bool same_value(const std::string& key, const std::string& a, const std::string& b) {
  if (a == b) return true;
  for (const ParameterSpec& spec : parameter_specs())
    if (spec.key == key && takes_number(spec)) {
      try {
        return parse_number(key, a) == parse_number(key, b);
      } catch (const InvalidParameter&) {
        return false;
      }
    }
  return false;
}

/// The members of the private namespace that hold the node's own scene keys (for a read of them
/// alone, without every top's URDF).
std::vector<std::string> node_key_members() {
  std::set<std::string> members = {"scene_file", "overrides_file", "scene_file_values"};
  for (const ParameterSpec& spec : parameter_specs()) {
    const std::string key = spec.key;
    members.insert(key.substr(0, key.find('/')));
  }
  return {members.begin(), members.end()};
}

/// The reason of an InvalidParameter without its "key: " prefix.
std::string reason_of(const InvalidParameter& error) {
  const std::string what = error.what();
  const std::size_t skip = error.parameter().size() + 2;
  return what.size() >= skip ? what.substr(skip) : what;
}

/// The live keys held by tops that a change changes and that apply to `top` (applies_to()).
std::vector<std::string> changes_for(const SceneConfig& top, const SpinningTopConfig& config,
                                     const SpinningTopConfig& old) {
  std::vector<std::string> names;
  for (const LiveKey& key : live_keys())
    if (key.in_top != nullptr && config.*key.field != old.*key.field && applies_to(key, top)) names.push_back(key.name);
  return names;
}

/// A refusal of a live change names a key the change changed: the core names the key of the
/// quantity it checks (of the pendulum rate sqrt(m g h / A), the key furthest from the shipped
/// top's), which need not be the one changed.
InvalidParameter blame(const InvalidParameter& error, const std::vector<std::string>& changed) {
  std::string key = error.parameter();
  if (key == "initial/spin") key = "spin";  // the live key's name
  if (changed.empty() || std::find(changed.begin(), changed.end(), key) != changed.end())
    return InvalidParameter(key, reason_of(error));
  return InvalidParameter(changed.front(), "refused by the check of " + error.parameter() + ": " + reason_of(error));
}


/// The publishers of /clock in the master's order of registration (getSystemState: rosmaster
/// appends each new publisher of a topic to its list); false if the master did not answer.
bool clock_publishers(std::vector<std::string>& publishers) {
  publishers.clear();
  XmlRpc::XmlRpcValue request, response, payload;
  request[0] = ros::this_node::getName();
  if (!ros::master::execute("getSystemState", request, response, payload, false)) return false;
  if (payload.getType() != XmlRpc::XmlRpcValue::TypeArray || payload.size() < 1) return false;
  const std::string clock = ros::names::resolve("/clock");
  XmlRpc::XmlRpcValue& topics = payload[0];
  if (topics.getType() != XmlRpc::XmlRpcValue::TypeArray) return false;
  for (int i = 0; i < topics.size(); ++i) {
    XmlRpc::XmlRpcValue& entry = topics[i];
    if (entry.getType() != XmlRpc::XmlRpcValue::TypeArray || entry.size() < 2 ||
        entry[0].getType() != XmlRpc::XmlRpcValue::TypeString || static_cast<std::string>(entry[0]) != clock)
      continue;
    XmlRpc::XmlRpcValue& nodes = entry[1];
    if (nodes.getType() != XmlRpc::XmlRpcValue::TypeArray) return false;
    for (int j = 0; j < nodes.size(); ++j)
      if (nodes[j].getType() == XmlRpc::XmlRpcValue::TypeString) publishers.push_back(static_cast<std::string>(nodes[j]));
  }
  return true;
}

/// Whether a node is a spinning_top node whose ~publish_clock is auto (it writes "auto" there
/// at start when the key is not set), which gives way to the first registered one of its kind.
bool yields_clock(const std::string& node) {
  XmlRpc::XmlRpcValue value;
  return ros::param::get(node + "/publish_clock", value) && value.getType() == XmlRpc::XmlRpcValue::TypeString &&
         static_cast<std::string>(value) == "auto";
}

/// What a (re)started top's release already is, for the response of ~spawn and ~set_state: its
/// events at t = 0 reach ~events' subscribers, but come before any subscriber can have connected
/// to topics a spawn creates (latched, ~event then keeps only the last of them), so the caller
/// learns them here.
std::string at_release(const Simulator& simulator) {
  if (simulator.event() != Event::kNone)
    return std::string("; its release is already an event: ") + to_string(simulator.event()) +
           " at t = 0, where the run stops";
  if (simulator.phase() != Phase::kContact)
    return std::string("; R < 0 at its release: lift_off at t = 0, it goes on in ") + to_string(simulator.phase());
  return "";
}

}  // namespace

SpinningTopNode::SpinningTopNode(ros::NodeHandle nh, ros::NodeHandle private_nh)
    : nh_(nh), private_nh_(private_nh), settings_(read_node_settings(private_nh)),
      clock_(settings_.rate, settings_.real_time_factor) {
  // Everything is read and validated before anything is advertised (a TopInstance validates its
  // configuration before it advertises): the private namespace in one call, however many tops.
  stop_if_shutting_down("reading the parameters");
  const ParameterTree tree = ParameterTree::fetch(private_nh_.getNamespace());
  NodeKeys node_keys;
  const std::vector<std::pair<std::string, SceneConfig>> configs = read_tops(tree, node_keys);
  std::vector<Eigen::Vector2d> positions;
  for (const auto& named : configs) positions.push_back(read_tip_position(tree, named.first));
  warn_about_unknown_keys(private_nh_, settings_.tops);
  paused_ = settings_.start_paused;
  waiting_for_subscriber_ = settings_.wait_for_subscriber;
  // Under use_sim_time our own /clock is the time base and starts at the first tick (never
  // 0); otherwise stamps start at the wall time of the start, so that tf users on wall time
  // see current transforms at real_time_factor 1.
  stamp_origin_ = ros::Time::isSimTime() ? ros::Time(0, 0) : ros::Time::now();
  last_stamp_ = stamp_origin_.base;
  stop_if_shutting_down("writing the parameters");
  write_back(node_keys);

  start_clock();
  status_publisher_ = private_nh_.advertise<std_msgs::String>("status", 1, /*latch=*/true);
  tf_publisher_ = nh_.advertise<tf2_msgs::TFMessage>("/tf", 1000);
  static_publisher_ = nh_.advertise<tf2_msgs::TFMessage>("/tf_static", 100, /*latch=*/true);
  {
    // Counted by the connect callbacks, as a top's topics are: without a subscriber the tick
    // builds no TopStateArray.
    const std::shared_ptr<std::atomic<int>> listeners = states_listeners_;
    states_publisher_ = private_nh_.advertise<spinning_top::TopStateArray>(
        "states", 100, [listeners](const ros::SingleSubscriberPublisher&) { ++*listeners; },
        [listeners](const ros::SingleSubscriberPublisher&) { --*listeners; });
  }
  // Not latched: a latched topic keeps one message, the last event of whichever top had one.
  // Several tops can have events within one tick: a deep queue.
  events_publisher_ = private_nh_.advertise<spinning_top::TopEvent>("events", 1000);
  diagnostics_ = std::make_unique<diagnostic_updater::Updater>(nh_, private_nh_);
  diagnostics_->setHardwareID("spinning_top/" + std::string(to_string(configs.front().second.scene)));
  diagnostics_->add("simulation", this, &SpinningTopNode::diagnose);

  for (std::size_t i = 0; i < configs.size(); ++i) {
    stop_if_shutting_down("starting the tops");  // each top advertises its topics and services
    add_top(make_top(configs[i].first, configs[i].second, positions[i], settings_.top_topics),
            settings_.top_reset_services);
  }
  send_static_transforms();

  stop_if_shutting_down("advertising the services");
  reset_service_ = private_nh_.advertiseService("reset", &SpinningTopNode::on_reset, this);
  reload_service_ = private_nh_.advertiseService("reload", &SpinningTopNode::on_reload, this);
  pause_service_ = private_nh_.advertiseService("pause", &SpinningTopNode::on_pause, this);
  resume_service_ = private_nh_.advertiseService("resume", &SpinningTopNode::on_resume, this);
  step_service_ = private_nh_.advertiseService("step", &SpinningTopNode::on_step, this);
  spawn_service_ = private_nh_.advertiseService("spawn", &SpinningTopNode::on_spawn, this);
  kill_service_ = private_nh_.advertiseService("kill", &SpinningTopNode::on_kill, this);
  set_state_service_ = private_nh_.advertiseService("set_state", &SpinningTopNode::on_set_state, this);
  get_state_service_ = private_nh_.advertiseService("get_state", &SpinningTopNode::on_get_state, this);

  // dynamic_reconfigure starts from the effective values: the node's own keys (those its tops
  // inherit; the scene's documented defaults included) and its pacing. A live key that does not
  // apply to the node's own scene (friction outside the viscous one) stays off ~, so that its
  // own keys stay valid for ~reload and ~spawn while the tops it applies to take it.
  SpinningTopConfig initial = SpinningTopConfig::__getDefault__();
  {
    SceneConfig own = SceneConfig{};
    for (const LiveKey& key : live_keys()) {
      if (key.in_node != nullptr) {
        initial.*key.field = *key.in_node(settings_);
        continue;
      }
      const auto it = node_keys.keys.find(key.scene_key);
      initial.*key.field = *key.in_top(own);  // the documented default
      try {
        if (it != node_keys.keys.end()) initial.*key.field = parse_number(key.scene_key, it->second);
      } catch (const InvalidParameter&) {
        // Not a number at the node's level: every named top overrides it (each was validated).
      }
    }
  }
  stop_if_shutting_down("starting dynamic_reconfigure");
  reconfigure_server_ = std::make_unique<ReconfigureServer>(
      private_nh_, initial, [this](SpinningTopConfig& c, std::uint32_t level) { reconfigure(c, level); },
      [this](const std::string& why) {
        ROS_ERROR("spinning_top: dynamic_reconfigure update refused: %s. The previous configuration stays.",
                  why.c_str());
        report("refused: " + why);
      },
      [this](const std::string& name) {
        for (const LiveKey& key : live_keys())
          if (name == key.name && key.in_top != nullptr) {
            SceneConfig own;
            own.scene = node_scene_;
            return applies_to(key, own);
          }
        return true;
      });

  stop_if_shutting_down("starting the timers");
  // The pacing and the wall-clock stamps start together, after the set-up above (advertising
  // and the reconfigure server take tens of ms): tick n is due at the wall time it is stamped.
  window_wall_start_ = ros::WallTime::now();
  clock_.anchor(window_wall_start_.toSec());
  if (!ros::Time::isSimTime() && clock_role_ != ClockRole::kFollow)
    last_stamp_ = (stamp_origin_ = ros::Time(window_wall_start_.sec, window_wall_start_.nsec)).base;
  restart_timer();
  if (clock_role_ == ClockRole::kFollow) timer_.stop();  // the external /clock drives the ticks
  diagnostics_timer_ = nh_.createWallTimer(ros::WallDuration(1.0), &SpinningTopNode::on_diagnostics_timer, this);
  if (settings_.publish_clock == ClockMode::kAuto) {
    clock_role_timer_ = nh_.createWallTimer(ros::WallDuration(1.0), &SpinningTopNode::on_clock_role_timer, this);
    clock_arbiter_ = std::thread(&SpinningTopNode::clock_arbiter_loop, this);
  }
  if (tops_.size() <= 10) {  // with more, one line for all
    for (const auto& top : tops_)
      ROS_INFO("spinning_top: %s%sscene %s, integrator %s", top->name().c_str(), top->name().empty() ? "" : ": ",
               to_string(top->simulator().config().scene), top->simulator().integrator_description().c_str());
  }
  ROS_INFO("spinning_top: %zu top%s, %g Hz, real-time factor %g%s", tops_.size(), tops_.size() == 1 ? "" : "s",
           settings_.rate, settings_.real_time_factor, paused_ ? " (paused)" : "");
}

SpinningTopNode::~SpinningTopNode() {
  {
    std::lock_guard<std::mutex> lock(arbiter_mutex_);
    arbiter_stop_ = true;
  }
  arbiter_wake_.notify_all();
  if (clock_arbiter_.joinable()) clock_arbiter_.join();
}

std::atomic<int> SpinningTopNode::stop_requested_{0};
std::atomic<int> SpinningTopNode::stopping_the_start_{0};

void SpinningTopNode::stop_if_shutting_down(const char* step) {
  if (ros::ok() && !ros::isShuttingDown() && !stop_requested()) return;
  if (stop_requested() && ros::ok() && !ros::isShuttingDown()) {
    // SIGINT, and ROS still up: what was advertised so far goes in one call to the master, as at
    // a SIGINT once running. roscpp's own shutdown made a call per topic and service: with 300
    // tops half started, ~1 s.
    stopping_the_start_ = 1;
    shut_down_at_sigint();
  } else {
    ros::shutdown();
  }
  // Unwinding destroys every publisher made so far: after the shutdown that costs nothing.
  throw StartupInterrupted(std::string("shut down while ") + step);
}

SpinningTopNode::ClockVerdict SpinningTopNode::judge_clock(const std::vector<std::string>& publishers) {
  const std::string me = ros::this_node::getName();
  std::vector<std::string> others;
  for (const std::string& node : publishers)
    if (node != me) others.push_back(node);
  ClockVerdict verdict;
  if (others.empty()) return verdict;  // nobody else: ours
  verdict.publish = false;
  // A clock that never gives way (rosbag play --clock, Gazebo, ~publish_clock true) is followed.
  for (const std::string& node : others)
    if (!yields_clock(node)) {
      verdict.source = node;
      return verdict;
    }
  // Only auto nodes: the first registered keeps publishing (all of them read the same list).
  const bool registered = others.size() < publishers.size();
  verdict.source = registered ? publishers.front() : others.front();
  verdict.publish = verdict.source == me;
  if (verdict.publish) verdict.source.clear();
  return verdict;
}

void SpinningTopNode::start_clock() {
  if (settings_.publish_clock == ClockMode::kOff) {
    clock_role_ = ClockRole::kOwnPace;
    return;
  }
  if (settings_.publish_clock == ClockMode::kPublish) {
    // A /clock subscriber (every sim-time node) may fall behind by a few callbacks at 1 kHz.
    clock_publisher_ = nh_.advertise<rosgraph_msgs::Clock>("/clock", 1000);
    clock_role_ = ClockRole::kPublish;
    return;
  }
  // auto. The mark by which other auto nodes know this one gives way (judge_clock).
  if (!private_nh_.hasParam("publish_clock")) private_nh_.setParam("publish_clock", std::string("auto"));
  std::vector<std::string> publishers;
  if (clock_publishers(publishers) && !publishers.empty()) {
    const ClockVerdict verdict = judge_clock(publishers);  // we are not registered: never ours
    return follow_clock(verdict.source, "it publishes /clock");
  }
  // Nobody publishes /clock: advertise it and look again before the first tick. Two nodes that
  // started together may both be here; the master's list orders them alike for both.
  clock_publisher_ = nh_.advertise<rosgraph_msgs::Clock>("/clock", 1000);
  clock_role_ = ClockRole::kPublish;
  if (!clock_publishers(publishers)) return;
  const ClockVerdict verdict = judge_clock(publishers);
  if (verdict.publish) {
    ROS_INFO("spinning_top: no other node publishes /clock: publishing it (~publish_clock auto)");
    return;
  }
  follow_clock(verdict.source, "it registered /clock first");
}

void SpinningTopNode::clock_arbiter_loop() {
  std::unique_lock<std::mutex> lock(arbiter_mutex_);
  // Every second; on a large graph (getSystemState lists every topic: 0.13 s for the 7,000 topics
  // of 1,000 tops) 50 times as long as the master took, so that asking costs it at most 2 %.
  std::chrono::duration<double> interval(1.0);
  while (!arbiter_stop_) {
    arbiter_wake_.wait_for(lock, interval, [this] { return arbiter_stop_; });
    if (arbiter_stop_) break;
    lock.unlock();  // the master calls without the lock
    const auto asked = std::chrono::steady_clock::now();
    std::vector<std::string> publishers;
    const bool answered = ros::ok() && clock_publishers(publishers);
    ClockVerdict verdict;
    if (answered) verdict = judge_clock(publishers);
    const std::chrono::duration<double> took = std::chrono::steady_clock::now() - asked;
    interval = std::max(std::chrono::duration<double>(1.0), 50.0 * took);
    lock.lock();
    if (answered) {
      verdict_ = verdict;
      verdict_ready_ = true;
    }
  }
}

void SpinningTopNode::on_clock_role_timer(const ros::WallTimerEvent&) {
  ClockVerdict verdict;
  {
    std::lock_guard<std::mutex> lock(arbiter_mutex_);
    if (!verdict_ready_) return;
    verdict_ready_ = false;
    verdict = verdict_;
  }
  if (verdict.publish && clock_role_ == ClockRole::kFollow) {
    ++clock_role_changes_;
    publish_own_clock("nobody else publishes /clock (" + clock_source_ + " stopped)");
  } else if (!verdict.publish && clock_role_ == ClockRole::kPublish) {
    ++clock_role_changes_;
    follow_clock(verdict.source, "it publishes /clock too");
  } else if (!verdict.publish && verdict.source != clock_source_) {
    ++clock_role_changes_;
    follow_clock(verdict.source, "it publishes /clock now");
  }
}

void SpinningTopNode::publish_own_clock(const std::string& why) {
  clock_subscriber_.shutdown();
  clock_publisher_ = nh_.advertise<rosgraph_msgs::Clock>("/clock", 1000);
  clock_role_ = ClockRole::kPublish;
  const std::string previous = clock_source_;
  clock_source_.clear();
  // Another follower of the same clock may take over at the same time: as at the start, the
  // master's list decides at once (the first registered auto node keeps publishing).
  std::vector<std::string> publishers;
  if (clock_publishers(publishers)) {
    const ClockVerdict verdict = judge_clock(publishers);
    if (!verdict.publish) return follow_clock(verdict.source, "it took over the /clock of " + previous + " first");
  }
  // Our /clock goes on from the time followed: stamps and /clock continue, paced by the wall clock.
  if (external_anchored_) anchor_stamps(std::max(external_time_, last_stamp_));
  external_anchored_ = false;
  clock_.anchor(ros::WallTime::now().toSec());
  restart_timer();
  timer_.start();
  ROS_WARN("spinning_top: %s: publishing /clock from %.9f s on (~publish_clock auto)", why.c_str(),
           stamp_at(clock_.next_time()).toSec());
}

void SpinningTopNode::follow_clock(const std::string& source, const std::string& why) {
  if (clock_publisher_) clock_publisher_.shutdown();  // unregistered: the master lists one publisher
  clock_publisher_ = ros::Publisher();
  clock_role_ = ClockRole::kFollow;
  clock_source_ = source;
  external_anchored_ = false;  // the next /clock message anchors the stamps
  if (!clock_subscriber_)
    clock_subscriber_ = nh_.subscribe("/clock", 100, &SpinningTopNode::on_clock, this, ros::TransportHints().tcpNoDelay());
  if (timer_.isValid()) timer_.stop();
  ROS_INFO("spinning_top: following the /clock of %s (%s): the tops advance in ticks of 1/rate to its time, "
           "stamped with it; this node does not publish /clock (~publish_clock auto)",
           source.c_str(), why.c_str());
}

void SpinningTopNode::anchor_stamps(const ros::Time& stamp) {
  stamp_origin_.base = stamp;
  stamp_origin_.world_base = clock_.time();
}

void SpinningTopNode::on_clock(const rosgraph_msgs::Clock::ConstPtr& message) {
  if (clock_role_ != ClockRole::kFollow) return;
  const ros::Time now = message->clock;
  external_wall_ = ros::WallTime::now();
  if (!external_anchored_ || now < external_time_) {
    if (external_anchored_) {
      ++external_jumps_back_;
      ROS_WARN("spinning_top: the /clock of %s went back from %.9f s to %.9f s (its source restarted: rosbag "
               "play --loop, a Gazebo reset?): the tops go on from where they are, stamped on the new time",
               clock_source_.c_str(), external_time_.toSec(), now.toSec());
    }
    // The world's time now is stamped `now`; its next tick one period later. Stamps already sent
    // beyond it belong to the old time line (tf2 listeners clear their buffers at the jump).
    anchor_stamps(now);
    if (last_stamp_ > now) last_stamp_ = now;
    external_anchored_ = true;
  }
  external_time_ = now;
  if (paused_) return;
  if (waiting_for_subscriber_) {
    if (tops_.empty() || !tops_.front()->subscribed()) return;
    waiting_for_subscriber_ = false;
    anchor_stamps(now);  // the first tick one period after the subscriber came
    ROS_INFO("spinning_top: a subscriber is there; the simulation starts");
  }
  follow_to(external_wall_);
}

void SpinningTopNode::follow_to(ros::WallTime start) {
  if (!external_anchored_ || waiting_for_subscriber_ || paused_) {
    timer_.stop();
    return;
  }
  // Far behind the external clock (it jumped ahead, or it runs faster than the ticks can be
  // computed): beyond ~max_lag of its time the ticks are given up, as with the wall clock.
  const double behind = (external_time_ - stamp_at(clock_.time())).toSec();
  if (!tick_unfinished_ && behind > settings_.max_lag + 1.0 / settings_.rate) {
    const long given_up = static_cast<long>(std::floor((behind - settings_.max_lag) * settings_.rate));
    if (given_up > 0) {
      given_up_ticks_ += given_up;
      stamp_origin_ += ros::Duration(static_cast<double>(given_up) / settings_.rate);
      ROS_WARN_THROTTLE(5.0, "spinning_top: more than ~max_lag = %g s behind the /clock of %s: %ld ticks given up",
                        settings_.max_lag, clock_source_.c_str(), given_up);
    }
  }
  const ros::WallTime deadline = start + ros::WallDuration(settings_.tick_budget);
  ros::WallTime now = start;
  auto* queue = dynamic_cast<NodeCallbackQueue*>(nh_.getCallbackQueue());
  while (!paused_ && now < deadline) {
    if (!tick_unfinished_ && stamp_at(clock_.next_time()) > external_time_) break;
    if (!timed_tick(deadline, now)) break;
    if (queue != nullptr && queue->others_waiting()) break;  // served between two ticks
  }
  const bool backlog = !paused_ && (tick_unfinished_ || stamp_at(clock_.next_time()) <= external_time_);
  if (backlog)
    timer_.start();  // goes on at the timer, after what waits in the queue
  else
    timer_.stop();
}

void SpinningTopNode::shut_down_at_sigint() {
  const std::vector<std::string> topics = topics_in_registration_order();
  ROS_INFO("spinning_top: unregistering %zu topics from the master in one call, the services beside it, "
           "while ROS shuts down",
           topics.size());
  // The master's work (~80 us per topic in rosmaster: 0.6-0.8 s for the 7,000 topics of 1,000
  // tops), roscpp's one call per service (each top's ~<name>/reset) and roscpp's own shutdown
  // (its threads each wait up to 0.1 s for their next turn) overlap: three threads.
  bool all_unregistered = false;
  std::thread services([] { ros::ServiceManager::instance()->shutdown(); });
  std::thread master([&topics, &all_unregistered] { all_unregistered = unregister_publishers(topics); });
  // Dropped before roscpp's shutdown, which then leaves them alone (it would unregister each with
  // a call of its own). roscpp finds a publication by a linear search (0.1-0.2 s for 7,000):
  // done while the master works on the call.
  for (const std::string& topic : topics)
    if (const ros::PublicationPtr publication = ros::TopicManager::instance()->lookupPublication(topic))
      publication->drop();
  ros::shutdown();  // rosconsole prints nothing after it
  services.join();
  master.join();
  if (!all_unregistered)
    std::fprintf(stderr, "spinning_top: the master did not confirm the unregistration of every topic of %s\n",
                 ros::this_node::getName().c_str());
}

std::vector<std::string> SpinningTopNode::topics_in_registration_order() const {
  std::vector<std::string> advertised;
  ros::this_node::getAdvertisedTopics(advertised);  // sorted by name (a std::set in roscpp)
  // /rosout stays with roscpp: its logging thread may still publish there, and roscpp aborts on a
  // message published on a dropped publication. Only this thread publishes on the others.
  const std::string rosout = ros::names::resolve("/rosout");
  // In the order of their registration: the master keeps a node's topics in a list and removes
  // each with a linear search (rosmaster's NodeRef.remove), so that in name order 7,000 topics
  // cost it 0.4-0.5 s and in registration order (each found first) ~0.1 s. The node's own
  // topics came first, then each top's, in the order of tops_ (a spawn appends, a kill removes).
  std::vector<std::string> of_tops;
  for (const auto& top : tops_)
    for (std::string& topic : top->advertised_topics()) of_tops.push_back(std::move(topic));
  const std::unordered_set<std::string> is_advertised(advertised.begin(), advertised.end()),
      is_of_a_top(of_tops.begin(), of_tops.end());
  std::vector<std::string> topics;
  for (const std::string& topic : advertised)
    if (topic != rosout && is_of_a_top.count(topic) == 0) topics.push_back(topic);
  for (const std::string& topic : of_tops)
    if (is_advertised.count(topic) != 0) topics.push_back(topic);
  return topics;
}

bool SpinningTopNode::unregister_publishers(const std::vector<std::string>& topics) {
  if (topics.empty()) return true;
  const std::string node = ros::this_node::getName(), api = ros::XMLRPCManager::instance()->getServerURI();
  auto arguments_for = [&](const std::string& topic) {
    XmlRpc::XmlRpcValue arguments;
    arguments[0] = node;
    arguments[1] = topic;
    arguments[2] = api;
    return arguments;
  };
  XmlRpc::XmlRpcValue calls;
  for (std::size_t i = 0; i < topics.size(); ++i) {
    XmlRpc::XmlRpcValue& call = calls[static_cast<int>(i)];
    call["methodName"] = std::string("unregisterPublisher");
    call["params"] = arguments_for(topics[i]);
  }
  XmlRpc::XmlRpcValue parameters, result;
  parameters[0] = calls;
  XmlRpc::XmlRpcClient client(ros::master::getHost().c_str(), static_cast<int>(ros::master::getPort()), "/");
  bool done = client.execute("system.multicall", parameters, result) && !client.isFault() &&
              result.getType() == XmlRpc::XmlRpcValue::TypeArray && result.size() == static_cast<int>(topics.size());
  if (!done) {
    // A master without system.multicall (or a failed call): one call per topic, as roscpp does.
    done = true;
    for (const std::string& topic : topics) {
      XmlRpc::XmlRpcValue each;
      done = client.execute("unregisterPublisher", arguments_for(topic), each) && !client.isFault() && done;
    }
  }
  client.close();
  return done;
}

NodeKeys SpinningTopNode::read_node_keys(const ParameterTree& own) const {
  NodeKeys result;
  XmlRpc::XmlRpcValue value;
  // The files: read as every front end reads a scene file (the core's reader, YAML 1.2), so that
  // one file describes one top everywhere; the overrides file's keys replace the scene file's.
  for (const char* key : {"scene_file", "overrides_file"}) {
    if (!own.get(key, value)) continue;
    if (value.getType() != XmlRpc::XmlRpcValue::TypeString)
      throw InvalidParameter(key, "must be a string: the path of a scene file (YAML)");
    const std::string path = static_cast<std::string>(value);
    if (path.empty()) continue;  // the launch file's "no overrides"
    result.files = true;
    try {
      for (const auto& [k, v] : read_scene_file(path)) result.from_files[k] = v;
    } catch (const SceneFileError& error) {
      throw InvalidParameter(key, error.what());
    }
  }
  const ParameterMap explicit_keys = read_scene_parameters(own);  // throws naming the key
  if (!result.files) {
    result.keys = explicit_keys;
    return result;
  }
  for (const ParameterSpec& spec : parameter_specs())
    if (result.from_files.count(spec.key) == 0) result.from_files[spec.key] = spec.default_value;
  // What the node wrote back the last time (this run's or a previous one's): a private key that
  // still holds it is not an explicit override, so that the files' values (read again) win.
  ParameterMap written;
  try {
    written = read_scene_parameters(own.sub("scene_file_values"));
  } catch (const InvalidParameter&) {
    written.clear();  // not ours: then every private key is explicit
  }
  result.keys = result.from_files;
  for (const auto& [key, text] : explicit_keys) {
    const auto was = written.find(key);
    if (was != written.end() && same_value(key, was->second, text)) continue;
    result.keys[key] = text;
  }
  return result;
}

void SpinningTopNode::write_back(const NodeKeys& node_keys) {
  try {
    node_scene_ = parse_scene(node_keys.keys.count("scene") ? node_keys.keys.at("scene") : "fixed_tip");
  } catch (const InvalidParameter&) {
    node_scene_ = SceneType::kFixedTip;  // the tops override it; each top's own scene was validated
  }
  if (!node_keys.files) return;
  for (const ParameterSpec& spec : parameter_specs()) {
    const std::string& now = node_keys.keys.at(spec.key);
    const std::string& from_files = node_keys.from_files.at(spec.key);
    try {
      if (takes_number(spec)) {
        private_nh_.setParam(spec.key, parse_number(spec.key, now));
        private_nh_.setParam(std::string("scene_file_values/") + spec.key, parse_number(spec.key, from_files));
      } else {
        private_nh_.setParam(spec.key, now);
        private_nh_.setParam(std::string("scene_file_values/") + spec.key, from_files);
      }
    } catch (const InvalidParameter&) {
      // Not a number: only where a named top overrides the key (each top's keys were validated).
    }
  }
}

std::vector<std::pair<std::string, SceneConfig>> SpinningTopNode::read_tops(const ParameterTree& tree,
                                                                           NodeKeys& node_keys) const {
  node_keys = read_node_keys(tree);
  const ParameterMap& own = node_keys.keys;
  std::vector<std::pair<std::string, SceneConfig>> configs;
  if (settings_.tops.empty()) {
    configs.emplace_back("", parse_scene_config(own, /*require_all=*/false));
    return configs;
  }
  for (const std::string& name : settings_.tops) {
    ParameterMap keys = own;  // ~<name>/key over ~key
    try {
      for (const auto& [key, value] : read_scene_parameters(tree.sub(name))) keys[key] = value;
      configs.emplace_back(name, parse_scene_config(keys, /*require_all=*/false));
    } catch (const InvalidParameter& error) {
      throw InvalidParameter(name + "/" + error.parameter(), reason_of(error));
    }
  }
  return configs;
}

Eigen::Vector2d SpinningTopNode::read_tip_position(const ParameterTree& tree, const std::string& name) const {
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();
  if (name.empty()) return xy;  // the node's own top starts at the origin
  const ParameterTree top = tree.sub(name);
  const char* const keys[] = {"x", "y"};
  for (int i = 0; i < 2; ++i) {
    const std::string key = name + "/" + keys[i];
    try {
      xy[i] = read_number(top, keys[i], 0.0);
    } catch (const InvalidParameter& error) {
      throw InvalidParameter(key, reason_of(error));
    }
    if (!(std::abs(xy[i]) <= 1e6)) throw InvalidParameter(key, "must be finite and within 1e6 m of the origin");
  }
  return xy;
}

std::unique_ptr<TopInstance> SpinningTopNode::make_top(const std::string& name, const SceneConfig& config,
                                                      const Eigen::Vector2d& tip_xy,
                                                      const std::vector<std::string>& topics) {
  TopInstance::EventSink to_events = [this](const spinning_top::TopEvent& event) {
    if (events_publisher_) events_publisher_.publish(event);
  };
  return std::make_unique<TopInstance>(name, config, tip_xy, settings_, topics, private_nh_, clock_.time(), stamp_of(),
                                       world_clock(), std::move(to_events));
}

void SpinningTopNode::add_top(std::unique_ptr<TopInstance> top, bool reset_service) {
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
    if (reset_service)
      top_reset_services_.push_back(private_nh_.advertiseService(name + "/reset", reset));
  }
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
  // Published when the pivots change (a top with one spawned, killed, placed elsewhere), not at
  // every call: a spawn costs the same however many pivots exist. The latched message is the
  // whole set (a late subscriber gets only it), so a killed top's pivot leaves it.
  auto same = [](const geometry_msgs::TransformStamped& a, const geometry_msgs::TransformStamped& b) {
    return a.child_frame_id == b.child_frame_id && a.header.frame_id == b.header.frame_id &&
           a.transform.translation.x == b.transform.translation.x &&
           a.transform.translation.y == b.transform.translation.y &&
           a.transform.translation.z == b.transform.translation.z;
  };
  if (transforms.size() == static_sent_.size() &&
      std::equal(transforms.begin(), transforms.end(), static_sent_.begin(), same))
    return;  // nothing new (nothing static, now or before, included)
  if (!static_publisher_) return;  // shutting down
  tf2_msgs::TFMessage message;
  message.transforms = transforms;
  static_publisher_.publish(message);
  static_sent_ = std::move(transforms);
}

void SpinningTopNode::update_hardware_id() {
  // The updater's own (its "starting up" statuses); each top's status carries its own scene.
  diagnostics_->setHardwareID("spinning_top/" +
                              std::string(tops_.empty() ? "none" : to_string(tops_.front()->simulator().config().scene)));
}

void SpinningTopNode::restart_timer() {
  const double period = settings_.real_time_factor > 0.0 ? 1.0 / (settings_.rate * settings_.real_time_factor)
                                                         : kAsFastAsPossibleSlice;
  ticks_per_marker_ = ticks_per(settings_.rate, settings_.marker_rate);
  ticks_per_clock_ = ticks_per(settings_.rate, settings_.clock_rate);
  ticks_per_tf_ = ticks_per(settings_.rate, settings_.tf_rate);
  ticks_per_states_ = ticks_per(settings_.rate, settings_.states_rate);
  const bool first = !timer_.isValid();
  timer_.setPeriod(ros::WallDuration(period));
  if (first) timer_.start();  // as createWallTimer's timer
}

void SpinningTopNode::spin_once() {
  auto* queue = dynamic_cast<NodeCallbackQueue*>(nh_.getCallbackQueue());
  queue->callAvailable(timer_.until_due(ros::WallDuration(0.1)));
  if (ros::ok() && !stop_requested() && timer_.take_due()) on_timer(ros::WallTimerEvent());
}

void SpinningTopNode::on_timer(const ros::WallTimerEvent&) {
  if (paused_) return;
  const ros::WallTime start = ros::WallTime::now();
  if (clock_role_ == ClockRole::kFollow) return follow_to(start);  // a backlog of the external clock
  if (waiting_for_subscriber_) {
    const bool clock_heard = clock_role_ != ClockRole::kPublish || clock_publisher_.getNumSubscribers() > 0;
    if (!clock_heard || tops_.empty() || !tops_.front()->subscribed()) {
      // Said, not silent: a recorder subscribed to other names (an absolute /spinning_top/...
      // under a namespace) left the node waiting for ever without a word.
      // Built only when the throttled line is printed, not at every turn of the timer.
      const auto prefix = [this] {
        return private_nh_.getNamespace() + "/" +
               (tops_.empty() || tops_.front()->name().empty() ? std::string() : tops_.front()->name() + "/");
      };
      ROS_INFO_THROTTLE(5.0, "spinning_top: ~wait_for_subscriber: no tick until %scontact_point and %sstate%s have a "
                        "subscriber (record:=true starts rosbag record)", prefix().c_str(), prefix().c_str(),
                        clock_role_ == ClockRole::kPublish ? " and /clock" : "");
      return;
    }
    // The first subscriber is there: pacing (and wall-clock stamps) start now, at tick 1.
    waiting_for_subscriber_ = false;
    clock_.anchor(start.toSec());
    if (!ros::Time::isSimTime() && clock_role_ != ClockRole::kFollow)
      last_stamp_ = (stamp_origin_ = ros::Time(start.sec, start.nsec)).base;
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
  while (!paused_ && now < deadline && !stop_requested()) {
    if (paced && !tick_unfinished_) {
      const long due = clock_.due(now.toSec());
      if (due == 0) break;
      if (due > 1) {
        ++late_ticks_;
        // A catch-up (the node was held up) publishes its ticks back to back: more of them than
        // a subscriber's queue holds (rosbag record's: 100) can be lost there, silently. Said
        // here and in the diagnostics, since the node cannot see a subscriber's loss.
        if (++catch_up_run_ == kSubscriberQueueHint + 1) {
          ++long_catch_ups_;
          ROS_WARN_THROTTLE(5.0, "spinning_top: held up, the node publishes more than %ld ticks back to back: a "
                                 "subscriber whose queue is shorter (rosbag record's: 100) may lose messages",
                            kSubscriberQueueHint);
        }
      } else {
        catch_up_run_ = 0;
      }
    }
    if (!timed_tick(deadline, now)) break;
    // A service call, a parameter update or the diagnostics waiting: served now, between two
    // ticks, rather than after the whole budget (the timer, late, fires again at once). With
    // many tops a node behind the wall clock answers ~spawn within one tick, however long the
    // budget (a spawn waited for it: 8 ms with 1 top, 61 ms with 300).
    auto* queue = dynamic_cast<NodeCallbackQueue*>(nh_.getCallbackQueue());
    if (queue != nullptr && queue->others_waiting()) break;
  }
  if (paced) last_lag_ = clock_.lag(now.toSec());
}

bool SpinningTopNode::timed_tick(ros::WallTime deadline, ros::WallTime& now) {
  const bool finished = tick(deadline);
  const ros::WallTime end = ros::WallTime::now();
  tick_cost_sum_ += (end - now).toSec();
  tick_cost_max_ = std::max(tick_cost_max_, (end - now).toSec());
  now = end;
  if (finished) ++ticks_in_window_;
  return finished;
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
  const ros::Time stamp = stamp_at(world_time);
  if (stamp <= last_stamp_) return true;  // never twice the same stamp (tf2 TF_REPEATED_DATA)
  last_stamp_ = stamp;
  publish(stamp);
  return true;
}

void SpinningTopNode::publish(const ros::Time& stamp) {
  const long tick = clock_.ticks();
  if (clock_role_ == ClockRole::kPublish && tick % ticks_per_clock_ == 0) {
    rosgraph_msgs::Clock clock;
    clock.clock = stamp;
    clock_publisher_.publish(clock);
  }
  if (tick % ticks_per_tf_ == 0) {
    std::vector<geometry_msgs::TransformStamped> transforms;
    for (const auto& top : tops_) top->append_transforms(stamp, transforms);
    if (!transforms.empty() && tf_publisher_) {  // none once every top is killed
      tf2_msgs::TFMessage message;
      message.transforms = std::move(transforms);
      tf_publisher_.publish(message);
    }
  }
  const bool markers = tick % ticks_per_marker_ == 0;
  // ~states_rate: with n tops a message holds n states, so a subscriber may want fewer of them.
  if (*states_listeners_ > 0 && states_publisher_ && tick % ticks_per_states_ == 0) {
    spinning_top::TopStateArray states;
    states.header.stamp = stamp;
    states.header.frame_id = settings_.world_frame;
    states.states.reserve(tops_.size());
    for (const auto& top : tops_) top->publish(stamp, markers, &states.states);
    states_publisher_.publish(states);
  } else {
    for (const auto& top : tops_) top->publish(stamp, markers);
  }
}

void SpinningTopNode::report(const std::string& status) {
  std_msgs::String message;
  message.data = status;
  if (status_publisher_) status_publisher_.publish(message);
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
  // fraction of them, a real-time factor below the threshold or ticks given up are not. A node
  // following an external /clock goes at its pace, whatever the requested real-time factor.
  const bool following = clock_role_ == ClockRole::kFollow;
  if (!paused_ && !following && late_fraction > settings_.late_tick_warning)
    status.mergeSummaryf(DiagnosticStatus::WARN, "%.0f%% of the ticks late in the last %.1f s", 100.0 * late_fraction,
                         wall);
  if (!paused_ && !following && requested > 0.0 && wall >= 0.5 &&
      achieved_rtf < settings_.real_time_factor_warning * requested)
    status.mergeSummaryf(DiagnosticStatus::WARN, "real-time factor %.3f of %g requested", achieved_rtf, requested);
  if (given_up_in_window > 0)
    status.mergeSummaryf(DiagnosticStatus::WARN, "%ld ticks given up beyond ~max_lag = %g s", given_up_in_window,
                         settings_.max_lag);
  if (long_catch_ups_ > long_catch_ups_at_window_start_)
    status.mergeSummaryf(DiagnosticStatus::WARN,
                         "more than %ld ticks published back to back (a catch-up): a subscriber with a shorter "
                         "queue (rosbag record's: 100) may have lost messages", kSubscriberQueueHint);
  if (exhaustions_in_window > 0)
    status.mergeSummaryf(DiagnosticStatus::ERROR, "ticks ran out of their %g s work budget %ld times in the last %.1f s",
                         settings_.tick_budget, exhaustions_in_window, wall);
  // The node's own top reports here, as it always has; named tops have a status of their own.
  if (TopInstance* own = find_top("")) own->diagnose(status);
  status.add("tops", static_cast<int>(tops_.size()));
  status.add("clock", clock_role_ == ClockRole::kPublish ? std::string("publishes /clock")
                      : following ? "follows the /clock of " + clock_source_
                                  : std::string("own pace, /clock not published (~publish_clock false)"));
  if (following) {
    status.addf("external clock [s]", "%.9f", external_time_.toSec());
    status.addf("external clock last heard [wall s ago]", "%.3f",
                external_anchored_ ? (now - external_wall_).toSec() : -1.0);
    status.add("external clock jumps back", external_jumps_back_);
  }
  status.add("clock role changes", clock_role_changes_);
  status.addf("world time [s]", "%.9g", clock_.time());
  status.addf("rate [Hz]", "%g", settings_.rate);
  status.addf("requested real-time factor", "%g", requested);
  status.addf("achieved real-time factor", "%.3f", achieved_rtf);
  status.addf("lag behind the wall clock [s]", "%.6f", last_lag_);
  status.add("late ticks (total)", late_ticks_);
  status.add("late ticks (window)", late_in_window);
  status.add("ticks given up (total)", given_up_ticks_);
  status.add("catch-ups over 100 ticks (total)", long_catch_ups_);
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
  long_catch_ups_at_window_start_ = long_catch_ups_;
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
  // A key applies to the tops that run with it (friction: the viscous ones) and leaves the others
  // alone; one that applies to no top is refused, since nothing would take it.
  for (const LiveKey& key : live_keys()) {
    if (key.in_top == nullptr || config.*key.field == old.*key.field) continue;
    const bool applies =
        tops_.empty() || std::any_of(tops_.begin(), tops_.end(), [&](const auto& top) {
          return applies_to(key, top->simulator().config());
        });
    if (!applies)
      return refuse(std::string(key.name) + ": applies to " + applies_only_to(key) + " only, and no top runs it");
  }
  // Each top's change: the keys that changed and apply to it, checked for every top before any
  // changes, so that a refusal leaves all of them as they were. A body change (m, A, C, h, spin) is
  // prepared whole here (its new model from the current state); the others are the core's update.
  struct Change {
    TopInstance* top;
    std::vector<std::string> keys;  // the changed live keys that apply to it
    SceneConfig config;             // its current configuration with them
    bool body;
    TopInstance::BodyChange body_change;
  };
  std::vector<Change> changes;
  for (const auto& top : tops_) {
    Change change{top.get(), changes_for(top->simulator().config(), config, old), {}, false, {}};
    if (change.keys.empty()) continue;
    // A body change names its body key first (the others come along with it).
    const auto body_key = std::find_if(change.keys.begin(), change.keys.end(), [](const std::string& k) {
      for (const LiveKey& key : live_keys())
        if (k == key.name) return key.level == kBody;
      return false;
    });
    change.body = body_key != change.keys.end();
    if (change.body) std::rotate(change.keys.begin(), body_key, body_key + 1);
    try {
      // Its start with its current body and integrator, and the changes (the spin's included).
      SceneConfig candidate = top->start_config();
      candidate.top = top->simulator().config().top;
      candidate.integrator = top->simulator().config().integrator;
      candidate = with_applicable_changes(candidate, config, old);
      validate(candidate);
      if (change.body && top->event() != Event::kNone)
        throw InvalidParameter(config.spin != old.spin ? "spin" : change.keys.front(),
                               std::string("the top stopped at its ") + to_string(top->event()) +
                                   " event: reset it before changing its body");
      top->require_on_the_floor(change.keys.front());
      change.config = with_applicable_changes(top->simulator().config(), config, old);
      if (change.body) {
        const double spin = config.spin != old.spin ? config.spin : top->snapshot().body_rates.z();
        change.body_change = top->prepare_body(change.config.top, change.config.integrator, spin, change.keys.front());
      }
    } catch (const InvalidParameter& error) {
      return refuse(std::string(blame(error, change.keys).what()) +
                    (top->name().empty() ? "" : " (top " + top->name() + ")"));
    }
    changes.push_back(std::move(change));
  }
  // Applied: a prepared body cannot fail; the core's update() checks the state itself, and if it
  // refuses one top, those already updated go back to what they had.
  std::vector<std::pair<TopInstance*, SceneConfig>> updated;  // each with its configuration before
  for (Change& change : changes) {
    TopInstance* top = change.top;
    if (change.body) {
      top->change_body(std::move(change.body_change));
      continue;
    }
    const SceneConfig before = top->simulator().config();
    try {
      if (top->update(change.config.top, change.config.integrator)) {
        // auto chose again for the current state (exact may refuse it now, or accept it again).
        ROS_WARN("spinning_top: the update switched the integrator of %s at t = %.9g s: now %s",
                 top->name().empty() ? "the top" : top->name().c_str(), top->time(),
                 top->simulator().integrator_description().c_str());
      }
      updated.emplace_back(top, before);
    } catch (const InvalidParameter& error) {
      for (auto back = updated.rbegin(); back != updated.rend(); ++back) {
        try {
          back->first->update(back->second.top, back->second.integrator);
        } catch (const InvalidParameter&) {
          ROS_ERROR("spinning_top: %s could not go back to its previous model after a refused change",
                    back->first->name().empty() ? "the top" : back->first->name().c_str());
        }
      }
      return refuse(std::string(blame(error, change.keys).what()) +
                    (top->name().empty() ? "" : " (top " + top->name() + ")"));
    }
  }
  if (!changes.empty()) send_static_transforms();
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
                     format("%.9f", stamp_at(clock_.time()).toSec()) + (paused_ ? " (still paused)" : "");
  ROS_INFO("spinning_top: %s", response.message.c_str());
  return true;
}

bool SpinningTopNode::on_reload(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response) {
  // The scene keys are read again and validated for every top the parameters describe before
  // any top changes; tops spawned by ~spawn are reset.
  std::vector<std::pair<std::string, SceneConfig>> configs;
  std::vector<Eigen::Vector2d> positions;
  NodeKeys node_keys;
  try {
    const ParameterTree tree = ParameterTree::fetch(private_nh_.getNamespace());
    configs = read_tops(tree, node_keys);
    for (const auto& [name, config] : configs) {
      if (find_top(name) == nullptr)
        throw InvalidParameter("tops", "'" + name + "' is not running: ~tops is read at start only");
      positions.push_back(read_tip_position(tree, name));
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
  write_back(node_keys);
  send_static_transforms();
  update_hardware_id();
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
  // Following a clock: the next tick one period after the external time now.
  if (paused_ && clock_role_ == ClockRole::kFollow && external_anchored_)
    anchor_stamps(std::max(external_time_, last_stamp_));
  paused_ = false;
  if (clock_role_ == ClockRole::kFollow) follow_to(ros::WallTime::now());
  return true;
}

bool SpinningTopNode::on_step(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response) {
  if (!paused_) {
    response.success = false;
    response.message = "~step advances one tick while paused: call ~pause first";
    return true;
  }
  // Following a clock: the step is stamped one period after the external time now (or after
  // the last stamp), not where the pause left the stamps.
  if (clock_role_ == ClockRole::kFollow && external_anchored_ && !tick_unfinished_)
    anchor_stamps(std::max(external_time_, last_stamp_));
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
      // The node's own keys (those of its files and ~<key>): its namespace's scene members only,
      // not every top's URDF beside them.
      keys = read_node_keys(ParameterTree::fetch_members(private_nh_.getNamespace(), node_key_members())).keys;
    } else {
      if (request.scene_file.size() > kMaxPathLength)
        throw InvalidParameter("scene_file", "'" + excerpt(request.scene_file) + "' is longer than " +
                                                 std::to_string(kMaxPathLength) + " characters");
      try {
        keys = read_scene_file(request.scene_file);
      } catch (const SceneFileError& error) {
        throw InvalidParameter("scene_file", error.what());
      }
    }
    if (request.keys.size() > kMaxSpawnKeys)
      throw InvalidParameter("keys", std::to_string(request.keys.size()) + " assignments; at most " +
                                         std::to_string(kMaxSpawnKeys));
    const std::vector<std::string> known = parameter_keys();
    for (const std::string& assignment : request.keys) {
      const std::size_t equals = assignment.find('=');
      if (equals == std::string::npos || equals == 0)
        throw InvalidParameter("keys", "'" + excerpt(assignment) + "' is not key=value (e.g. initial/spin=80)");
      const std::string key = assignment.substr(0, equals);
      if (std::find(known.begin(), known.end(), key) == known.end()) {
        const std::string nearest = nearest_name(key, known);
        throw InvalidParameter("keys", "'" + excerpt(key) + "' is not a scene key" +
                                           (nearest.empty() ? "" : " (did you mean " + nearest + "?)") +
                                           "; `simulate --help` lists them");
      }
      if (assignment.size() - equals - 1 > kMaxValueLength)
        throw InvalidParameter(key, "the value '" + excerpt(assignment.substr(equals + 1)) + "' is longer than " +
                                        std::to_string(kMaxValueLength) + " characters");
      keys[key] = assignment.substr(equals + 1);
    }
    const SceneConfig config = parse_scene_config(keys, /*require_all=*/false);
    add_top(make_top(request.name, config, Eigen::Vector2d(request.x, request.y), settings_.spawn_topics),
            settings_.spawn_reset_services);
  } catch (const InvalidParameter& error) {
    response.message = std::string("spawn refused: ") + error.what();
    ROS_WARN("spinning_top: %s", response.message.c_str());
    return true;
  }
  send_static_transforms();
  const TopInstance& top = *tops_.back();
  response.success = true;
  response.message = "top " + top.name() + ": scene " + to_string(top.simulator().config().scene) + ", " +
                     top.simulator().integrator_description() + "; frames " + top.body_frame() + ", " +
                     top.contact_frame() + at_release(top.simulator()) + "; its state on " +
                     private_nh_.resolveName("states") + " and its events on " + private_nh_.resolveName("events") +
                     (settings_.spawn_topics.empty() ? " (no topics of its own: ~spawn_topics)" : "");
  // DEBUG, not INFO: the caller has the message in the response, and roscpp puts the names of all
  // the node's topics in each /rosout record (7,000 names, ~165 kB, at the 1,000th top).
  ROS_DEBUG("spinning_top: spawned %s", response.message.c_str());
  return true;
}

bool SpinningTopNode::on_kill(Kill::Request& request, Kill::Response& response) {
  const auto it = std::find_if(tops_.begin(), tops_.end(), [&](const auto& top) { return top->name() == request.name; });
  if (request.name.empty() || it == tops_.end()) {
    response.success = false;
    response.message = request.name.empty() ? "kill: name: give the name of a spawned top"
                                            : "kill: name: no top named '" + excerpt(request.name) + "'";
    return true;
  }
  diagnostics_->removeByName(request.name);
  const std::string service = private_nh_.resolveName(request.name + "/reset");
  top_reset_services_.erase(std::remove_if(top_reset_services_.begin(), top_reset_services_.end(),
                                           [&](const ros::ServiceServer& s) { return s.getService() == service; }),
                            top_reset_services_.end());
  private_nh_.deleteParam(request.name + "/robot_description");  // a killed top's URDF goes with it
  tops_.erase(it);
  send_static_transforms();
  update_hardware_id();
  response.success = true;
  response.message = "killed " + request.name;
  ROS_DEBUG("spinning_top: %s", response.message.c_str());  // as a spawn's: the response has it
  return true;
}

bool SpinningTopNode::on_set_state(SetState::Request& request, SetState::Response& response) {
  TopInstance* top = find_top(request.name);
  response.success = false;
  if (top == nullptr) {
    response.message = "set_state refused, nothing changed: name: no top named '" + excerpt(request.name) + "'";
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
  response.message = format("state set; the top's simulated time 0 is stamped %.9f", stamp_at(clock_.time()).toSec()) +
                     at_release(top->simulator());
  return true;
}

bool SpinningTopNode::on_get_state(GetState::Request& request, GetState::Response& response) {
  // "" is the node's own top, or the only top when it has one named top.
  TopInstance* top = find_top(request.name);
  if (top == nullptr && request.name.empty() && tops_.size() == 1) top = tops_.front().get();
  response.success = false;
  if (top == nullptr) {
    response.message = "get_state: name: no top named '" + excerpt(request.name) + "'";
    return true;
  }
  SettableState state;
  try {
    state = top->settable_state();
  } catch (const InvalidParameter& error) {
    response.message = std::string("get_state: ") + error.what() + (top->name().empty() ? "" : " (top " + top->name() + ")");
    return true;
  }
  response.time = top->time();
  response.tilt = state.initial.tilt;
  response.heading = state.initial.heading;
  response.spin_angle = state.initial.spin_angle;
  response.precession_rate = state.initial.precession_rate;
  response.nutation_rate = state.initial.nutation_rate;
  response.spin = state.initial.spin;
  response.velocity_x = state.initial.velocity_x;
  response.velocity_y = state.initial.velocity_y;
  response.x = state.tip.x();
  response.y = state.tip.y();
  response.success = true;
  response.message = format("state at t = %.17g s", response.time) +
                     format(" (stamped %.9f); ~set_state sets it back", stamp_at(clock_.time()).toSec());
  return true;
}

}  // namespace ros_front_end
}  // namespace spinning_top
