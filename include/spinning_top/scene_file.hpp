// Scene files: YAML maps whose nested keys flatten with '/' into the configuration keys
// ("initial: {tilt: 0.3}" is the key initial/tilt), so that a scene file is also a
// `rosparam load` file. One reader for every front end (`simulate`, the Python module) and the
// tests; needs yaml-cpp, hence its own library (spinning_top_scene_file) beside the core.
#pragma once

#include <stdexcept>
#include <string>

#include "spinning_top/config.hpp"

namespace spinning_top {

/// A scene file that cannot be read, is malformed YAML (what() gives file:line:column), has more
/// than one document, or is not a map of scalars.
class SceneFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The file's keys and their values as text, not yet parsed (parse_scene_config() does that,
/// so that --set overrides and a Python dict go through the same validation). An empty file
/// gives an empty map. Throws SceneFileError.
ParameterMap read_scene_file(const std::string& path);

}  // namespace spinning_top
