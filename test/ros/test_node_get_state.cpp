// ~get_state and ~set_state: save, set back bit for bit, run again alike (node_get_state.test).
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "node_test_helpers.hpp"
#include "spinning_top/GetState.h"
#include "spinning_top/SetState.h"
#include "spinning_top/TopState.h"

using node_test::Recorder;
using node_test::trigger;
using node_test::wait_for;

namespace {

const char* const kTops[] = {"slider", "pivot"};

spinning_top::GetState::Response get_state(const std::string& name) {
  EXPECT_TRUE(ros::service::waitForService("/saver/get_state", ros::Duration(10.0)));
  spinning_top::GetState srv;
  srv.request.name = name;
  EXPECT_TRUE(ros::service::call("/saver/get_state", srv)) << name;
  return srv.response;
}

spinning_top::SetState::Response set_state(const std::string& name, const spinning_top::GetState::Response& s) {
  spinning_top::SetState srv;
  srv.request.name = name;
  srv.request.tilt = s.tilt;
  srv.request.heading = s.heading;
  srv.request.spin_angle = s.spin_angle;
  srv.request.precession_rate = s.precession_rate;
  srv.request.nutation_rate = s.nutation_rate;
  srv.request.spin = s.spin;
  srv.request.velocity_x = s.velocity_x;
  srv.request.velocity_y = s.velocity_y;
  srv.request.x = s.x;
  srv.request.y = s.y;
  EXPECT_TRUE(ros::service::call("/saver/set_state", srv)) << name;
  return srv.response;
}

/// The fields ~set_state takes, bit for bit.
std::vector<double> fields(const spinning_top::GetState::Response& s) {
  return {s.tilt, s.heading, s.spin_angle, s.precession_rate, s.nutation_rate, s.spin, s.velocity_x, s.velocity_y, s.x, s.y};
}
bool identical(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}
std::string shown(const std::vector<double>& v) {
  std::string text;
  char buffer[40];
  for (double x : v) {
    std::snprintf(buffer, sizeof buffer, "%s%.17g", text.empty() ? "" : ", ", x);
    text += buffer;
  }
  return text;
}

/// Every number of a published state but its stamp (the time goes on) and its top time.
std::vector<double> numbers(const spinning_top::TopState& s) {
  return {s.tilt, s.heading, s.spin_angle, s.precession_rate, s.nutation_rate, s.spin,
          s.angular_velocity.x, s.angular_velocity.y, s.angular_velocity.z,
          s.center_of_mass.x, s.center_of_mass.y, s.center_of_mass.z,
          s.center_of_mass_velocity.x, s.center_of_mass_velocity.y, s.center_of_mass_velocity.z,
          s.contact_point.x, s.contact_point.y, s.contact_point.z, s.normal_force,
          s.contact_force.x, s.contact_force.y, s.contact_force.z, s.energy, s.dissipated_energy, s.energy_balance,
          s.quaternion_norm_error, s.constraint_residual};
}

class GetState : public testing::Test {
 protected:
  GetState() {
    for (const char* top : kTops) recorders_.emplace_back(new Recorder<spinning_top::TopState>(nh_, std::string("/saver/") + top + "/state", 10000));
  }
  /// `n` ticks by ~step; returns each top's states published meanwhile.
  std::vector<std::vector<spinning_top::TopState>> step(int n) {
    for (auto& r : recorders_) r->clear();
    for (int i = 0; i < n; ++i) EXPECT_TRUE(trigger("/saver/step").success);
    EXPECT_TRUE(wait_for([&] {
      for (auto& r : recorders_)
        if (r->size() < static_cast<size_t>(n)) return false;
      return true;
    }, 20.0));
    std::vector<std::vector<spinning_top::TopState>> out;
    for (auto& r : recorders_) out.push_back(r->messages());
    return out;
  }
  ros::NodeHandle nh_;
  std::vector<std::unique_ptr<Recorder<spinning_top::TopState>>> recorders_;
};

TEST_F(GetState, SavedStateIsSetBackBitForBitAndRunsAgainAlike) {
  ASSERT_TRUE(wait_for([&] {
    for (auto& r : recorders_)
      if (r->publishers() == 0) return false;
    return true;
  }, 20.0));
  // "" names the node's own top; this node has two named ones.
  EXPECT_FALSE(get_state("").success);
  EXPECT_FALSE(get_state("nobody").success);

  step(30);
  std::vector<spinning_top::GetState::Response> saved;
  for (const char* top : kTops) {
    saved.push_back(get_state(top));
    ASSERT_TRUE(saved.back().success) << top << ": " << saved.back().message;
    EXPECT_NEAR(saved.back().time, 0.3, 1e-12) << top;
  }
  EXPECT_NE(saved[0].velocity_x, 0.0) << "the viscous top's G moves sideways";
  EXPECT_NEAR(saved[1].y, 0.2, 1e-9) << "the pivot";
  const auto original = step(20);  // the run from the saved states, as it went on

  std::vector<std::vector<std::vector<spinning_top::TopState>>> runs;
  for (int again = 0; again < 2; ++again) {
    for (size_t i = 0; i < saved.size(); ++i) {
      const auto set = set_state(kTops[i], saved[i]);
      ASSERT_TRUE(set.success) << kTops[i] << ": " << set.message;
      const auto back = get_state(kTops[i]);
      ASSERT_TRUE(back.success) << back.message;
      EXPECT_EQ(back.time, 0.0);
      EXPECT_TRUE(identical(fields(back), fields(saved[i]))) << kTops[i] << "\n  saved " << shown(fields(saved[i]))
                                                             << "\n  got   " << shown(fields(back));
    }
    runs.push_back(step(20));
  }
  for (size_t i = 0; i < saved.size(); ++i) {
    ASSERT_EQ(runs[0][i].size(), 20u);
    ASSERT_EQ(runs[1][i].size(), 20u);
    ASSERT_EQ(original[i].size(), 20u);
    long differing = 0;
    double largest = 0.0;
    for (size_t k = 0; k < 20; ++k) {
      // Set back twice: the same run, bit for bit (the top's time too).
      EXPECT_EQ(runs[0][i][k].time, static_cast<double>(k + 1) / 100.0);
      EXPECT_EQ(runs[1][i][k].time, runs[0][i][k].time);
      if (!identical(numbers(runs[0][i][k]), numbers(runs[1][i][k]))) ++differing;
      // ... and the run the state was saved from, to rounding (the state went through Euler
      // angles; the integrator's own history is not part of it).
      const auto a = numbers(runs[0][i][k]), b = numbers(original[i][k]);
      for (size_t j = 0; j < 22; ++j) largest = std::max(largest, std::abs(a[j] - b[j]));
    }
    EXPECT_EQ(differing, 0) << kTops[i] << ": ticks of the two runs from the same state that differ";
    EXPECT_LT(largest, 1e-9) << kTops[i] << ": the run set back strays from the run saved";
    std::printf("[ measured ] %s: set back twice, %ld of 20 ticks differ; largest difference from the original run %.3g\n",
                kTops[i], differing, largest);
  }

  // A state read later (the top's time 0.2) is set back bit for bit as well.
  for (const char* top : kTops) {
    const auto later = get_state(top);
    ASSERT_TRUE(later.success);
    EXPECT_NEAR(later.time, 0.2, 1e-12);
    ASSERT_TRUE(set_state(top, later).success);
    EXPECT_TRUE(identical(fields(get_state(top)), fields(later))) << top;
  }
}

}  // namespace

int main(int argc, char** argv) { return node_test::run_node_tests(argc, argv, "test_node_get_state", 2); }
