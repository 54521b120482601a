// rostest (test/node_determinism.test, use_sim_time): determinism is a promise (issue 10,
// item 5; README "Reliability"). The node is run twice on the same inputs, once at real-time
// factor 1 with the default tick budget, once as fast as possible with the smallest budget (1e-4 s:
// every tick is split across many timer callbacks), and the samples published at the same
// stamps (simulated time) are compared: tf, contact point and floor force, bit for bit.
// The physics is the viscous scene with rk4 at a 1e-6 s step: 1000 substeps per tick, so that the
// split ticks resume the fixed-step plan mid-way.
#include <geometry_msgs/PointStamped.h>
#include <geometry_msgs/WrenchStamped.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <signal.h>
#include <sys/wait.h>
#include <tf2_msgs/TFMessage.h>
#include <unistd.h>

#include <array>
#include <cstring>
#include <map>
#include <mutex>
#include <string>

#include "node_test_helpers.hpp"

using node_test::trigger;
using node_test::wait_for;

namespace {

using Sample = std::array<double, 14>;  // G, q (tf), P (contact point), force (x, y, R)

/// Everything one node run published, by stamp [ns]; a sample is complete when all three
/// topics have filled their part.
class Collector {
 public:
  Collector(ros::NodeHandle& nh, const std::string& name) : name_(name) {
    tf_ = nh.subscribe<tf2_msgs::TFMessage>("/tf", 100000, [this](const tf2_msgs::TFMessage::ConstPtr& m) {
      std::lock_guard<std::mutex> lock(mutex_);
      for (const auto& t : m->transforms) {
        if (t.child_frame_id != name_ + "_top") continue;
        Sample& s = samples_[t.header.stamp.toNSec()];
        const double values[] = {t.transform.translation.x, t.transform.translation.y, t.transform.translation.z,
                                 t.transform.rotation.w,    t.transform.rotation.x,    t.transform.rotation.y,
                                 t.transform.rotation.z};
        std::memcpy(s.data(), values, sizeof values);
        ++parts_[t.header.stamp.toNSec()];
      }
    });
    point_ = nh.subscribe<geometry_msgs::PointStamped>(
        "/" + name + "/contact_point", 100000, [this](const geometry_msgs::PointStamped::ConstPtr& m) {
          std::lock_guard<std::mutex> lock(mutex_);
          Sample& s = samples_[m->header.stamp.toNSec()];
          s[7] = m->point.x, s[8] = m->point.y, s[9] = m->point.z;
          ++parts_[m->header.stamp.toNSec()];
        });
    force_ = nh.subscribe<geometry_msgs::WrenchStamped>(
        "/" + name + "/normal_force", 100000, [this](const geometry_msgs::WrenchStamped::ConstPtr& m) {
          std::lock_guard<std::mutex> lock(mutex_);
          Sample& s = samples_[m->header.stamp.toNSec()];
          s[10] = m->wrench.force.x, s[11] = m->wrench.force.y, s[12] = m->wrench.force.z, s[13] = 1.0;
          ++parts_[m->header.stamp.toNSec()];
          latest_ = std::max(latest_, m->header.stamp.toSec());
        });
  }
  bool connected() const { return tf_.getNumPublishers() > 0 && point_.getNumPublishers() > 0 && force_.getNumPublishers() > 0; }
  double latest() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return latest_;
  }
  std::map<uint64_t, Sample> complete() const {
    std::lock_guard<std::mutex> lock(mutex_);
    std::map<uint64_t, Sample> out;
    for (const auto& kv : samples_)
      if (parts_.at(kv.first) == 3) out[kv.first] = kv.second;
    return out;
  }

 private:
  std::string name_;
  ros::Subscriber tf_, point_, force_;
  mutable std::mutex mutex_;
  std::map<uint64_t, Sample> samples_;
  std::map<uint64_t, int> parts_;
  double latest_ = 0.0;
};

/// Runs the node as `name` until it has published simulated time `until`; returns what it published.
std::map<uint64_t, Sample> run(const std::string& name, const char* real_time_factor, const char* tick_budget,
                               double until) {
  ros::NodeHandle nh;
  Collector collector(nh, name);
  const pid_t pid = fork();
  if (pid == 0) {
    const std::string node_name = "__name:=" + name, body = "_body_frame:=" + name + "_top",
                      contact = "_contact_frame:=" + name + "_contact",
                      rtf = std::string("_real_time_factor:=") + real_time_factor,
                      budget = std::string("_tick_budget:=") + tick_budget;
    execl(SPINNING_TOP_NODE_EXECUTABLE, SPINNING_TOP_NODE_EXECUTABLE, node_name.c_str(), body.c_str(), contact.c_str(),
          rtf.c_str(), budget.c_str(), "_start_paused:=true", "_scene:=viscous", "_friction:=0.02",
          "_integrator:=rk4", "_step:=1.0e-6", "_initial/precession_rate:=3.0", "_initial/velocity_x:=0.01",
          static_cast<char*>(nullptr));
    _exit(127);
  }
  EXPECT_GT(pid, 0);
  EXPECT_TRUE(wait_for([&] { return collector.connected(); }, 20.0)) << name << " never connected";
  EXPECT_TRUE(trigger("/" + name + "/resume").success);
  EXPECT_TRUE(wait_for([&] { return collector.latest() >= until; }, 60.0)) << name << " reached " << collector.latest();
  kill(pid, SIGINT);
  int status = 0;
  waitpid(pid, &status, 0);
  return collector.complete();
}

}  // namespace

TEST(NodeDeterminism, TwoRunsAtDifferentPaceAndBudgetPublishTheSameSamples) {
  const auto paced = run("paced", "1.0", "0.05", 0.3);
  const auto hurried = run("hurried", "0", "0.0001", 0.3);
  long common = 0, differing = 0;
  for (const auto& kv : paced) {
    const auto other = hurried.find(kv.first);
    if (other == hurried.end()) continue;
    ++common;
    if (std::memcmp(kv.second.data(), other->second.data(), sizeof(Sample)) != 0) {
      if (++differing <= 5) ADD_FAILURE() << "sample at " << kv.first << " ns differs";
    }
  }
  std::printf("[ measured ] %zu and %zu samples, %ld at common stamps, %ld differing\n", paced.size(), hurried.size(),
              common, differing);
  EXPECT_GE(common, 250) << "too few samples to compare";
  EXPECT_EQ(differing, 0);
}

int main(int argc, char** argv) { return node_test::run_node_tests(argc, argv, "test_node_determinism", 2); }
