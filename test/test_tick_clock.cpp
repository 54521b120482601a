// The node's ROS-free tick clock (tick_clock.hpp) and the Euler state the node publishes
// (kinematics.hpp, euler_state).
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>

#include "spinning_top/kinematics.hpp"
#include "spinning_top/tick_clock.hpp"

namespace spinning_top {
namespace {

// Tick n is at exactly n / rate: 1e6 ticks at 1 kHz end at 1000 s, not 1000 s plus the rounding
// of a million additions of 0.001.
TEST(TickClock, TickTimesCarryNoAccumulatedRounding) {
  TickClock clock(1000.0, 1.0);
  for (int i = 0; i < 1000000; ++i) clock.take();
  EXPECT_EQ(clock.time(), 1000.0);
  EXPECT_EQ(clock.next_time(), 1000.001);
}

// A rate change re-anchors: the next tick is one new period after the last old one.
TEST(TickClock, RateChangeKeepsTheLastTick) {
  TickClock clock(1000.0, 1.0);
  for (int i = 0; i < 3; ++i) clock.take();
  clock.set_pace(250.0, 1.0, 0.0);
  EXPECT_DOUBLE_EQ(clock.time(), 0.003);
  clock.take();
  EXPECT_DOUBLE_EQ(clock.time(), 0.007);
}

// Ticks due against the wall clock: one per period, a missed stretch is due at once (catch-up),
// and a tick is due from half a period before its slot (timer jitter).
TEST(TickClock, MissedTicksAreDueAndTakenLate) {
  TickClock clock(1000.0, 1.0);
  clock.anchor(100.0);
  EXPECT_EQ(clock.due(100.0), 0);
  EXPECT_EQ(clock.due(100.0004), 0);
  EXPECT_EQ(clock.due(100.0006), 1);  // jitter: 0.4 ms early still counts
  EXPECT_EQ(clock.due(100.001), 1);
  clock.take();
  EXPECT_EQ(clock.due(100.001), 0);
  // The machine stalls for 250 ms: 250 ticks are due, and the lag is 0.25 s.
  EXPECT_EQ(clock.due(100.251), 250);
  EXPECT_NEAR(clock.lag(100.251), 0.25, 1e-9);
  for (int i = 0; i < 250; ++i) clock.take();
  EXPECT_EQ(clock.due(100.251), 0);
  EXPECT_NEAR(clock.time(), 0.251, 1e-12);  // simulated time caught up with the wall clock
  // At a factor of 2, two ticks per wall period.
  clock.set_pace(1000.0, 2.0, 200.0);
  EXPECT_EQ(clock.due(200.001), 2);
}

// Beyond max_lag the overload is given up: what remains due is max_lag of wall time.
TEST(TickClock, GivesUpBeyondTheLagBound) {
  TickClock clock(1000.0, 1.0);
  clock.anchor(0.0);
  EXPECT_EQ(clock.give_up_beyond(0.5, 1.0), 0);
  EXPECT_EQ(clock.due(5.0), 5000);
  EXPECT_EQ(clock.give_up_beyond(5.0, 1.0), 4000);
  EXPECT_EQ(clock.due(5.0), 1000);
  EXPECT_NEAR(clock.lag(5.0), 1.0, 1e-9);
}

TEST(TickClock, AsFastAsPossibleHasNoPace) {
  TickClock clock(1000.0, 0.0);
  clock.anchor(0.0);
  EXPECT_EQ(clock.due(10.0), 0);
  EXPECT_EQ(clock.lag(10.0), 0.0);
  EXPECT_EQ(clock.give_up_beyond(10.0, 1.0), 0);
}

TEST(TickClock, RefusesBadPace) {
  EXPECT_THROW(TickClock(0.0, 1.0), std::invalid_argument);
  EXPECT_THROW(TickClock(NAN, 1.0), std::invalid_argument);
  EXPECT_THROW(TickClock(1000.0, -1.0), std::invalid_argument);
  TickClock clock(1000.0, 1.0);
  EXPECT_THROW(clock.set_pace(1000.0, INFINITY, 0.0), std::invalid_argument);
}

// euler_state inverts initial_attitude and initial_body_rates: random angles and rates come
// back to round-off (1e-12), and rebuilding the attitude and rates from them gives the same
// quaternion (up to sign) and body rates, upright tops included.
TEST(EulerState, InvertsTheInitialConditions) {
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> angle(-3.1, 3.1), tilt(1e-3, 3.1), rate(-50.0, 50.0);
  for (int i = 0; i < 1000; ++i) {
    InitialConditions ic;
    ic.heading = angle(random);
    ic.tilt = tilt(random);
    ic.spin_angle = angle(random);
    ic.precession_rate = rate(random);
    ic.nutation_rate = rate(random);
    ic.spin = rate(random);
    const EulerState e = euler_state(initial_attitude(ic), initial_body_rates(ic));
    EXPECT_NEAR(e.heading, ic.heading, 1e-11);
    EXPECT_NEAR(e.tilt, ic.tilt, 1e-11);
    EXPECT_NEAR(e.spin_angle, ic.spin_angle, 1e-11);
    EXPECT_NEAR(e.precession_rate, ic.precession_rate, 1e-9);
    EXPECT_NEAR(e.nutation_rate, ic.nutation_rate, 1e-11);
    EXPECT_EQ(e.spin, ic.spin);
  }
  for (const Vector3& rates : {Vector3(0.0, 0.0, 40.0), Vector3(1.5, -2.0, 40.0), Vector3(0.0, 3.0, -5.0)}) {
    InitialConditions upright;
    upright.tilt = 0.0;
    upright.heading = 0.7;
    const Quaternion q = initial_attitude(upright);
    const EulerState e = euler_state(q, rates);
    InitialConditions back;
    back.heading = e.heading;
    back.tilt = e.tilt;
    back.spin_angle = e.spin_angle;
    back.precession_rate = e.precession_rate;
    back.nutation_rate = e.nutation_rate;
    back.spin = e.spin;
    EXPECT_NEAR(std::abs(initial_attitude(back).dot(q)), 1.0, 1e-14);
    EXPECT_NEAR((initial_body_rates(back) - rates).norm(), 0.0, 1e-13);
  }
}

}  // namespace
}  // namespace spinning_top
