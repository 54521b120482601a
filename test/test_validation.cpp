// Every invalid input is refused with InvalidParameter naming the configuration key (issue 2:
// finite numbers only; m, A, C > 0; h, g, k >= 0; C <= 2A; the axis above the floor; friction
// and G's initial velocity only where there is friction; a usable step and tolerance; known
// scene and integrator names; no unknown key, no missing required key in a scene file).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <string>
#include <type_traits>

#include "core_test_support.hpp"
#include "spinning_top/config.hpp"
#include "spinning_top/defaults.hpp"
#include "spinning_top/work_budget.hpp"

namespace spinning_top {
namespace {
using namespace core_test;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

/// A valid viscous configuration (every key in use) that each case spoils in one place.
SceneConfig valid_viscous() {
  InitialConditions ic;
  ic.tilt = 0.3;
  ic.spin = 150.0;
  ic.velocity_x = 0.01;
  TopParameters top = toy_top();
  top.friction = 0.5;
  return adaptive(SceneType::kViscous, ic, 1e-10, top);
}

/// make_simulator must throw InvalidParameter whose parameter() is `key` and whose message
/// starts with it.
void expect_refused(const SceneConfig& config, const std::string& key, const std::string& what) {
  try {
    make_simulator(config);
    ADD_FAILURE() << what << ": accepted, expected InvalidParameter(" << key << ")";
  } catch (const InvalidParameter& e) {
    EXPECT_EQ(e.parameter(), key) << what << ": " << e.what();
    EXPECT_EQ(std::string(e.what()).rfind(key + ": ", 0), 0u) << what << ": " << e.what();
  }
}

void expect_refused(const std::string& key, const std::function<void(SceneConfig&)>& spoil, const std::string& what,
                    SceneConfig config = valid_viscous()) {
  spoil(config);
  expect_refused(config, key, what);
}

TEST(InvalidParameters, ValidBaseConfigurationAndBoundaryValuesAreAccepted) {
  EXPECT_NO_THROW(make_simulator(valid_viscous()));
  SceneConfig boundary = valid_viscous();
  boundary.top.inertia_axial = 2.0 * boundary.top.inertia_transverse;  // a flat disc: C = 2A
  boundary.top.tip_distance = 0.0;
  boundary.top.gravity = 0.0;
  boundary.top.friction = 0.0;
  boundary.initial.tilt = -1.5;
  EXPECT_NO_THROW(make_simulator(boundary));
}

TEST(InvalidParameters, NonFiniteNumbersNameTheirKey) {
  for (double bad : {kNaN, kInf, -kInf}) {
    expect_refused("mass", [&](SceneConfig& c) { c.top.mass = bad; }, "m non-finite");
    expect_refused("inertia_transverse", [&](SceneConfig& c) { c.top.inertia_transverse = bad; }, "A non-finite");
    expect_refused("inertia_axial", [&](SceneConfig& c) { c.top.inertia_axial = bad; }, "C non-finite");
    expect_refused("tip_distance", [&](SceneConfig& c) { c.top.tip_distance = bad; }, "h non-finite");
    expect_refused("gravity", [&](SceneConfig& c) { c.top.gravity = bad; }, "g non-finite");
    expect_refused("friction", [&](SceneConfig& c) { c.top.friction = bad; }, "k non-finite");
    expect_refused("initial/tilt", [&](SceneConfig& c) { c.initial.tilt = bad; }, "theta0 non-finite");
    expect_refused("initial/precession_rate", [&](SceneConfig& c) { c.initial.precession_rate = bad; }, "phidot0");
    expect_refused("initial/nutation_rate", [&](SceneConfig& c) { c.initial.nutation_rate = bad; }, "thetadot0");
    expect_refused("initial/spin", [&](SceneConfig& c) { c.initial.spin = bad; }, "omega_Z non-finite");
    expect_refused("initial/heading", [&](SceneConfig& c) { c.initial.heading = bad; }, "phi0 non-finite");
    expect_refused("initial/spin_angle", [&](SceneConfig& c) { c.initial.spin_angle = bad; }, "psi0 non-finite");
    expect_refused("initial/velocity_x", [&](SceneConfig& c) { c.initial.velocity_x = bad; }, "vx non-finite");
    expect_refused("initial/velocity_y", [&](SceneConfig& c) { c.initial.velocity_y = bad; }, "vy non-finite");
    expect_refused("step", [&](SceneConfig& c) { c.integrator.step = bad; }, "step non-finite");
    expect_refused("tolerance", [&](SceneConfig& c) { c.integrator.tolerance = bad; }, "tolerance non-finite");
  }
}

TEST(InvalidParameters, MassAndMomentsOfInertiaMustBePositive) {
  for (double bad : {0.0, -1e-3}) {
    expect_refused("mass", [&](SceneConfig& c) { c.top.mass = bad; }, "m <= 0");
    expect_refused("inertia_transverse", [&](SceneConfig& c) { c.top.inertia_transverse = bad; }, "A <= 0");
    expect_refused("inertia_axial", [&](SceneConfig& c) { c.top.inertia_axial = bad; }, "C <= 0");
  }
}

TEST(InvalidParameters, TipDistanceGravityAndFrictionMustNotBeNegative) {
  expect_refused("tip_distance", [](SceneConfig& c) { c.top.tip_distance = -1e-3; }, "h < 0");
  expect_refused("gravity", [](SceneConfig& c) { c.top.gravity = -9.8; }, "g < 0");
  expect_refused("friction", [](SceneConfig& c) { c.top.friction = -0.1; }, "k < 0");
}

// 2A - C = 2 integral z^2 dm >= 0 for any rigid body.
TEST(InvalidParameters, AxialMomentAboveTwiceTheTransverseIsNoRigidBody) {
  expect_refused("inertia_axial", [](SceneConfig& c) { c.top.inertia_axial = 2.0 * c.top.inertia_transverse * (1 + 1e-12); },
                 "C > 2A");
}

// The double M_PI / 2 lies 6e-17 below pi/2 (cos = 6e-17 > 0, a valid start at the floor that
// falls at once), so the first refused tilts are the doubles just above pi/2.
TEST(InvalidParameters, AxisMustStartAboveTheFloor) {
  for (double bad : {std::nextafter(M_PI / 2, 2.0), -std::nextafter(M_PI / 2, 2.0), 2.0, M_PI, -3.0})
    expect_refused("initial/tilt", [&](SceneConfig& c) { c.initial.tilt = bad; }, "|theta0| >= pi/2");
  // Angles a turn away from a valid one have cos > 0 too, but the documented range is |theta0| < pi/2.
  for (double bad : {2 * M_PI + 0.3, -2 * M_PI + 0.3, 4 * M_PI})
    expect_refused("initial/tilt", [&](SceneConfig& c) { c.initial.tilt = bad; }, "a turn beyond the range");
}

TEST(InvalidParameters, FrictionAndInitialVelocityOnlyInTheViscousScene) {
  for (SceneType scene : {SceneType::kFixedTip, SceneType::kFrictionless}) {
    SceneConfig config = valid_viscous();
    config.scene = scene;
    config.initial.velocity_x = config.initial.velocity_y = 0.0;
    expect_refused("friction", [](SceneConfig&) {}, "k > 0 without friction", config);
    config.top.friction = 0.0;
    EXPECT_NO_THROW(make_simulator(config)) << to_string(scene);
    expect_refused("initial/velocity_x", [](SceneConfig& c) { c.initial.velocity_x = 0.1; }, "vx", config);
    expect_refused("initial/velocity_y", [](SceneConfig& c) { c.initial.velocity_y = -0.1; }, "vy", config);
  }
}

TEST(InvalidParameters, StepAndToleranceMustBeUsable) {
  SceneConfig rk4 = valid_viscous();
  rk4.integrator.type = IntegratorType::kRk4;
  for (double bad : {0.0, -1e-3})
    expect_refused("step", [&](SceneConfig& c) { c.integrator.step = bad; }, "step <= 0", rk4);
  expect_refused("step", [](SceneConfig& c) { c.integrator.step = 1.0; }, "step beyond the nutation", rk4);
  for (double bad : {0.0, -1e-8, 1e-16, 1.0, 2.0})
    expect_refused("tolerance", [&](SceneConfig& c) { c.integrator.tolerance = bad; }, "tolerance out of range");
  // Below 1e-9 s a step only multiplies substeps: 1e-300 overflowed their count (a lift-off with
  // five times the energy, exit 0).
  for (double bad : {1e-300, 1e-10})
    expect_refused("step", [&](SceneConfig& c) { c.integrator.step = bad; }, "step below 1e-9 s", rk4);
}

// The fastest motion the simulator resolves is 1e6 rad/s: above it a configuration is refused
// naming the key that drives the motion, in every scene and for every method (exact too: a spin of
// 1e22 rad/s gave it quaternions of 1e290, and 1.4e154 overflowed the rates into a crash).
TEST(InvalidParameters, MotionsFasterThanTheSimulatorResolvesAreRefusedByTheirKey) {
  for (const SceneType scene : {SceneType::kFixedTip, SceneType::kFrictionless, SceneType::kViscous}) {
    SceneConfig config = valid_viscous();
    config.scene = scene;
    if (scene != SceneType::kViscous) {
      config.top.friction = 0.0;
      config.initial.velocity_x = config.initial.velocity_y = 0.0;
    }
    for (const double spin : {1e7, 1e12, 1e22, 1.4e154, 1e300})
      expect_refused("initial/spin", [&](SceneConfig& c) { c.initial.spin = spin; }, "spin " + std::to_string(spin), config);
    expect_refused("initial/precession_rate", [](SceneConfig& c) { c.initial.precession_rate = 1e8; }, "precession", config);
    expect_refused("initial/nutation_rate", [](SceneConfig& c) { c.initial.nutation_rate = -1e8; }, "nutation", config);
    expect_refused("gravity", [](SceneConfig& c) { c.top.gravity = 1e14; }, "gravity", config);
    // The pendulum rate sqrt(m g h / A) names the key that made it fast (it named gravity for all
    // four: issue 19's attack, mass 1e20 on the viscous floor, tip_distance 3e9 on the frictionless).
    // On the fixed tip A is about the tip, A + m h^2, so a heavy or long top is a point pendulum
    // there, sqrt(g / h), and is accepted.
    if (scene != SceneType::kFixedTip) {
      expect_refused("mass", [](SceneConfig& c) { c.top.mass = 1e20; }, "mass", config);
      expect_refused("tip_distance", [](SceneConfig& c) { c.top.tip_distance = 3e9; }, "tip_distance", config);
      expect_refused("inertia_transverse", [](SceneConfig& c) { c.top.inertia_transverse = c.top.inertia_axial = 1e-22; },
                     "A, C tiny", config);
    } else {
      SceneConfig heavy = config;
      heavy.top.mass = 1e20;
      EXPECT_NO_THROW(make_simulator(heavy)) << "a heavy top on a pivot";
    }
    SceneConfig fast = config;
    fast.initial.spin = 5e5;  // a fast but resolvable top: accepted
    EXPECT_NO_THROW(make_simulator(fast)) << to_string(scene);
  }
}

// Issue 19, item 6: every key is bounded so that every derived quantity is finite, in the one
// validation of every front end (simulate, Python's Simulator and run_case, the node's spawn,
// set_state and live changes all call it). Before, G's initial speed had no bound:
// initial/velocity_x = 1e300 ran (simulate exit 0) with E = inf; and a body of A = C = 1e300 at a
// spin of 1e6 rad/s, within the motion bound, had E = inf too.
TEST(InvalidParameters, EveryKeyIsBoundedSoThatTheEnergyStaysFinite) {
  for (double v : {1e300, -1e300, 1e100, 2e6}) {
    expect_refused("initial/velocity_x", [&](SceneConfig& c) { c.initial.velocity_x = v; }, "vx");
    expect_refused("initial/velocity_y", [&](SceneConfig& c) { c.initial.velocity_y = v; }, "vy");
  }
  EXPECT_NO_THROW(make_simulator([] {
    SceneConfig c = valid_viscous();
    c.initial.velocity_x = -1e6;  // the bound itself
    return c;
  }()));
  for (double huge : {1e300, 1.1e30}) {
    expect_refused("mass", [&](SceneConfig& c) { c.top.mass = huge; }, "m huge");
    expect_refused("inertia_transverse", [&](SceneConfig& c) { c.top.inertia_transverse = c.top.inertia_axial = huge; },
                   "A, C huge");
    expect_refused("tip_distance", [&](SceneConfig& c) { c.top.tip_distance = huge; }, "h huge");
    expect_refused("gravity", [&](SceneConfig& c) { c.top.gravity = huge; }, "g huge");
    expect_refused("friction", [&](SceneConfig& c) { c.top.friction = huge; }, "k huge");
    expect_refused("rim_radius", [&](SceneConfig& c) { c.top.rim_radius = huge; }, "b huge");
    expect_refused("restitution_speed", [&](SceneConfig& c) { c.top.restitution_speed = huge; }, "speed huge");
    expect_refused("initial/heading", [&](SceneConfig& c) { c.initial.heading = -huge; }, "phi0 huge");
    expect_refused("initial/spin_angle", [&](SceneConfig& c) { c.initial.spin_angle = huge; }, "psi0 huge");
  }
  // They divide: a denormal mass made the friction rate 0 x inf = NaN, refused blaming friction.
  for (double tiny : {1e-320, 0.9e-30}) {
    expect_refused("mass", [&](SceneConfig& c) { c.top.mass = tiny; }, "m tiny");
    expect_refused("inertia_transverse", [&](SceneConfig& c) { c.top.inertia_transverse = c.top.inertia_axial = tiny; },
                   "A tiny");
  }
  // Whatever is accepted at the corners of the bounds has a finite state, energy and forces (at
  // +-1e100 and 1e-100, m h^2 / A = 1e400 made R = inf / inf = NaN).
  int accepted = 0;
  for (int corner = 0; corner < (1 << 9); ++corner) {
    auto pick = [corner](int bit, double lo, double hi) { return (corner >> bit) & 1 ? hi : lo; };
    SceneConfig c = valid_viscous();
    c.top.mass = pick(0, 1e-30, 1e30);
    c.top.inertia_transverse = c.top.inertia_axial = pick(1, 1e-30, 1e30);
    c.top.tip_distance = pick(2, 0.0, 1e30);
    c.top.gravity = pick(3, 0.0, 1e30);
    c.top.friction = pick(4, 0.0, 1e30);
    c.initial.velocity_x = pick(5, 0.0, 1e6);
    c.initial.spin = pick(6, 0.0, 9.9e5);
    c.initial.tilt = pick(7, 0.3, 1.5);
    c.initial.precession_rate = pick(8, 0.0, -9.9e5);
    c.integrator.type = IntegratorType::kAuto;
    std::unique_ptr<Simulator> sim;
    try {
      sim = make_simulator(c);
    } catch (const InvalidParameter&) {
      continue;
    }
    ++accepted;
    const Snapshot start = sim->snapshot();
    sim->advance_to(1e-3, WorkBudget::steps(200));
    for (const Snapshot& s : {start, sim->snapshot()}) {
      EXPECT_TRUE(std::isfinite(s.outputs.energy) && std::isfinite(s.outputs.normal_force) &&
                  s.outputs.contact_force.allFinite() && s.outputs.center_of_mass.allFinite() &&
                  s.body_rates.allFinite() && std::isfinite(s.outputs.dissipated_energy))
          << "corner " << corner << ": E = " << s.outputs.energy << ", R = " << s.outputs.normal_force;
    }
  }
  EXPECT_GT(accepted, 10);
}

TEST(InvalidParameters, UnknownSceneAndIntegratorNames) {
  EXPECT_THROW(parse_scene("sliding"), InvalidParameter);
  try {
    parse_scene("Fixed_Tip");
    ADD_FAILURE() << "scene names are case-sensitive";
  } catch (const InvalidParameter& e) {
    EXPECT_EQ(e.parameter(), "scene");
  }
  try {
    parse_integrator("euler");
    ADD_FAILURE() << "euler accepted";
  } catch (const InvalidParameter& e) {
    EXPECT_EQ(e.parameter(), "integrator");
  }
  EXPECT_EQ(parse_scene("viscous"), SceneType::kViscous);
  EXPECT_EQ(parse_integrator("dopri5"), IntegratorType::kDopri5);
}

/// A complete scene file's keys (config/fixed_tip.yaml's required ones).
ParameterMap scene_file() {
  ParameterMap values;
  for (const ParameterSpec& spec : parameter_specs())
    if (spec.required_in_file) values[spec.key] = spec.default_value;
  return values;
}

/// The bits of a struct of doubles (TopParameters, InitialConditions): equal only if every
/// member is the same double, and a member added later is compared too.
template <class Doubles>
bool same_bits(const Doubles& a, const Doubles& b) {
  static_assert(sizeof(Doubles) % sizeof(double) == 0 && std::is_trivially_copyable_v<Doubles>);
  return std::memcmp(&a, &b, sizeof(Doubles)) == 0;
}

// One source for each default (defaults.def, issue 17): the key table's defaults, as the node and
// a scene file without the key get them, are the structs' own, bit for bit; a default written
// again in either place and changed in one of them fails here.
TEST(Defaults, TheKeyTableGivesTheStructsDefaults) {
  const SceneConfig parsed = parse_scene_config({}, /*require_all=*/false);
  const SceneConfig built;
  EXPECT_EQ(parsed.scene, built.scene);
  EXPECT_EQ(parsed.after_lift_off, built.after_lift_off);
  EXPECT_TRUE(same_bits(parsed.top, built.top));
  EXPECT_TRUE(same_bits(parsed.initial, built.initial));
  EXPECT_EQ(parsed.integrator.type, built.integrator.type);
  EXPECT_TRUE(same_bits(parsed.integrator.step, built.integrator.step));
  EXPECT_TRUE(same_bits(parsed.integrator.tolerance, built.integrator.tolerance));
  // Every numeric key's default is defaults.def's entry, and every entry but the node's pacing
  // is a key of the table.
  int numeric = 0;
  for (const defaults::KeyDefault& entry : defaults::kByKey) {
    const std::string key = entry.key;
    if (key == "rate" || key == "real_time_factor") continue;  // the node's (NodeSettings)
    const auto spec = std::find_if(parameter_specs().begin(), parameter_specs().end(),
                                   [&](const ParameterSpec& s) { return s.key == key; });
    ASSERT_NE(spec, parameter_specs().end()) << key << " of defaults.def is not in the key table";
    EXPECT_TRUE(same_bits(parse_number(key, spec->default_value), entry.value)) << key;
    ++numeric;
  }
  EXPECT_EQ(numeric + 3, static_cast<int>(parameter_specs().size()));  // + scene, integrator, after_lift_off
}

void expect_parse_refused(const ParameterMap& values, bool require_all, const std::string& key,
                          const std::string& what) {
  try {
    parse_scene_config(values, require_all);
    ADD_FAILURE() << what << ": accepted, expected InvalidParameter(" << key << ")";
  } catch (const InvalidParameter& e) {
    EXPECT_EQ(e.parameter(), key) << what << ": " << e.what();
  }
}

TEST(InvalidParameters, ParsedKeysAreCheckedByName) {
  EXPECT_NO_THROW(parse_scene_config(scene_file(), true));
  // Each required key, missing from a scene file: refused naming it; the node's defaults fill it.
  int required = 0;
  for (const ParameterSpec& spec : parameter_specs()) {
    if (!spec.required_in_file) continue;
    ++required;
    ParameterMap values = scene_file();
    values.erase(spec.key);
    expect_parse_refused(values, true, spec.key, std::string("missing ") + spec.key);
    EXPECT_NO_THROW(parse_scene_config(values, false)) << spec.key;
  }
  EXPECT_GE(required, 6);  // scene, m, A, C, h, tilt, spin at least
  ParameterMap values = scene_file();
  values["masss"] = "0.1";
  expect_parse_refused(values, true, "masss", "unknown key");
  expect_parse_refused(values, false, "masss", "unknown key (node)");
  // A near miss says what it probably meant; a word far from every key does not guess.
  try {
    parse_scene_config(values, true);
  } catch (const InvalidParameter& e) {
    EXPECT_NE(std::string(e.what()).find("did you mean mass?"), std::string::npos) << e.what();
  }
  EXPECT_EQ(nearest_name("mas", parameter_keys()), "mass");
  EXPECT_EQ(nearest_name("initial/tlit", parameter_keys()), "initial/tilt");
  EXPECT_EQ(nearest_name("gravitation", parameter_keys()), "");
  EXPECT_EQ(nearest_name("xy", parameter_keys()), "");
  for (const char* text : {"abc", "0.1kg", "", "1e999"}) {
    values = scene_file();
    values["mass"] = text;
    expect_parse_refused(values, true, "mass", std::string("mass = '") + text + "'");
  }
  const std::pair<const char*, const char*> invalid_values[] = {
      {"scene", "sliding"},        {"integrator", "euler"},      {"inertia_axial", "1e-4"},
      {"initial/tilt", "1.5708"},  {"friction", "0.5"},          {"gravity", "-1"},
      {"tolerance", "0"},          {"step", "-0.001"},           {"initial/velocity_x", "0.1"},
      {"initial/spin", "nan"},     {"tip_distance", "-inf"}};
  for (const auto& [key, text] : invalid_values) {
    values = scene_file();
    values[key] = text;
    expect_parse_refused(values, true, key, std::string(key) + " = " + text);
  }
}

// A refused update during a run changes nothing (the run continues with the old parameters).
TEST(InvalidParameters, RefusedUpdateLeavesTheRunUnchanged) {
  auto sim = make_simulator(valid_viscous());
  ASSERT_EQ(sim->advance_to(0.01), Event::kNone);
  TopParameters bad = sim->config().top;
  bad.friction = -1.0;
  try {
    sim->update(bad, sim->config().integrator);
    ADD_FAILURE() << "negative friction accepted";
  } catch (const InvalidParameter& e) {
    EXPECT_EQ(e.parameter(), "friction");
  }
  EXPECT_EQ(sim->config().top.friction, 0.5);
  EXPECT_EQ(sim->time(), 0.01);
  EXPECT_EQ(sim->advance_to(0.02), Event::kNone);
}

// A live change of g that would need the floor to pull the tip at the current state (R < 0) is
// refused naming gravity, and the run goes on unchanged: before, it was applied as an instant
// lift-off whose snapshot published that negative R (issue 10). Every scene.
TEST(InvalidParameters, AnUpdateThatWouldLiftTheTipOffAtOnceIsRefusedAndTheSnapshotStaysValid) {
  for (const SceneType scene : {SceneType::kFixedTip, SceneType::kFrictionless, SceneType::kViscous}) {
    SceneConfig config;
    config.scene = scene;
    config.top.friction = scene == SceneType::kViscous ? 0.5 : 0.0;
    config.initial.tilt = 0.3;
    config.initial.spin = 150.0;
    config.initial.nutation_rate = 10.0;  // a wide nutation: R swings with theta's acceleration
    auto sim = make_simulator(config);
    auto twin = make_simulator(config);
    TopParameters weak = config.top;
    weak.gravity = 0.0;
    int refused = 0;
    for (int k = 1; k <= 100 && refused == 0; ++k) {
      const double t = 1e-3 * k;
      ASSERT_EQ(sim->advance_to(t), Event::kNone);
      ASSERT_EQ(twin->advance_to(t), Event::kNone);
      // Try the change on a copy of the state's simulator: the twin stays the reference.
      const Snapshot before = sim->snapshot();
      try {
        auto probe = make_simulator(config);
        ASSERT_EQ(probe->advance_to(t), Event::kNone);
        probe->update(weak, config.integrator);
        // Accepted: the state is valid under g = 0 too.
        EXPECT_EQ(probe->event(), Event::kNone) << to_string(scene) << ": an update applied as an instant event";
        EXPECT_GE(probe->snapshot().outputs.normal_force, 0.0) << to_string(scene) << " at " << t;
      } catch (const InvalidParameter& e) {
        EXPECT_EQ(e.parameter(), "gravity") << e.what();
        // The same refusal on the running simulator changes nothing.
        EXPECT_THROW(sim->update(weak, config.integrator), InvalidParameter);
        EXPECT_EQ(sim->config().top.gravity, config.top.gravity);
        EXPECT_EQ(sim->time(), t);
        EXPECT_EQ(sim->snapshot().attitude.coeffs(), before.attitude.coeffs());
        EXPECT_GE(sim->snapshot().outputs.normal_force, 0.0);
        ++refused;
      }
    }
    EXPECT_EQ(refused, 1) << to_string(scene) << ": no state within 0.1 s where g = 0 would need R < 0";
    ASSERT_EQ(sim->advance_to(0.2), twin->advance_to(0.2));
    EXPECT_EQ(sim->snapshot().attitude.coeffs(), twin->snapshot().attitude.coeffs()) << to_string(scene);
  }
}

// Messages show numbers as they were written (shortest text, at most 17 digits), not the 301
// digits of std::to_string(1e300), and at most the start of a long value (issue 19, item 13).
TEST(InvalidParameters, MessagesShowShortNumbersAndTheStartOfALongValue) {
  auto message_of = [](const std::function<void()>& f) -> std::string {
    try {
      f();
    } catch (const InvalidParameter& e) {
      return e.what();
    }
    return "";
  };
  const std::string huge = message_of([] {
    SceneConfig c = valid_viscous();
    c.top.mass = 1e300;
    make_simulator(c);
  });
  EXPECT_NE(huge.find("got 1e+300"), std::string::npos) << huge;
  ParameterMap values = scene_file();
  values["mass"] = std::string(20 << 20, '9') + "x";  // 20 MB
  const std::string long_value = message_of([&] { parse_scene_config(values, true); });
  EXPECT_LT(long_value.size(), 200u) << long_value.substr(0, 300);
  EXPECT_NE(long_value.find("(20971521 characters)"), std::string::npos) << long_value.substr(0, 300);
  values = scene_file();
  values["scene"] = std::string(1 << 20, 's');
  EXPECT_LT(message_of([&] { parse_scene_config(values, true); }).size(), 200u);
  values = scene_file();
  values[std::string(1 << 20, 'k')] = "1";  // an unknown key: no near-miss search over it either
  const std::string unknown = message_of([&] { parse_scene_config(values, true); });
  EXPECT_LT(unknown.size(), 200u) << unknown.substr(0, 300);
  EXPECT_NE(unknown.find("unknown key"), std::string::npos) << unknown.substr(0, 300);
}

}  // namespace
}  // namespace spinning_top
