// The configuration keys shared by the batch simulator's YAML files and the node's private
// parameters (~key), with their units and defaults, and their parsing into a SceneConfig.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "spinning_top/simulator.hpp"

namespace spinning_top {

struct ParameterSpec {
  const char* key;            ///< e.g. "initial/tilt" (YAML: initial: {tilt: ...})
  const char* unit;           ///< SI unit, "" for text
  /// Used when the key is absent: SceneConfig{}'s value (defaults.def) as text that parses back
  /// to it, bit for bit.
  std::string default_value;
  bool required_in_file;      ///< a scene file (batch simulator) must give it
  std::string description;
  bool text = false;          ///< a name (scene, integrator, after_lift_off), not a number
};

/// Every key, in documentation order.
const std::vector<ParameterSpec>& parameter_specs();

/// key -> value as text (a YAML scalar, a --set value, a ROS parameter).
using ParameterMap = std::map<std::string, std::string>;

/// Builds and validates a configuration. Unknown keys, values that are not numbers where a
/// number is expected and invalid values throw InvalidParameter naming the key. With
/// require_all, keys marked required_in_file must be present; otherwise their documented
/// defaults apply (the node's behaviour).
SceneConfig parse_scene_config(const ParameterMap& values, bool require_all);

/// Parses a whole decimal number in text (no trailing characters); throws InvalidParameter
/// (whose message shows at most the text's first 40 characters).
double parse_number(const std::string& key, const std::string& text);

/// `text` as a message shows a value someone gave: whole up to `limit` characters, else its first
/// limit / 2 and its length (a 20 MB value is not echoed, a 300-digit number shows 20 digits);
/// control characters escaped (\x0a), so that a message is one line.
std::string brief_text(const std::string& text, std::size_t limit = 40);

/// The known name nearest to `name` if it is a near miss (at most 2 edits, Levenshtein, and
/// fewer than half its letters), else "": for "did you mean" hints on unknown keys.
std::string nearest_name(const std::string& name, const std::vector<std::string>& known);

/// Every key of parameter_specs(), as strings.
std::vector<std::string> parameter_keys();

}  // namespace spinning_top
