#include "spinning_top/scene_file.hpp"

#include <sys/stat.h>
#include <yaml-cpp/yaml.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <vector>

namespace spinning_top {
namespace {

void flatten(const YAML::Node& node, const std::string& prefix, const std::string& file, ParameterMap& out) {
  for (const auto& entry : node) {
    if (!entry.first.IsScalar()) throw SceneFileError(file + ": keys must be plain names");
    const std::string name = entry.first.Scalar();
    const std::string key = prefix.empty() ? name : prefix + "/" + name;
    const YAML::Node& value = entry.second;
    if (value.IsMap()) {
      flatten(value, key, file, out);
    } else if (value.IsScalar()) {
      if (!out.emplace(key, value.Scalar()).second) throw SceneFileError(key + ": given twice in " + file);
    } else if (value.IsSequence()) {
      throw SceneFileError(key + ": a list is not a valid value (in " + file + ")");
    } else {
      throw SceneFileError(key + ": has no value (in " + file + ")");
    }
  }
}

}  // namespace

ParameterMap read_scene_file(const std::string& path) {
  struct stat st {};
  if (stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode))
    throw SceneFileError("'" + path + "' is a directory; give a scene file (e.g. config/fixed_tip.yaml)");
  std::ifstream in(path);
  if (!in) throw SceneFileError("cannot read '" + path + "': " + std::strerror(errno));
  std::stringstream text;
  text << in.rdbuf();
  YAML::Node root;
  try {
    // One document: a second one (after ---) would otherwise be ignored without a word.
    const std::vector<YAML::Node> documents = YAML::LoadAll(text.str());
    if (documents.size() > 1)
      throw SceneFileError(path + ": has " + std::to_string(documents.size()) +
                           " YAML documents (separated by ---); a scene file is one");
    if (!documents.empty()) root = documents.front();
  } catch (const YAML::Exception& e) {
    std::ostringstream where;
    where << path << ":" << e.mark.line + 1 << ":" << e.mark.column + 1 << ": malformed YAML: " << e.msg;
    throw SceneFileError(where.str());
  }
  ParameterMap values;
  if (root.IsNull()) return values;  // an empty file: the missing keys are reported later
  if (!root.IsMap()) throw SceneFileError(path + ": the top level must be a map of key: value");
  flatten(root, "", path, values);
  return values;
}

}  // namespace spinning_top
