#include "spinning_top/config.hpp"

#include <algorithm>
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

std::vector<std::string> parameter_keys() {
  std::vector<std::string> keys;
  for (const ParameterSpec& spec : parameter_specs()) keys.push_back(spec.key);
  return keys;
}

std::string nearest_name(const std::string& name, const std::vector<std::string>& known) {
  std::string best;
  std::size_t best_distance = 3;
  for (const std::string& candidate : known) {
    // Levenshtein distance, one row at a time.
    std::vector<std::size_t> row(candidate.size() + 1);
    for (std::size_t j = 0; j <= candidate.size(); ++j) row[j] = j;
    for (std::size_t i = 1; i <= name.size(); ++i) {
      std::size_t diagonal = row[0];
      row[0] = i;
      for (std::size_t j = 1; j <= candidate.size(); ++j) {
        const std::size_t above = row[j];
        row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (name[i - 1] == candidate[j - 1] ? 0 : 1)});
        diagonal = above;
      }
    }
    const std::size_t distance = row[candidate.size()];
    if (distance < best_distance && 2 * distance < name.size()) best_distance = distance, best = candidate;
  }
  return best;
}

SceneConfig parse_scene_config(const ParameterMap& values, bool require_all) {
  const std::vector<std::string> keys = parameter_keys();
  for (const auto& [key, value] : values) {
    if (std::find(keys.begin(), keys.end(), key) != keys.end()) continue;
    const std::string nearest = nearest_name(key, keys);
    throw InvalidParameter(key, "unknown key" + (nearest.empty() ? std::string() : " (did you mean " + nearest + "?)") +
                                    " (see --help for the list of keys)");
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
