// The driver of `integrator: auto`: it runs auto's plan (auto_plan(), simulator.hpp) on the
// scene's own drivers. At every (re)start, reset() or a live update, it starts the plan's first
// choice from the current state and, if that one refuses the state (MethodRefusal: exact's
// degenerate states), the plan's fallback from the same state, and keeps what it chose and why
// (choice()). To SceneSimulator it is just another driver.
// Its candidates are the drivers of the integrators auto may choose (kAutoCandidates) that serve
// the scene: exact and dop853 for the integrable scenes, dop853 and radau9 for the viscous one.
#pragma once

#include <iterator>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>
#include <variant>

#include "spinning_top/integration/range_tracker.hpp"
#include "spinning_top/integrators/registry_rows.hpp"
#include "spinning_top/method_refusal.hpp"
#include "spinning_top/simulator.hpp"

namespace spinning_top {

template <class Model>
class AutoDriver {
  /// A candidate's driver, tagged with its integrator.
  template <IntegratorType type>
  struct Candidate {
    static constexpr IntegratorType kType = type;
    explicit Candidate(const IntegratorSettings& settings) : driver(settings) {}
    DriverFor<Model, type> driver;
  };
  /// std::variant of the Candidates of kAutoCandidates that serve the scene.
  template <std::size_t... i>
  static auto served(std::index_sequence<i...>)
      -> decltype(std::tuple_cat(std::declval<std::conditional_t<serves<kAutoCandidates[i], Model>(),
                                                                 std::tuple<Candidate<kAutoCandidates[i]>>,
                                                                 std::tuple<>>>()...));
  template <class... C>
  static auto as_variant(std::tuple<C...>*) -> std::variant<C...>;
  using Candidates = decltype(as_variant(
      static_cast<decltype(served(std::make_index_sequence<std::size(kAutoCandidates)>()))*>(nullptr)));

 public:
  using State = typename Model::State;
  static constexpr IntegratorKind kKind = IntegratorKind::kAutomatic;

  explicit AutoDriver(const SceneConfig& config) : plan_(auto_plan(config)), driver_(make(plan_.first)) {}

  /// (Re)starts at (t, y) with the plan's first choice, or with its fallback if the first refuses
  /// this state. A plan without fallback (viscous: its methods refuse no state) lets a refusal
  /// through, as does any other exception; the driver is then left as it was.
  void reset(const Model& model, double t, const State& y) {
    try {
      start(plan_.first, model, t, y);
      choice_ = {IntegratorType::kAuto, plan_.first.type, false, plan_.reason};
    } catch (const MethodRefusal& refusal) {
      if (plan_.fallback.type == IntegratorType::kAuto) throw;
      start(plan_.fallback, model, t, y);
      choice_ = {IntegratorType::kAuto, plan_.fallback.type, true, refusal.reason()};
    }
  }

  Event advance_to(const Model& model, double t, const WorkBudget& budget = WorkBudget()) {
    return std::visit([&](auto& c) { return c.driver.advance_to(model, t, budget); }, driver_);
  }
  double time() const {
    return std::visit([](const auto& c) { return c.driver.time(); }, driver_);
  }
  const State& state() const {
    return std::visit([](const auto& c) -> const State& { return c.driver.state(); }, driver_);
  }
  Event event() const {
    return std::visit([](const auto& c) { return c.driver.event(); }, driver_);
  }
  long steps() const {
    return std::visit([](const auto& c) { return c.driver.steps(); }, driver_);
  }
  /// Work units since the last (re)start (Driver::work()).
  long work() const {
    return std::visit([](const auto& c) { return c.driver.work(); }, driver_);
  }
  /// The last (re)start's work (Driver::restart_work()).
  long restart_work() const {
    return std::visit([](const auto& c) { return c.driver.restart_work(); }, driver_);
  }
  void stop(Event event) {
    std::visit([&](auto& c) { c.driver.stop(event); }, driver_);
  }

  /// The running driver's description, and why it runs: e.g. "exact: closed form, ...", or
  /// "dop853, tolerance 1e-12 (exact refused: the axis is vertical while it moves ...)".
  std::string description() const {
    const std::string running = std::visit([](const auto& c) { return c.driver.description(); }, driver_);
    if (choice_.fallback) return running + " (" + to_string(plan_.first.type) + " refused: " + choice_.reason + ")";
    return choice_.reason.empty() ? running : running + " (" + choice_.reason + ")";
  }
  const IntegratorChoice& choice() const { return choice_; }
  std::optional<ClosedFormRange> closed_form_range() const {
    return std::visit([](const auto& c) { return c.driver.closed_form_range(); }, driver_);
  }
  /// Driver::track_range() on the running candidate, and on every candidate started after it.
  void track_range(const Model& model) {
    tracking_ = true;
    std::visit([&](auto& c) { c.driver.track_range(model); }, driver_);
  }
  const RangeTracker<Model>* range_tracker() const {
    return std::visit([](const auto& c) { return c.driver.range_tracker(); }, driver_);
  }

 private:
  /// The candidate of settings.type, not started.
  template <std::size_t index = 0>
  static Candidates make(const IntegratorSettings& settings) {
    if constexpr (index < std::variant_size_v<Candidates>) {
      using C = std::variant_alternative_t<index, Candidates>;
      if (settings.type == C::kType) return Candidates(std::in_place_index<index>, settings);
      return make<index + 1>(settings);
    } else {
      throw std::logic_error(std::string("auto: planned ") + to_string(settings.type) + ", which is not among "
                             "kAutoCandidates serving " + Model::kName);
    }
  }

  /// Starts the candidate of settings.type at (t, y); throws what its reset throws, and then
  /// leaves the running driver as it was. The running candidate restarts in place (exact's
  /// restart to the state it was built from reuses its series and interpolation).
  void start(const IntegratorSettings& settings, const Model& model, double t, const State& y) {
    const bool running = std::visit([&](const auto& c) { return c.kType == settings.type; }, driver_);
    if (running) {
      std::visit([&](auto& c) { c.driver.reset(model, t, y); }, driver_);
      return;
    }
    Candidates next = make(settings);
    std::visit(
        [&](auto& c) {
          c.driver.reset(model, t, y);
          if (tracking_) c.driver.track_range(model);
        },
        next);
    driver_ = std::move(next);
  }

  AutoPlan plan_;
  Candidates driver_;
  IntegratorChoice choice_;
  bool tracking_ = false;  ///< track_range() was called: each candidate started tracks too
};

}  // namespace spinning_top
