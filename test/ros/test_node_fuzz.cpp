// rostest (test/node_fuzz.test), issue 19: an attacker's requests to the node's services, drawn
// from a fixed seed: random and garbage values for ~spawn, ~set_state, ~kill and dynamic_reconfigure
// (unknown names, other types, NaN, inf, 1e300, huge strings). Counted and asserted:
//   - no crash and no hang: every call is answered (a generous guard per call, not a speed bound);
//   - every refusal is one line that names a key ("spawn refused: <key>: ...", "refused: <key>: ..."
//     on ~status), never echoes a huge value or a 300-digit number;
//   - nothing non-finite is published, and no negative floor force, on /tf and every top's topics;
//   - the node still serves ~pause and ~resume at the end.
// The counts depend on the seed only; the run takes a few seconds.
#include <dynamic_reconfigure/BoolParameter.h>
#include <dynamic_reconfigure/DoubleParameter.h>
#include <dynamic_reconfigure/IntParameter.h>
#include <dynamic_reconfigure/Reconfigure.h>
#include <dynamic_reconfigure/StrParameter.h>
#include <geometry_msgs/PointStamped.h>
#include <geometry_msgs/TwistStamped.h>
#include <geometry_msgs/WrenchStamped.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <std_msgs/String.h>
#include <tf2_msgs/TFMessage.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <future>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <regex>
#include <set>
#include <string>
#include <vector>

#include "node_test_helpers.hpp"
#include "spinning_top/Kill.h"
#include "spinning_top/SetState.h"
#include "spinning_top/Spawn.h"
#include "spinning_top/SpinningTopConfig.h"
#include "spinning_top/TopEvent.h"
#include "spinning_top/TopState.h"
#include "spinning_top/TopStateArray.h"
#include "spinning_top/config.hpp"

using node_test::Recorder;
using node_test::trigger;
using node_test::wait_for;

namespace {

const std::string kNode = "/fuzzed";
const std::vector<std::string> kTops = {"a", "b", "c", "d"};  // the names a valid request uses

/// What was published that should never be: non-finite numbers and negative floor forces.
struct Watch {
  std::atomic<long> messages{0}, non_finite{0}, negative_force{0};
  std::atomic<long> broken{0};  // non_finite or energy_drift events: a state the core should have refused
  std::atomic<long> broken_on_events{0};  // the same, seen on the node's ~events
  std::vector<ros::Subscriber> subscribers;

  static bool ok(double x) { return std::isfinite(x); }
  static bool ok(const geometry_msgs::Vector3& v) { return ok(v.x) && ok(v.y) && ok(v.z); }
  static bool ok(const geometry_msgs::Point& v) { return ok(v.x) && ok(v.y) && ok(v.z); }
  void count(bool finite, bool negative = false) {
    ++messages;
    if (!finite) ++non_finite;
    if (negative) ++negative_force;
  }

  void watch(ros::NodeHandle& nh, const std::string& ns) {
    subscribers.push_back(nh.subscribe<geometry_msgs::WrenchStamped>(
        ns + "/normal_force", 1000, [this](const geometry_msgs::WrenchStamped::ConstPtr& m) {
          count(ok(m->wrench.force) && ok(m->wrench.torque), m->wrench.force.z < 0.0);
        }));
    subscribers.push_back(nh.subscribe<geometry_msgs::PointStamped>(
        ns + "/contact_point", 1000, [this](const geometry_msgs::PointStamped::ConstPtr& m) { count(ok(m->point)); }));
    subscribers.push_back(nh.subscribe<geometry_msgs::TwistStamped>(
        ns + "/twist", 1000, [this](const geometry_msgs::TwistStamped::ConstPtr& m) {
          count(ok(m->twist.linear) && ok(m->twist.angular));
        }));
    subscribers.push_back(nh.subscribe<spinning_top::TopEvent>(ns + "/event_stamped", 1000, [this](const spinning_top::TopEvent::ConstPtr& e) {
      if (e->event == "non_finite" || e->event == "energy_drift") ++broken;
    }));
    subscribers.push_back(nh.subscribe<spinning_top::TopState>(
        ns + "/state", 1000, [this](const spinning_top::TopState::ConstPtr& s) { check(*s); }));
  }
  void check(const spinning_top::TopState& s) {
    const double numbers[] = {s.time, s.tilt, s.heading, s.spin_angle, s.precession_rate, s.nutation_rate,
                              s.spin, s.normal_force, s.energy, s.dissipated_energy, s.energy_balance,
                              s.quaternion_norm_error, s.constraint_residual};
    bool finite = ok(s.angular_velocity) && ok(s.center_of_mass) && ok(s.center_of_mass_velocity) &&
                  ok(s.contact_point) && ok(s.contact_force);
    for (const double x : numbers) finite = finite && ok(x);
    count(finite, s.normal_force < 0.0);
  }
  /// The node's ~states and ~events: every top, those spawned without topics of their own too.
  void watch_every_top(ros::NodeHandle& nh, const std::string& node) {
    subscribers.push_back(nh.subscribe<spinning_top::TopStateArray>(
        node + "/states", 1000, [this](const spinning_top::TopStateArray::ConstPtr& m) {
          for (const auto& s : m->states) check(s);
        }));
    subscribers.push_back(nh.subscribe<spinning_top::TopEvent>(node + "/events", 1000, [this](const spinning_top::TopEvent::ConstPtr& e) {
      count(ok(e->time) && ok(e->contact_point));
      if (e->event == "non_finite" || e->event == "energy_drift") ++broken_on_events;
    }));
  }
  void watch_tf(ros::NodeHandle& nh) {
    subscribers.push_back(nh.subscribe<tf2_msgs::TFMessage>("/tf", 1000, [this](const tf2_msgs::TFMessage::ConstPtr& m) {
      bool finite = true;
      for (const auto& t : m->transforms)
        finite = finite && ok(t.transform.translation) && ok(t.transform.rotation.w) && ok(t.transform.rotation.x) &&
                 ok(t.transform.rotation.y) && ok(t.transform.rotation.z);
      count(finite);
    }));
  }
};

/// Random requests from a fixed seed.
class Attacker {
 public:
  explicit Attacker(unsigned seed) : rng_(seed) {}

  bool chance(double p) { return std::uniform_real_distribution<double>(0.0, 1.0)(rng_) < p; }
  template <class T>
  const T& pick(const std::vector<T>& pool) {
    return pool[std::uniform_int_distribution<std::size_t>(0, pool.size() - 1)(rng_)];
  }
  double uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng_); }

  /// A number: mostly garbage at the edges of double, sometimes an ordinary value.
  double number() {
    const double inf = std::numeric_limits<double>::infinity();
    static const std::vector<double> edges = {0.0, -0.0, 1.0, -1.0, 1e-300, 5e-324, 1e300, -1e300, inf, -inf,
                                              std::numeric_limits<double>::quiet_NaN(), 1e6, -1e6, 1e12,
                                              std::numeric_limits<double>::max()};
    return chance(0.5) ? pick(edges) : uniform(-10.0, 10.0);
  }
  std::string number_text(double x) {
    char buffer[64];
    std::snprintf(buffer, sizeof buffer, "%.17g", x);
    return buffer;
  }
  /// A top name: mostly one of kTops, else garbage (empty, a digit first, a slash, a space,
  /// non-ASCII, a control character, 100,000 characters).
  std::string name() {
    static const std::vector<std::string> garbage = {"", "1a", "a b", "a/b", "/a", "~a", "a-b", "\xc3\xa4",
                                                     "a\nb", std::string(100000, 'a'), std::string(65, 'n'), "__"};
    return chance(0.8) ? pick(kTops) : pick(garbage);
  }
  /// key=value for ~spawn: a scene key with a sensible or a garbage value, or a garbage key.
  std::string assignment() {
    static const std::vector<std::string> keys = spinning_top::parameter_keys();
    static const std::vector<std::string> bad_keys = {"", "mas", "initial/", "/mass", "initial//tilt",
                                                      std::string(5000, 'k'), "rate", "tops", "x"};
    static const std::vector<std::string> bad_values = {"", "abc", "0x10", "1e", "--1", "9.8.1", "\"9.8\"", "nan",
                                                        "inf", "1e400", "-1e400", std::string(2000, '9'), "\xc3\xa4",
                                                        "010", "1_000", "0b1", ".inf", "~", "null", "[1]", "{a: 1}"};
    if (chance(0.1)) return pick(bad_keys) + "=" + number_text(number());
    if (chance(0.05)) return pick(keys);  // no '='
    const std::string key = pick(keys);
    std::string value;
    if (key == "scene") value = chance(0.8) ? pick(std::vector<std::string>{"fixed_tip", "frictionless", "viscous"}) : pick(bad_values);
    else if (key == "integrator") value = chance(0.7) ? pick(std::vector<std::string>{"auto", "dop853", "exact"}) : pick(bad_values);
    else if (key == "after_lift_off") value = chance(0.8) ? pick(std::vector<std::string>{"fly", "stop"}) : pick(bad_values);
    else if (key == "step") value = chance(0.5) ? "1e-3" : pick(bad_values);  // no tiny steps: the run stays lean
    else value = chance(0.3) ? pick(bad_values) : number_text(key.rfind("initial/", 0) == 0 && chance(0.7) ? uniform(-1.0, 1.0) : number());
    return key + "=" + value;
  }
  std::string scene_file() {
    static const std::vector<std::string> files = {"", "", "", "", SPINNING_TOP_SOURCE_DIR "/config/frictionless.yaml",
                                                   SPINNING_TOP_SOURCE_DIR "/config/extreme/lift_off.yaml",
                                                   "/nonexistent/scene.yaml", "/", "/dev/null",
                                                   SPINNING_TOP_SOURCE_DIR "/package.xml", std::string(10000, '/')};
    return pick(files);
  }

 private:
  std::mt19937 rng_;
};

/// "<prefix><key>: <reason>": the key of a refusal ("" if the message is not so).
std::string refused_key(const std::string& message, const std::string& prefix) {
  if (message.compare(0, prefix.size(), prefix) != 0) return "";
  const std::string rest = message.substr(prefix.size());
  const std::size_t colon = rest.find(": ");
  return colon == std::string::npos || colon + 2 == rest.size() ? "" : rest.substr(0, colon);
}

/// How a message names a parameter that is not one of ours: at most 40 characters of it.
std::string as_named(const std::string& name) {
  if (name.empty()) return "(empty name)";
  return name.size() <= 40 ? name : name.substr(0, 40) + "... (" + std::to_string(name.size()) + " characters)";
}

/// What a message must never be: several lines, long, or a number of 20 and more digits that
/// it printed itself (a quoted excerpt of the request's own text, at most 40 characters, may be
/// digits).
std::string unclear(const std::string& message) {
  static const std::regex long_number("[0-9]{20,}"), quoted("'[^']*'");
  if (message.find('\n') != std::string::npos) return "several lines";
  if (message.size() > 500) return std::to_string(message.size()) + " characters";
  if (std::regex_search(std::regex_replace(message, quoted, "''"), long_number)) return "a number of 20 or more digits";
  return "";
}

template <class Service>
bool call_with_guard(ros::ServiceClient& client, Service& srv) {
  auto answered = std::async(std::launch::async, [&] { return client.call(srv); });
  if (answered.wait_for(std::chrono::seconds(30)) != std::future_status::ready) {
    ADD_FAILURE() << client.getService() << " did not answer within 30 s: a hang";
    std::abort();  // the call's thread cannot be joined; the test cannot go on
  }
  return answered.get();
}

}  // namespace

TEST(NodeFuzz, GarbageRequestsAreRefusedNamingAKeyAndNothingBadIsPublished) {
  ros::NodeHandle nh;
  Watch watch;
  watch.watch_tf(nh);
  watch.watch(nh, kNode);
  for (const std::string& top : kTops) watch.watch(nh, kNode + "/" + top);  // node_fuzz.test: ~spawn_topics
  watch.watch_every_top(nh, kNode);
  Recorder<std_msgs::String> status(nh, kNode + "/status");
  for (const char* service : {"spawn", "set_state", "kill", "set_parameters"})
    ASSERT_TRUE(ros::service::waitForService(kNode + "/" + service, ros::Duration(30.0))) << service;
  ros::ServiceClient spawn = nh.serviceClient<spinning_top::Spawn>(kNode + "/spawn", true);
  ros::ServiceClient set_state = nh.serviceClient<spinning_top::SetState>(kNode + "/set_state", true);
  ros::ServiceClient kill = nh.serviceClient<spinning_top::Kill>(kNode + "/kill", true);
  ros::ServiceClient reconfigure = nh.serviceClient<dynamic_reconfigure::Reconfigure>(kNode + "/set_parameters", true);
  ASSERT_TRUE(wait_for([&] { return !status.messages().empty(); }, 10.0)) << "no ~status at start";

  std::set<std::string> keys = {"name", "keys", "scene_file", "x", "y"};
  for (const std::string& key : spinning_top::parameter_keys()) keys.insert(key);
  std::set<std::string> live;
  for (const auto& parameter : spinning_top::SpinningTopConfig::__getParamDescriptions__()) live.insert(parameter->name);

  Attacker attacker(19);
  std::map<std::string, std::map<std::string, int>> table;  // service -> accepted / refused
  auto refusal = [&](const std::string& service, const std::string& message, const std::string& prefix,
                     const std::set<std::string>& allowed, const std::set<std::string>& also = {}) {
    ++table[service]["refused"];
    const std::string key = refused_key(message, prefix);
    EXPECT_TRUE(allowed.count(key) > 0 || also.count(key) > 0)
        << service << ": the refusal names no key: " << node_test::shown(message);
    const std::string why = unclear(message);
    EXPECT_EQ(why, "") << service << ": " << node_test::shown(message);
  };

  const int calls = 400;
  for (int i = 0; i < calls; ++i) {
    const double what = attacker.uniform(0.0, 1.0);
    if (what < 0.35) {
      spinning_top::Spawn srv;
      srv.request.name = attacker.name();
      srv.request.scene_file = attacker.scene_file();
      const int count = attacker.chance(0.02) ? 300 : static_cast<int>(attacker.uniform(0.0, 5.0));
      for (int k = 0; k < count; ++k) srv.request.keys.push_back(attacker.assignment());
      srv.request.x = attacker.chance(0.8) ? attacker.uniform(-1.0, 1.0) : attacker.number();
      srv.request.y = attacker.chance(0.8) ? attacker.uniform(-1.0, 1.0) : attacker.number();
      ASSERT_TRUE(call_with_guard(spawn, srv)) << "~spawn call failed (the node died?) at call " << i;
      if (srv.response.success) ++table["spawn"]["accepted"];
      else refusal("spawn", srv.response.message, "spawn refused: ", keys);
    } else if (what < 0.6) {
      spinning_top::SetState srv;
      auto& r = srv.request;
      r.name = attacker.chance(0.9) ? (attacker.chance(0.2) ? "" : attacker.name()) : "nobody";
      double* fields[] = {&r.tilt, &r.heading, &r.spin_angle, &r.precession_rate, &r.nutation_rate, &r.spin,
                          &r.velocity_x, &r.velocity_y, &r.x, &r.y};
      for (double* f : fields) *f = attacker.chance(0.75) ? attacker.uniform(-0.5, 0.5) : attacker.number();
      ASSERT_TRUE(call_with_guard(set_state, srv)) << "~set_state call failed at call " << i;
      if (srv.response.success) ++table["set_state"]["accepted"];
      else refusal("set_state", srv.response.message, "set_state refused, nothing changed: ", keys);
    } else if (what < 0.75) {
      spinning_top::Kill srv;
      srv.request.name = attacker.name();
      ASSERT_TRUE(call_with_guard(kill, srv)) << "~kill call failed at call " << i;
      if (srv.response.success) ++table["kill"]["accepted"];
      else refusal("kill", srv.response.message, "kill: ", {"name"});
    } else {
      dynamic_reconfigure::Reconfigure srv;
      std::vector<std::string> names(live.begin(), live.end());
      const int count = 1 + static_cast<int>(attacker.uniform(0.0, 3.0));
      std::set<std::string> given;
      for (int k = 0; k < count; ++k) {
        dynamic_reconfigure::DoubleParameter p;
        p.name = attacker.chance(0.9) ? attacker.pick(names) : attacker.pick(std::vector<std::string>{
                                                                   "bogus", "mas", "", std::string(3000, 'z')});
        p.value = attacker.number();
        given.insert(p.name);
        srv.request.config.doubles.push_back(p);
      }
      if (attacker.chance(0.05)) {
        dynamic_reconfigure::IntParameter p;
        p.name = attacker.pick(names);
        p.value = 3;
        srv.request.config.ints.push_back(p);
        given.insert(p.name);
      }
      if (attacker.chance(0.05)) {
        dynamic_reconfigure::StrParameter p;
        p.name = attacker.pick(names);
        p.value = "9.8";
        srv.request.config.strs.push_back(p);
        given.insert(p.name);
      }
      const size_t before = status.size();
      ASSERT_TRUE(call_with_guard(reconfigure, srv)) << "~set_parameters call failed at call " << i;
      for (const auto& d : srv.response.config.doubles)
        EXPECT_TRUE(std::isfinite(d.value)) << "the configuration in force has " << d.name << " = " << d.value;
      ASSERT_TRUE(wait_for([&] { return status.size() > before; }, 30.0)) << "no ~status for a reconfigure";
      const std::string message = status.messages().back().data;
      if (message.rfind("applied: ", 0) == 0) {
        ++table["reconfigure"]["accepted"];
      } else {
        std::set<std::string> named;
        for (const std::string& g : given) named.insert(as_named(g));
        refusal("reconfigure", message, "refused: ", live, named);
      }
    }
  }

  // Alive and serving; what it published meanwhile was finite, with no negative floor force.
  EXPECT_TRUE(trigger(kNode + "/pause").success);
  EXPECT_TRUE(trigger(kNode + "/resume").success);
  const long published = watch.messages;
  ASSERT_TRUE(wait_for([&] { return watch.messages > published + 50; }, 30.0)) << "nothing published at the end";
  EXPECT_EQ(watch.non_finite, 0) << "non-finite values published";
  EXPECT_EQ(watch.negative_force, 0) << "negative floor forces published";
  // Accepted garbage: a request the core's validation let through whose run ends at once with
  // non_finite or energy_drift (set_state with a velocity of 1e300 on the viscous top: issue 19,
  // item 6, the core's bounds). Counted and printed; the node publishes nothing non-finite of it.
  std::printf("[ measured ] accepted garbage (runs ended at once by non_finite or energy_drift): %ld (~events: %ld)\n",
              static_cast<long>(watch.broken), static_cast<long>(watch.broken_on_events));
  std::printf("[ measured ] %d calls, %ld messages checked:", calls, static_cast<long>(watch.messages));
  for (const auto& [service, counts] : table)
    std::printf(" %s %d accepted / %d refused;", service.c_str(), counts.count("accepted") ? counts.at("accepted") : 0,
                counts.count("refused") ? counts.at("refused") : 0);
  std::printf("\n");
}

int main(int argc, char** argv) { return node_test::run_node_tests(argc, argv, "test_node_fuzz", 2); }
