#include "spinning_top/config.hpp"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

#include "spinning_top/integrator_registry.hpp"

namespace spinning_top {

namespace {

/// The integrator key's help: the registry's names (what each one is: integrator_registry()).
std::string integrator_key_description() {
  std::string names;
  for (const IntegratorInfo& row : integrator_registry()) names += (names.empty() ? "" : " | ") + std::string(row.name);
  return names + " (scenes and kinds: the integrator table)";
}

/// The shortest text that parses back to `value` (strtod), e.g. "0.3", "4e-05", "150".
std::string shortest_text(double value) {
  char text[32];
  for (int digits = 1; digits <= 17; ++digits) {
    std::snprintf(text, sizeof text, "%.*g", digits, value);
    if (std::strtod(text, nullptr) == value) break;
  }
  return text;
}

/// A numeric key's row, with its default from defaults.def.
ParameterSpec numeric(const char* key, const char* unit, bool required_in_file, std::string description) {
  for (const defaults::KeyDefault& entry : defaults::kByKey)
    if (std::string(entry.key) == key)
      return {key, unit, shortest_text(entry.value), required_in_file, std::move(description)};
  throw std::logic_error(std::string("no default for the key ") + key + " in defaults.def");
}

}  // namespace

const std::vector<ParameterSpec>& parameter_specs() {
  static const std::vector<ParameterSpec> specs = {
      {"scene", "", to_string(SceneConfig{}.scene), true, "contact scene: fixed_tip | frictionless | viscous", true},
      numeric("mass", "kg", true, "m, mass of the top"),
      numeric("inertia_transverse", "kg m^2", true, "A, transverse principal moment of inertia about G"),
      numeric("inertia_axial", "kg m^2", true, "C, moment of inertia about the symmetry axis (C <= 2A)"),
      numeric("tip_distance", "m", true, "h, distance from the tip to the centre of mass G"),
      numeric("gravity", "m/s^2", false, "g, gravitational acceleration"),
      numeric("friction", "N s/m", false, "k, viscous friction F = -k v_P on the tip (viscous scene only)"),
      numeric("rim_radius", "m", false,
              "b, radius of the body's rim, a circle about the axis: the top has fallen when it touches the "
              "floor (0: a needle, fallen when the axis reaches the floor)"),
      numeric("rim_distance", "m", false, "a, distance of the rim's centre from the tip along the axis (> 0 when b > 0)"),
      {"after_lift_off", "", to_string(SceneConfig{}.after_lift_off), false,
       "where the tip would leave the floor: fly (flight, landing, skim: doc/spec/HYBRID.md) | stop (the run ends "
       "with lift_off)", true},
      numeric("restitution", "", false, "e in [0, 1), landing: the tip's vertical velocity after = -e x before"),
      numeric("restitution_speed", "m/s", false, "landings slower than this are plastic (e = 0)"),
      numeric("initial/tilt", "rad", true, "theta0, initial angle of the axis from the vertical (|theta0| < pi/2)"),
      numeric("initial/precession_rate", "rad/s", false, "phidot0, initial precession rate"),
      numeric("initial/nutation_rate", "rad/s", false, "thetadot0, initial nutation rate"),
      numeric("initial/spin", "rad/s", true, "omega_Z, spin about the symmetry axis (a constant of motion)"),
      numeric("initial/heading", "rad", false, "phi0, initial heading (precession angle)"),
      numeric("initial/spin_angle", "rad", false, "psi0, initial spin angle"),
      numeric("initial/velocity_x", "m/s", false, "initial horizontal velocity of G, x (viscous scene only)"),
      numeric("initial/velocity_y", "m/s", false, "initial horizontal velocity of G, y (viscous scene only)"),
      {"integrator", "", to_string(IntegratorSettings{}.type), false, integrator_key_description(), true},
      numeric("step", "s", false,
              "largest substep of the fixed-step integrators; refused beyond 2 / (rate of the fastest motion), "
              "except by auto (its rule: the integrator table)"),
      numeric("tolerance", "", false,
              "local error tolerance (relative and absolute) of adaptive integrators; auto runs its methods at "
              "fractions of it (its rule: the integrator table)"),
  };
  return specs;
}

std::string brief_text(const std::string& text, std::size_t limit) {
  // Whole up to `limit` characters; else the first half of that, so that a number of 300 digits
  // shows 20 of them, and its length.
  const std::size_t shown_characters = text.size() <= limit ? text.size() : limit / 2;
  std::string shown;
  // Control characters (a newline, a NUL in a key) as escapes: a message stays one line.
  for (std::size_t i = 0; i < shown_characters; ++i) {
    const unsigned char c = static_cast<unsigned char>(text[i]);
    if (c >= 0x20 && c != 0x7f) {
      shown += text[i];
    } else {
      char escape[8];
      std::snprintf(escape, sizeof escape, "\\x%02x", c);
      shown += escape;
    }
  }
  if (text.size() > limit) shown += "... (" + std::to_string(text.size()) + " characters)";
  return shown;
}

double parse_number(const std::string& key, const std::string& text) {
  const char* begin = text.c_str();
  char* end = nullptr;
  errno = 0;
  const double value = std::strtod(begin, &end);
  while (end != nullptr && (*end == ' ' || *end == '\t')) ++end;
  // end != text's end: an embedded NUL ("1\0abc") is not a number either.
  if (text.empty() || end == begin || end != begin + text.size())
    throw InvalidParameter(key, "'" + brief_text(text) + "' is not a number");
  if (errno == ERANGE && (value > 1.0 || value < -1.0))
    throw InvalidParameter(key, "'" + brief_text(text) + "' is out of range");
  return value;
}

std::vector<std::string> parameter_keys() {
  std::vector<std::string> keys;
  for (const ParameterSpec& spec : parameter_specs()) keys.push_back(spec.key);
  return keys;
}

std::string nearest_name(const std::string& name, const std::vector<std::string>& known) {
  std::string best;
  // A near miss is at most 2 edits away: a name longer than every known one by more is none
  // (and a 20 MB name would cost 20 M x 25 steps).
  std::size_t longest = 0;
  for (const std::string& candidate : known) longest = std::max(longest, candidate.size());
  if (name.size() > longest + 2) return best;
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
    throw InvalidParameter(brief_text(key), "unknown key" + (nearest.empty() ? std::string() : " (did you mean " + nearest + "?)") +
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
  // A name's parser (parse_scene, ...) names what it was given: not a 20 MB value.
  auto name = [&](const char* key, auto parse) {
    const std::string given = string(key);
    if (given.size() > 40) throw InvalidParameter(key, "'" + brief_text(given) + "' is not a name this key takes");
    return parse(given);
  };

  SceneConfig config;
  config.scene = name("scene", parse_scene);
  config.top.mass = number("mass");
  config.top.inertia_transverse = number("inertia_transverse");
  config.top.inertia_axial = number("inertia_axial");
  config.top.tip_distance = number("tip_distance");
  config.top.gravity = number("gravity");
  config.top.friction = number("friction");
  config.top.rim_radius = number("rim_radius");
  config.top.rim_distance = number("rim_distance");
  config.top.restitution = number("restitution");
  config.top.restitution_speed = number("restitution_speed");
  config.after_lift_off = name("after_lift_off", parse_after_lift_off);
  config.initial.tilt = number("initial/tilt");
  config.initial.precession_rate = number("initial/precession_rate");
  config.initial.nutation_rate = number("initial/nutation_rate");
  config.initial.spin = number("initial/spin");
  config.initial.heading = number("initial/heading");
  config.initial.spin_angle = number("initial/spin_angle");
  config.initial.velocity_x = number("initial/velocity_x");
  config.initial.velocity_y = number("initial/velocity_y");
  config.integrator.type = name("integrator", parse_integrator);
  config.integrator.step = number("step");
  config.integrator.tolerance = number("tolerance");
  validate(config);
  return config;
}

}  // namespace spinning_top
