#include <gtest/gtest.h>
#include "spinning_top/simulator.hpp"
using namespace spinning_top;
TEST(Smoke, EnergyConservedFixedTip) {
  SceneConfig c; c.initial.tilt = 0.3; c.initial.spin = 150;
  auto s = make_simulator(c);
  const double e0 = s->snapshot().outputs.energy;
  s->advance_to(1.0);
  EXPECT_NEAR(s->snapshot().outputs.energy, e0, 1e-9 * e0);
}
