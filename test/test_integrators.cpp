// The integrators of issue 4: order of accuracy, exact invariants of the geometric
// splitting, bounded energy error, stiff stability, the auto rule and refused steps.
// Reference solutions: dopri5 at tolerance 1e-13 (its global error on these runs is ~1e-12,
// which is the floor below which no error ratio is measured).
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "spinning_top/drivers.hpp"
#include "spinning_top/integrators/dormand_prince.hpp"
#include "spinning_top/integrators/rk4.hpp"
#include "spinning_top/integrators/rosenbrock.hpp"
#include "spinning_top/integrators/splitting.hpp"
#include "spinning_top/scenes/fixed_tip.hpp"
#include "spinning_top/scenes/viscous.hpp"
#include "spinning_top/simulator.hpp"

namespace spinning_top {
namespace {

/// The toy top of config/ (m 0.1 kg, A 4e-5, C 6e-5, h 0.02 m, 150 rad/s), tilted 0.3 rad
/// with some precession and nutation so that every term of the equations is exercised.
InitialConditions nutating_top() {
  InitialConditions ic;
  ic.tilt = 0.3;
  ic.spin = 150.0;
  ic.precession_rate = 5.0;
  ic.nutation_rate = 2.0;
  return ic;
}

template <class Model, class Method>
typename Model::State run_fixed(const Model& model, double step, double duration) {
  FixedStepDriver<Model, Method> driver(step);
  driver.reset(model, 0.0, model.initial_state());
  EXPECT_EQ(driver.advance_to(model, duration), Event::kNone);
  return driver.state();
}

template <class Model>
typename Model::State reference(const Model& model, double duration) {
  AdaptiveDriver<Model, DormandPrince54<Model>> driver(1e-13);
  driver.reset(model, 0.0, model.initial_state());
  EXPECT_EQ(driver.advance_to(model, duration), Event::kNone);
  return driver.state();
}

/// log2 of the error ratio between steps dt and dt/2, i.e. the observed order.
template <class Model, class Method>
double observed_order(const Model& model, double duration, double step) {
  const typename Model::State exact = reference(model, duration);
  const double coarse = (run_fixed<Model, Method>(model, step, duration) - exact).norm();
  const double fine = (run_fixed<Model, Method>(model, 0.5 * step, duration) - exact).norm();
  EXPECT_GT(fine, 1e-11) << "error at the reference's floor: the ratio would be noise";
  return std::log2(coarse / fine);
}

// Steps chosen so that both errors lie well above the reference's 1e-12 floor and in the
// asymptotic range (measured: the ratio is within 0.1 of 2^p there).
TEST(SplittingOrder, BlanesMoanIsFourthOrder) {
  const FixedTip model(TopParameters(), nutating_top());
  EXPECT_NEAR((observed_order<FixedTip, Splitting<FixedTip, BlanesMoan4>>(model, 0.5, 2e-3)), 4.0, 0.15);
}

TEST(SplittingOrder, KahanLiSixIsSixthOrder) {
  const FixedTip model(TopParameters(), nutating_top());
  EXPECT_NEAR((observed_order<FixedTip, Splitting<FixedTip, KahanLi6>>(model, 0.5, 4e-3)), 6.0, 0.15);
}

TEST(SplittingOrder, KahanLiEightIsEighthOrder) {
  const FixedTip model(TopParameters(), nutating_top());
  EXPECT_NEAR((observed_order<FixedTip, Splitting<FixedTip, KahanLi8>>(model, 2.0, 8e-3)), 8.0, 0.25);
}

TEST(SplittingInvariants, SpinAndVerticalAngularMomentumExactEnergyBounded) {
  // A large step (30 steps per nutation period) makes the energy error visible while omega_Z
  // and L_z must stay at round-off: each flow conserves them exactly.
  SceneConfig config;
  config.initial = nutating_top();
  config.integrator.type = IntegratorType::kSplitting4;
  config.integrator.step = 2e-3;
  auto simulator = make_simulator(config);
  const Snapshot start = simulator->snapshot();
  const double e0 = start.outputs.energy, lz0 = start.outputs.vertical_angular_momentum;
  double max_energy_error_short = 0.0, max_energy_error_long = 0.0, max_lz_error = 0.0;
  for (int i = 1; i <= 10000; ++i) {  // 20 s, ~360 nutation periods
    ASSERT_EQ(simulator->advance_to(i * 2e-3), Event::kNone);
    const Snapshot s = simulator->snapshot();
    const double energy_error = std::abs(s.outputs.energy - e0) / e0;
    (i <= 1000 ? max_energy_error_short : max_energy_error_long) =
        std::max(i <= 1000 ? max_energy_error_short : max_energy_error_long, energy_error);
    max_lz_error = std::max(max_lz_error, std::abs(s.outputs.vertical_angular_momentum - lz0));
    ASSERT_EQ(s.body_rates.z(), start.body_rates.z());
  }
  // L_z ~ C omega_Z cos(theta) ~ 9e-3 kg m^2/s; 10^4 steps of ~30 round-off operations each
  // at 1e-16 relative: a random walk well below 1e-13 relative.
  EXPECT_LT(max_lz_error, 1e-13 * std::abs(lz0));
  // Bounded energy error: over 10x the time the maximum error is not 10x larger (a drift
  // would make it ~10x; a symmetric method's error oscillates about the modified energy).
  EXPECT_GT(max_energy_error_short, 0.0);
  EXPECT_LT(max_energy_error_long, 2.0 * max_energy_error_short);
}

TEST(AutoRule, GeometricForTheFixedTip) {
  SceneConfig config;
  config.initial = nutating_top();
  EXPECT_EQ(config.integrator.type, IntegratorType::kAuto);  // the default
  EXPECT_EQ(auto_integrator(config), IntegratorType::kSplitting6);
  EXPECT_EQ(make_simulator(config)->integrator_description(), "auto: splitting6, step 0.001 s");
}

TEST(AutoRule, AdaptiveForTheFrictionlessTop) {
  SceneConfig config;
  config.scene = SceneType::kFrictionless;
  config.initial = nutating_top();
  EXPECT_EQ(make_simulator(config)->integrator_description(), "auto: dopri5, tolerance 1e-10");
}

TEST(AutoRule, StiffStableWhenFrictionIsFasterThanTheStep) {
  SceneConfig config;
  config.scene = SceneType::kViscous;
  config.initial = nutating_top();
  // lambda = k (1/m + h^2/A) = k * 20 1/(kg): k = 0.01 -> 0.2 1/s (slow), k = 1e3 -> 2e4 1/s.
  config.top.friction = 0.01;
  EXPECT_EQ(auto_integrator(config), IntegratorType::kDopri5);
  config.top.friction = 1e3;
  EXPECT_NE(make_simulator(config)->integrator_description().find("auto: "), std::string::npos);
  EXPECT_NE(auto_integrator(config), IntegratorType::kDopri5);
}

TEST(RefusedSteps, FixedStepBeyondTheNutationIsRefusedNamingStep) {
  SceneConfig config;
  config.initial = nutating_top();
  config.integrator.type = IntegratorType::kRk4;
  // Nutation rate C wZ / A0 = 6e-5 * 150 / 8e-5 = 112.5 rad/s: limit 2/112.5 = 0.0178 s.
  config.integrator.step = 0.05;
  try {
    make_simulator(config);
    FAIL() << "a step of 0.05 s was accepted";
  } catch (const InvalidParameter& e) {
    EXPECT_EQ(e.parameter(), "step");
    EXPECT_NE(std::string(e.what()).find("nutation"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("0.0178"), std::string::npos) << e.what();
  }
  config.integrator.step = 0.017;
  EXPECT_NO_THROW(make_simulator(config));
}

TEST(RefusedSteps, AutoShortensTheSubstepInsteadAndStaysFinite) {
  SceneConfig config;
  config.initial = nutating_top();
  config.integrator.step = 0.05;  // beyond the limit: auto runs at half the limit instead
  auto simulator = make_simulator(config);
  EXPECT_EQ(simulator->integrator_description(), "auto: splitting6, step 0.00888889 s");
  const double e0 = simulator->snapshot().outputs.energy;
  ASSERT_EQ(simulator->advance_to(1.0), Event::kNone);
  EXPECT_NEAR(simulator->snapshot().outputs.energy, e0, 1e-6 * e0);
}

TEST(RefusedSteps, SplittingOnlyForTheFixedTip) {
  SceneConfig config;
  config.scene = SceneType::kFrictionless;
  config.integrator.type = IntegratorType::kSplitting6;
  try {
    make_simulator(config);
    FAIL();
  } catch (const InvalidParameter& e) {
    EXPECT_EQ(e.parameter(), "integrator");
  }
}

}  // namespace
}  // namespace spinning_top
