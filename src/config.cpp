#include "spinning_top/config.hpp"

#include <cerrno>
#include <cstdlib>

#include "spinning_top/integrator_registry.hpp"

namespace spinning_top {

namespace {

/// The integrator key's help: the registry's names (what each one is: integrator_registry()).
const std::string& integrator_key_description() {
  static const std::string text = [] {
    std::string names;
    for (const IntegratorInfo& row : integrator_registry()) names += (names.empty() ? "" : " | ") + std::string(row.name);
    return names + " (scenes and kinds: the integrator table)";
  }();
  return text;
}

}  // namespace

const std::vector<ParameterSpec>& parameter_specs() {
  static const std::vector<ParameterSpec> specs = {
      {"scene", "", "fixed_tip", true, "contact scene: fixed_tip | frictionless | viscous"},
      {"mass", "kg", "0.1", true, "m, mass of the top"},
      {"inertia_transverse", "kg m^2", "4e-05", true, "A, transverse principal moment of inertia about G"},
      {"inertia_axial", "kg m^2", "6e-05", true, "C, moment of inertia about the symmetry axis (C <= 2A)"},
      {"tip_distance", "m", "0.02", true, "h, distance from the tip to the centre of mass G"},
      {"gravity", "m/s^2", "9.80665", false, "g, gravitational acceleration"},
      {"friction", "N s/m", "0", false, "k, viscous friction F = -k v_P on the tip (viscous scene only)"},
      {"initial/tilt", "rad", "0.3", true, "theta0, initial angle of the axis from the vertical (|theta0| < pi/2)"},
      {"initial/precession_rate", "rad/s", "0", false, "phidot0, initial precession rate"},
      {"initial/nutation_rate", "rad/s", "0", false, "thetadot0, initial nutation rate"},
      {"initial/spin", "rad/s", "150", true, "omega_Z, spin about the symmetry axis (a constant of motion)"},
      {"initial/heading", "rad", "0", false, "phi0, initial heading (precession angle)"},
      {"initial/spin_angle", "rad", "0", false, "psi0, initial spin angle"},
      {"initial/velocity_x", "m/s", "0", false, "initial horizontal velocity of G, x (viscous scene only)"},
      {"initial/velocity_y", "m/s", "0", false, "initial horizontal velocity of G, y (viscous scene only)"},
      {"integrator", "", "auto", false, integrator_key_description().c_str()},
      {"step", "s", "0.001", false,
       "largest substep of the fixed-step integrators; refused beyond 2 / (rate of the fastest motion), "
       "auto shortens it to half that instead"},
      {"tolerance", "", "1e-12", false,
       "local error tolerance (relative and absolute) of adaptive integrators (auto in the viscous scene: dop853 "
       "at a tenth of it, radau5 at a hundredth of it)"},
  };
  return specs;
}

double parse_number(const std::string& key, const std::string& text) {
  const char* begin = text.c_str();
  char* end = nullptr;
  errno = 0;
  const double value = std::strtod(begin, &end);
  while (end != nullptr && (*end == ' ' || *end == '\t')) ++end;
  if (text.empty() || end == begin || *end != '\0')
    throw InvalidParameter(key, "'" + text + "' is not a number");
  if (errno == ERANGE && (value > 1.0 || value < -1.0)) throw InvalidParameter(key, "'" + text + "' is out of range");
  return value;
}

SceneConfig parse_scene_config(const ParameterMap& values, bool require_all) {
  for (const auto& [key, value] : values) {
    bool known = false;
    for (const ParameterSpec& spec : parameter_specs()) known = known || key == spec.key;
    if (!known) throw InvalidParameter(key, "unknown key (see --help for the list of keys)");
  }
  auto text = [&](const ParameterSpec& spec) -> std::string {
    const auto it = values.find(spec.key);
    if (it != values.end()) return it->second;
    if (require_all && spec.required_in_file) throw InvalidParameter(spec.key, "is required but missing");
    return spec.default_value;
  };
  auto number = [&](const char* key) {
    for (const ParameterSpec& spec : parameter_specs())
      if (std::string(key) == spec.key) return parse_number(key, text(spec));
    throw InvalidParameter(key, "unknown key");
  };
  auto string = [&](const char* key) {
    for (const ParameterSpec& spec : parameter_specs())
      if (std::string(key) == spec.key) return text(spec);
    throw InvalidParameter(key, "unknown key");
  };

  SceneConfig config;
  config.scene = parse_scene(string("scene"));
  config.top.mass = number("mass");
  config.top.inertia_transverse = number("inertia_transverse");
  config.top.inertia_axial = number("inertia_axial");
  config.top.tip_distance = number("tip_distance");
  config.top.gravity = number("gravity");
  config.top.friction = number("friction");
  config.initial.tilt = number("initial/tilt");
  config.initial.precession_rate = number("initial/precession_rate");
  config.initial.nutation_rate = number("initial/nutation_rate");
  config.initial.spin = number("initial/spin");
  config.initial.heading = number("initial/heading");
  config.initial.spin_angle = number("initial/spin_angle");
  config.initial.velocity_x = number("initial/velocity_x");
  config.initial.velocity_y = number("initial/velocity_y");
  config.integrator.type = parse_integrator(string("integrator"));
  config.integrator.step = number("step");
  config.integrator.tolerance = number("tolerance");
  validate(config);
  return config;
}

}  // namespace spinning_top
