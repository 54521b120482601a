// The driver of `integrator: auto`: it runs auto's plan (auto_plan(), simulator.hpp) on the
// scene's own drivers. At every (re)start, reset() or a live update, it starts the plan's first
// choice from the current state and, if that one refuses the state (exact:
// InvalidParameter("integrator", why)), the plan's fallback from the same state, and keeps what
// it chose and why (choice()). To SceneSimulator it is just another driver.
// The candidates live in one std::variant with one alternative per IntegratorType, the registry's
// driver where the row serves the scene and an empty placeholder elsewhere, so that the rule
// (auto_plan) can name any integrator the scene has without a second list here.
#pragma once

#include <stdexcept>
#include <string>
#include <utility>
#include <variant>

#include "spinning_top/integrators/registry_rows.hpp"
#include "spinning_top/simulator.hpp"

namespace spinning_top {

/// Builds a driver from the settings it runs with (auto's plan gives them per candidate).
template <class Driver>
Driver make_driver(const IntegratorSettings& settings) {
  constexpr IntegratorKind kind = kind_of_driver<Driver>();
  static_assert(kind != IntegratorKind::kAutomatic, "AutoDriver is built from the whole SceneConfig");
  if constexpr (kind == IntegratorKind::kClosedForm) {
    return Driver();
  } else if constexpr (kind == IntegratorKind::kAdaptive) {
    return Driver(settings.tolerance);
  } else {
    return Driver(settings.step);
  }
}

template <class Model>
class AutoDriver {
  /// Stands for an integrator that does not serve this scene (and for auto itself).
  struct Unserved {};
  template <IntegratorType type>
  using Candidate = std::conditional_t<type != IntegratorType::kAuto && serves<type, Model>(), DriverFor<Model, type>,
                                       Unserved>;
  template <int... index>
  static auto candidates(std::integer_sequence<int, index...>)
      -> std::variant<Candidate<static_cast<IntegratorType>(index)>...>;
  /// Alternative i is the driver of IntegratorType(i).
  using Candidates = decltype(candidates(std::make_integer_sequence<int, kIntegratorCount>()));

 public:
  using State = typename Model::State;

  explicit AutoDriver(const SceneConfig& config) : plan_(auto_plan(config)) {}

  /// (Re)starts at (t, y) with the plan's first choice, or with its fallback if the first refuses
  /// this state (InvalidParameter "integrator"). A plan without fallback (viscous: its methods
  /// refuse no state) lets a refusal through, as does any other exception.
  void reset(const Model& model, double t, const State& y) {
    try {
      start(plan_.first, model, t, y);
      choice_ = {IntegratorType::kAuto, plan_.first.type, false, plan_.reason};
    } catch (const InvalidParameter& refusal) {
      if (refusal.parameter() != "integrator" || plan_.fallback.type == IntegratorType::kAuto) throw;
      start(plan_.fallback, model, t, y);
      choice_ = {IntegratorType::kAuto, plan_.fallback.type, true, reason_of(refusal)};
    }
  }

  Event advance_to(const Model& model, double t, const WorkBudget& budget = WorkBudget()) {
    return visit([&](auto& driver) { return driver.advance_to(model, t, budget); });
  }
  double time() const {
    return visit([](const auto& driver) { return driver.time(); });
  }
  const State& state() const {
    return visit([](const auto& driver) -> const State& { return driver.state(); });
  }
  Event event() const {
    return visit([](const auto& driver) { return driver.event(); });
  }
  long steps() const {
    return visit([](const auto& driver) { return driver.steps(); });
  }
  void stop(Event event) {
    visit([&](auto& driver) { driver.stop(event); });
  }

  /// The running driver's description, and why it runs: e.g. "exact: closed form, ...", or
  /// "dop853, tolerance 1e-12 (exact refused: the axis is vertical while it moves ...)".
  std::string description() const {
    const std::string running = visit([](const auto& driver) { return driver.description(); });
    if (choice_.fallback) return running + " (" + to_string(plan_.first.type) + " refused: " + choice_.reason + ")";
    return choice_.reason.empty() ? running : running + " (" + choice_.reason + ")";
  }
  const IntegratorChoice& choice() const { return choice_; }
  std::optional<ClosedFormRange> closed_form_range() const {
    return visit([](const auto& driver) { return driver.closed_form_range(); });
  }

 private:
  /// Emplaces the candidate of settings.type and starts it at (t, y); throws what its reset throws.
  template <std::size_t index = 0>
  void start(const IntegratorSettings& settings, const Model& model, double t, const State& y) {
    if constexpr (index < std::variant_size_v<Candidates>) {
      using Driver = std::variant_alternative_t<index, Candidates>;
      if constexpr (!std::is_same_v<Driver, Unserved>) {
        if (settings.type == static_cast<IntegratorType>(index)) {
          // The running candidate restarts in place (reset() keeps its settings, and exact's
          // reset() to the state it was built from reuses its series and interpolation).
          if (driver_.index() == index)
            std::get<index>(driver_).reset(model, t, y);
          else
            driver_.template emplace<index>(make_driver<Driver>(settings)).reset(model, t, y);
          return;
        }
      }
      start<index + 1>(settings, model, t, y);
    } else {
      throw std::logic_error(std::string("auto: planned ") + to_string(settings.type) + ", which does not serve " +
                             Model::kName);
    }
  }

  /// A driver of this scene, for the result types of visit().
  template <std::size_t index = 1>
  static constexpr std::size_t first_served() {
    if constexpr (std::is_same_v<std::variant_alternative_t<index, Candidates>, Unserved>)
      return first_served<index + 1>();
    else
      return index;
  }
  using Served = std::variant_alternative_t<first_served(), Candidates>;

  /// Calls f on the running driver (never a placeholder once reset() has run).
  template <class F>
  decltype(auto) visit(F&& f) const {
    using Result = decltype(f(std::declval<const Served&>()));
    return std::visit(
        [&](const auto& driver) -> Result {
          if constexpr (std::is_same_v<std::decay_t<decltype(driver)>, Unserved>)
            throw std::logic_error("auto: used before reset()");
          else
            return f(driver);
        },
        driver_);
  }
  template <class F>
  decltype(auto) visit(F&& f) {
    using Result = decltype(f(std::declval<Served&>()));
    return std::visit(
        [&](auto& driver) -> Result {
          if constexpr (std::is_same_v<std::decay_t<decltype(driver)>, Unserved>)
            throw std::logic_error("auto: used before reset()");
          else
            return f(driver);
        },
        driver_);
  }

  /// The refusal without its key ("integrator: "), the refusing method's own name prefix and
  /// its advice to the user ("; use dop853"), which auto has just followed.
  std::string reason_of(const InvalidParameter& refusal) const {
    std::string why = refusal.what();
    for (const std::string& prefix : {refusal.parameter() + ": ", std::string(to_string(plan_.first.type)) + ": "})
      if (why.compare(0, prefix.size(), prefix) == 0) why.erase(0, prefix.size());
    const std::size_t advice = why.rfind("; use ");
    if (advice != std::string::npos) why.erase(advice);
    return why;
  }

  AutoPlan plan_;
  Candidates driver_;
  IntegratorChoice choice_;
};

}  // namespace spinning_top
