// Scene files: YAML maps whose nested keys flatten with '/' into the configuration keys
// ("initial: {tilt: 0.3}" is the key initial/tilt), so that a scene file is also a
// `rosparam load` file. One reader for every front end (`simulate`, the node's ~spawn, the Python
// module and the sweep) and the tests; needs yaml-cpp, hence its own library
// (spinning_top_scene_file) beside the core.
#pragma once

#include <stdexcept>
#include <string>

#include "spinning_top/config.hpp"

namespace spinning_top {

/// A scene file that cannot be read, is not a regular file of at most 1 MiB, is malformed YAML
/// (what() gives file:line:column), has more than one document, anchors, aliases, tags or more
/// than 10,000 nodes or 16 levels, is not a map of scalars, or has a number that is quoted or in
/// a form YAML 1.1 (rosparam) and YAML 1.2 read differently (what() starts with the key). One line.
class SceneFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The file's keys and their values as text, not yet parsed (parse_scene_config() does that,
/// so that --set overrides and a Python dict go through the same validation). An empty file
/// gives an empty map. Bounded in memory and time whatever the file is (issue 19: doc/simulate.md,
/// "What a scene file may be"). Throws SceneFileError.
ParameterMap read_scene_file(const std::string& path);

}  // namespace spinning_top
