// The run-time view of the integrator registry, generated from its rows
// (integrators/registry_rows.hpp), and the name <-> IntegratorType mapping that every front end
// goes through.
#include "spinning_top/integrator_registry.hpp"

#include <string>
#include <utility>

#include "spinning_top/auto_driver.hpp"  // the auto row's driver, for its kind
#include "spinning_top/integrators/registry_rows.hpp"

namespace spinning_top {

namespace {

/// A row's help line. auto's is its rule, auto_rule_summary(), built from the constants auto_plan()
/// runs on (not a copy of it).
template <IntegratorType type>
const char* help_of() {
  if constexpr (type == IntegratorType::kAuto) {
    static const std::string help =
        auto_rule_summary() + "; chooses again at reset and live updates, and says what it runs and why";
    return help.c_str();
  } else {
    return Integrator<type>::kHelp;
  }
}

template <IntegratorType type>
IntegratorInfo info_of() {
  using Row = Integrator<type>;
  return {type, Row::kName, Row::kScenes, kind_of<type>(), Row::kStepLimit, help_of<type>(), Row::kSceneNote};
}

template <int... index>
std::vector<IntegratorInfo> all_rows(std::integer_sequence<int, index...>) {
  return {info_of<static_cast<IntegratorType>(index)>()...};
}

/// "a, b, c<last>d".
std::string join(const std::vector<const char*>& names, const char* last) {
  std::string text;
  for (std::size_t i = 0; i < names.size(); ++i)
    text += std::string(i == 0 ? "" : i + 1 == names.size() ? last : ", ") + names[i];
  return text;
}

constexpr SceneType kAllSceneTypes[] = {SceneType::kFixedTip, SceneType::kFrictionless, SceneType::kViscous};

}  // namespace

const char* to_string(IntegratorKind kind) {
  switch (kind) {
    case IntegratorKind::kAutomatic: return "automatic";
    case IntegratorKind::kFixedStep: return "fixed step";
    case IntegratorKind::kAdaptive: return "adaptive";
    case IntegratorKind::kClosedForm: return "closed form";
  }
  return "";
}

std::string IntegratorInfo::scene_names() const {
  if (scenes == kAllScenes) return "all scenes";
  std::vector<const char*> names;
  for (SceneType scene : kAllSceneTypes)
    if (serves(scene)) names.push_back(to_string(scene));
  return join(names, " and ");
}

const std::vector<IntegratorInfo>& integrator_registry() {
  static const std::vector<IntegratorInfo> rows = all_rows(std::make_integer_sequence<int, kIntegratorCount>());
  return rows;
}

const IntegratorInfo& integrator_info(IntegratorType type) {
  return integrator_registry().at(static_cast<std::size_t>(type));  // rows are in enum order
}

std::string integrators_serving(SceneType scene) {
  std::vector<const char*> names;
  for (const IntegratorInfo& row : integrator_registry())
    if (row.serves(scene)) names.push_back(row.name);
  return join(names, " or ");
}

const char* to_string(IntegratorType integrator) { return integrator_info(integrator).name; }

IntegratorType parse_integrator(const std::string& name) {
  std::string names;
  for (const IntegratorInfo& row : integrator_registry()) {
    if (name == row.name) return row.type;
    names += (names.empty() ? "" : ", ") + std::string(row.name);
  }
  throw InvalidParameter("integrator", "'" + name + "' is not one of " + names);
}

}  // namespace spinning_top
