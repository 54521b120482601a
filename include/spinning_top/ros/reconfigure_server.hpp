// dynamic_reconfigure's protocol for the node's live keys (SpinningTopConfig): the service
// ~set_parameters and the latched topics ~parameter_descriptions and ~parameter_updates, as
// dynamic_reconfigure::Server serves them, so that dynparam, rqt_reconfigure and the Python
// client work unchanged. What that server cannot do, this one does: a request that names a
// parameter the node does not have, gives a live key with another type than double, or gives one
// twice is refused naming it (dynamic_reconfigure::Server ignores such entries and applies the
// rest, which the node then reported as "applied"). Header-only: the node's only user.
#pragma once

#include <dynamic_reconfigure/ConfigDescription.h>
#include <dynamic_reconfigure/Reconfigure.h>
#include <ros/ros.h>

#include <algorithm>
#include <functional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "spinning_top/SpinningTopConfig.h"
#include "spinning_top/config.hpp"
#include "spinning_top/ros/node_settings.hpp"

namespace spinning_top {
namespace ros_front_end {

class ReconfigureServer {
 public:
  /// `apply(config, levels)`: the node applies `config` or refuses it by setting it back to the
  /// previous configuration (dynamic_reconfigure::Server's callback contract). `refuse(why)`:
  /// a request refused here, before `apply` ("<key>: <reason>").
  using Apply = std::function<void(SpinningTopConfig& config, std::uint32_t levels)>;
  using Refuse = std::function<void(const std::string& why)>;
  /// Whether a parameter's value goes on the parameter server (~<name>), as dynamic_reconfigure
  /// writes every one.
  using Written = std::function<bool(const std::string& name)>;

  /// Publishes the descriptions and `initial` (also written to the parameter server, as
  /// dynamic_reconfigure does), calls apply(initial, ~0) once, then serves ~set_parameters.
  ReconfigureServer(ros::NodeHandle nh, const SpinningTopConfig& initial, Apply apply, Refuse refuse, Written written)
      : nh_(nh), config_(initial), apply_(std::move(apply)), refuse_(std::move(refuse)), written_(std::move(written)) {
    descriptions_ = nh_.advertise<dynamic_reconfigure::ConfigDescription>("parameter_descriptions", 1, true);
    updates_ = nh_.advertise<dynamic_reconfigure::Config>("parameter_updates", 1, true);
    if (descriptions_) descriptions_.publish(SpinningTopConfig::__getDescriptionMessage__());
    apply_(config_, ~0u);  // as dynamic_reconfigure::Server::setCallback: everything is new
    publish();
    service_ = nh_.advertiseService("set_parameters", &ReconfigureServer::on_set, this);
  }
  ReconfigureServer(const ReconfigureServer&) = delete;
  ReconfigureServer& operator=(const ReconfigureServer&) = delete;

  const SpinningTopConfig& config() const { return config_; }

  /// Why a request cannot be read as changes of our live keys ("" if it can): the first entry
  /// that names no live key, is not a double, or repeats a key. Groups (the clients send their
  /// states along) are not parameters.
  static std::string unreadable(const dynamic_reconfigure::Config& request) {
    std::vector<std::string> known;
    for (const auto& parameter : SpinningTopConfig::__getParamDescriptions__()) known.push_back(parameter->name);
    auto is_known = [&](const std::string& name) {
      return std::find(known.begin(), known.end(), name) != known.end();
    };
    auto unknown = [&](const std::string& name) {
      const std::string nearest = nearest_name(name, known);
      return (name.empty() ? std::string("(empty name)") : excerpt(name)) + ": no such live parameter" + (nearest.empty() ? "" : " (did you mean " + nearest + "?)") +
             "; the live parameters are those of cfg/SpinningTop.cfg";
    };
    auto wrong_type = [&](const std::string& name, const char* type) -> std::string {
      if (!is_known(name)) return unknown(name);
      return name + ": given as " + type + "; every live parameter is a double";
    };
    for (const auto& p : request.bools) return wrong_type(p.name, "a bool");
    for (const auto& p : request.ints) return wrong_type(p.name, "an int");
    for (const auto& p : request.strs) return wrong_type(p.name, "a string");
    std::set<std::string> seen;
    for (const auto& p : request.doubles) {
      if (!is_known(p.name)) return unknown(p.name);
      if (!seen.insert(p.name).second) return p.name + ": given twice in one request";
    }
    return "";
  }

 private:
  bool on_set(dynamic_reconfigure::Reconfigure::Request& request, dynamic_reconfigure::Reconfigure::Response& response) {
    const std::string why = unreadable(request.config);
    if (!why.empty()) {
      refuse_(why);
    } else {
      SpinningTopConfig config = config_;
      config.__fromMessage__(request.config);
      config.__clamp__();  // no bounds in the cfg (the node refuses instead): changes nothing
      const std::uint32_t levels = config_.__level__(config);
      apply_(config, levels);  // sets it back to the previous one when it refuses
      config_ = config;
      publish();
    }
    config_.__toMessage__(response.config);  // the configuration now in force
    return true;
  }

  /// The configuration in force: on ~parameter_updates and the parameter server (~<key>).
  void publish() {
    for (const auto& parameter : SpinningTopConfig::__getParamDescriptions__())
      if (written_(parameter->name)) parameter->toServer(nh_, config_);
    dynamic_reconfigure::Config message;
    config_.__toMessage__(message);
    if (updates_) updates_.publish(message);
  }

  ros::NodeHandle nh_;
  SpinningTopConfig config_;
  Apply apply_;
  Refuse refuse_;
  Written written_;
  ros::Publisher descriptions_, updates_;
  ros::ServiceServer service_;
};

}  // namespace ros_front_end
}  // namespace spinning_top
