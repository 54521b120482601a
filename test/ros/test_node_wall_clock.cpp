// Wall-clock stamps under load (node_wall_clock.test): 1 kHz at real-time factor 1 with two busy
// loops competing for the two cores for 15 s.
#include <diagnostic_msgs/DiagnosticArray.h>
#include <geometry_msgs/PointStamped.h>
#include <gtest/gtest.h>
#include <rosgraph_msgs/Clock.h>
#include <tf2_msgs/TFMessage.h>
#include <signal.h>

#include <algorithm>
#include <cstdlib>
#include <cstdio>
#include <vector>

#include "node_test_helpers.hpp"

namespace {

/// Busy loops, each stopped by its PID when this goes (also when a test fails).
class BusyLoops {
 public:
  explicit BusyLoops(int count) {
    for (int i = 0; i < count; ++i) {
      FILE* pipe = popen("sh -c 'while :; do :; done' >/dev/null 2>&1 & echo $!", "r");
      int pid = 0;
      if (pipe != nullptr && std::fscanf(pipe, "%d", &pid) == 1 && pid > 0) pids_.push_back(pid);
      if (pipe != nullptr) pclose(pipe);
    }
  }
  ~BusyLoops() {
    for (const int pid : pids_) kill(pid, SIGKILL);
  }
  size_t size() const { return pids_.size(); }

 private:
  std::vector<int> pids_;
};

struct Arrival {
  ros::Time stamp;  // as sent: a double of 1.7e9 s would only resolve 0.2 us
  double wall;
};

// Under two busy loops for 15 s, what holds however loaded the machine is (issue 19, item 15:
// the old delay and quiet-window thresholds failed at a load of 3 in a catkin workspace):
// - no tick is dropped: consecutive stamps exactly one tick apart (late ticks are taken late;
//   ~max_lag is an hour here, so none is given up however long the machine stalls);
// - no stamp leads the wall clock at its arrival by more than half a tick (a tick is taken from
//   half a period before its slot, never earlier);
// - /clock every 10th tick and tf every 4th, exactly.
// How far behind the wall clock the stamps arrive, and how often diagnostics stay OK, depend
// on the load: they are printed here and measured in bench/wall_clock_lag.py, not asserted.
TEST(WallClock, NoTickDroppedOrEarlyUnderLoad) {
  ros::NodeHandle nh;
  std::mutex mutex;
  std::vector<Arrival> arrivals;
  ros::Subscriber subscriber = nh.subscribe<geometry_msgs::PointStamped>(
      "/wall/contact_point", 100000, [&](const geometry_msgs::PointStamped::ConstPtr& m) {
        const double wall = ros::WallTime::now().toSec();
        std::lock_guard<std::mutex> lock(mutex);
        arrivals.push_back({m->header.stamp, wall});
      });
  ASSERT_TRUE(node_test::wait_for([&] { std::lock_guard<std::mutex> lock(mutex); return arrivals.size() > 100; }, 60.0));
  node_test::Recorder<rosgraph_msgs::Clock> clock(nh, "/clock", 100000);
  node_test::Recorder<tf2_msgs::TFMessage> tf(nh, "/tf", 100000);
  node_test::Recorder<diagnostic_msgs::DiagnosticArray> diagnostics(nh, "/diagnostics", 1000);
  {
    BusyLoops busy(2);
    ASSERT_EQ(busy.size(), 2u);
    ros::WallDuration(15.0).sleep();
  }
  subscriber.shutdown();
  std::lock_guard<std::mutex> lock(mutex);
  ASSERT_GT(arrivals.size(), 1000u);
  // Every tick arrived: consecutive stamps 1 ms apart (to the stamps' rounding, 1 ns).
  size_t gaps = 0;
  for (size_t i = 1; i < arrivals.size(); ++i)
    gaps += std::llabs((arrivals[i].stamp - arrivals[i - 1].stamp).toNSec() - 1000000) > 1;
  EXPECT_EQ(gaps, 0u);
  // Never early: the wall clock at arrival is at least the stamp less half a tick.
  std::vector<double> delays;
  for (const Arrival& a : arrivals) delays.push_back(a.wall - a.stamp.toSec());
  std::vector<double> last_second;
  for (const Arrival& a : arrivals)
    if (a.wall > arrivals.back().wall - 1.0) last_second.push_back(a.wall - a.stamp.toSec());
  std::sort(delays.begin(), delays.end());
  std::sort(last_second.begin(), last_second.end());
  EXPECT_GT(delays.front(), -0.5e-3) << "a stamp ahead of the wall clock";
  // ~clock_rate 100 and ~tf_rate 250 of the 1 kHz ticks: /clock every 10th tick (stamps 10 ms
  // apart, exactly), tf every 4th.
  const auto clocks = clock.messages();
  ASSERT_GT(clocks.size(), 100u);
  for (size_t i = 1; i < clocks.size(); ++i) ASSERT_NEAR((clocks[i].clock - clocks[i - 1].clock).toSec(), 0.01, 1e-9) << i;
  const auto transforms = tf.messages();
  ASSERT_GT(transforms.size(), 250u);
  for (size_t i = 1; i < transforms.size(); ++i)
    ASSERT_NEAR((transforms[i].transforms[0].header.stamp - transforms[i - 1].transforms[0].header.stamp).toSec(), 0.004, 1e-9);
  // Diagnostics report the pacing; whether a window is OK depends on the load (printed only).
  size_t windows = 0, quiet = 0;
  for (const auto& array : diagnostics.messages())
    for (const auto& status : array.status)
      if (status.name == "wall: simulation") {
        ++windows;
        quiet += status.level == diagnostic_msgs::DiagnosticStatus::OK;
      }
  EXPECT_GT(windows, 0u);
  std::printf("diagnostics: %zu of %zu windows OK under two busy loops\n", quiet, windows);
  std::printf("wall clock: %zu ticks over %.1f s; last second: least delay %.3f ms, median %.3f ms, max %.3f ms\n",
              arrivals.size(), arrivals.back().wall - arrivals.front().wall, 1e3 * last_second.front(),
              1e3 * last_second[last_second.size() / 2], 1e3 * last_second.back());
}

}  // namespace

int main(int argc, char** argv) { return node_test::run_node_tests(argc, argv, "test_node_wall_clock", 1); }
