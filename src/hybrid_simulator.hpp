// HybridSimulator: the top goes on where the seed's contact model ends (doc/spec/HYBRID.md). It
// runs one phase at a time, each with its own minimal model: the scene's contact phase (the scene
// model and its driver, scene_simulator.hpp; viscous skimming is the same model with R held at 0),
// and flight, in closed form (scenes/flight.hpp). A contact phase ends at its driver's validity
// event, located as before; a flight at its first touch of the floor, found along the closed form.
// The transitions (scenes/impact.hpp) map the state into the next phase:
//   contact --lift_off--> flight (the free tip rises), skim (viscous), or the end (fixed tip);
//   skim --take_off--> flight, skim --> contact (no row);
//   flight --landing--> contact (plastic), flight (a bounce), or fallen (the rim first).
// Included only by the per-scene factory units (src/scenes/*_simulator.cpp).
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "scene_simulator.hpp"
#include "spinning_top/scenes/flight.hpp"
#include "spinning_top/scenes/impact.hpp"

namespace spinning_top {
namespace scene_factory {

template <class Model>
class HybridSimulator final : public Simulator {
 public:
  using State = typename Model::State;
  static constexpr bool kViscous = std::is_same_v<Model, Viscous>;
  static constexpr bool kFixedTip = std::is_same_v<Model, FixedTip>;

  explicit HybridSimulator(const SceneConfig& config) : config_(config), contact_(make_contact_phase<Model>(config)) {
    time_ = contact_->time();
    settle_start();
  }

  using Simulator::advance_to;
  Event advance_to(double t, const WorkBudget& budget) override {
    if (!std::isfinite(t)) throw std::invalid_argument("advance_to: the target time must be finite, got " + std::to_string(t));
    // Work units of this call (work_budget.hpp): the contact phases' (with their restarts at the
    // transitions: exact builds its solution again), and one step of the budget per step of a
    // flight's search and per transition's row (record()).
    const long start = work_units();
    auto used = [&] { return work_units() - start; };
    for (;;) {
      if (terminal_ != Event::kNone) return terminal_;
      if (phase_ != Phase::kFlight) {
        const Event event = contact_->advance_to(t, budget.after(used()));
        time_ = contact_->time();
        if (event == Event::kNone) return Event::kNone;  // at t, or out of budget
        if (event != Event::kLiftOff) return end(event);
        if (used() >= budget.max_work) return Event::kNone;  // the event stays pending in the phase
        after_floor_event();
        continue;
      }
      if (t <= time_) return Event::kNone;
      // The search for the touch is the flight's work: each of its steps counts against the budget
      // (and the deadline), as an integration step does.
      const WorkBudget flight_budget = budget.after(used());
      BudgetMeter meter(flight_budget);
      long searched = 0;
      const Flight::Touch touch = flight_.search_until(t, [&] {
        if (!meter.allows_step()) return false;
        ++searched;
        return true;
      });
      own_work_ += searched * kWorkPerStep;
      finished_steps_ += searched;
      if (touch.out_of_budget) {
        time_ = std::max(time_, flight_.searched_until());
        return Event::kNone;
      }
      if (touch.event == Event::kNone) {
        time_ = t;
        return Event::kNone;
      }
      if (used() >= budget.max_work) return Event::kNone;
      touch_down(touch);
    }
  }

  double time() const override { return time_; }
  Event event() const override { return terminal_; }

  Snapshot snapshot() const override {
    if (phase_ == Phase::kFlight) return flight_snapshot(flight_.at(time_));
    Snapshot s = contact_->snapshot();
    if (contact_->event() == Event::kLiftOff && s.outputs.normal_force < 0.0) {
      // A contact phase that starts where its R < 0 (after a landing, or a skim's end under stiff
      // friction) lifts off at that instant: the floor cannot pull, so what it exerts there is 0.
      s.outputs.normal_force = 0.0;
      s.outputs.contact_force = Vector3::Zero();
    }
    s.outputs.center_of_mass.head<2>() += offset_;
    s.outputs.contact_point.head<2>() += offset_;
    s.outputs.dissipated_energy += impact_loss_;
    s.phase = phase_;
    return s;
  }

  std::optional<MotionRange> motion_range() const override {
    if (hops_.lift_offs > 0) return std::nullopt;  // the tip has left the floor: ranges of one contact phase only
    return contact_->motion_range();
  }
  void track_motion_range() override { contact_->track_motion_range(); }

  bool reset() override {
    const IntegratorChoice before = integrator_choice();
    const Model fresh(config_.top, config_.initial);
    contact_->restart(fresh, 0.0, fresh.initial_state());
    contact_->reset();
    phase_ = Phase::kContact;
    offset_ = Vector2::Zero();
    time_ = contact_->time();
    terminal_ = Event::kNone;
    transitions_.clear();
    hops_ = HopSummary();
    finished_steps_ = 0;
    own_work_ = 0;
    impact_loss_ = 0.0;
    flight_work_ = 0.0;
    same_instant_ = 0;
    last_transition_time_ = -1.0;
    settle_start();
    const IntegratorChoice now = integrator_choice();
    return now.method != before.method || now.fallback != before.fallback;
  }

  bool update(const TopParameters& top, const IntegratorSettings& integrator) override {
    if (phase_ != Phase::kContact) {
      SceneConfig next = config_;
      next.top = top;
      next.integrator = integrator;
      validate(next);
      throw InvalidParameter(changed_key(top, integrator), std::string("cannot change while the tip is off the floor (") +
                                                                to_string(phase_) + "); the run goes on unchanged");
    }
    const bool switched = contact_->update(top, integrator);
    config_.top = top;
    config_.integrator = integrator;
    return switched;
  }

  const SceneConfig& config() const override { return config_; }
  std::string integrator_description() const override { return contact_->integrator_description(); }
  IntegratorChoice integrator_choice() const override { return contact_->integrator_choice(); }
  long steps() const override { return finished_steps_ + (phase_ == Phase::kFlight ? 0 : contact_->steps()); }
  /// The contact phases' work (across their restarts), and one step of the budget per step of a
  /// flight's search and per transition.
  long work() const override { return work_in_steps(work_units()); }

  std::vector<Transition> take_transitions() override {
    std::vector<Transition> taken;
    taken.swap(transitions_);
    return taken;
  }
  HopSummary hops() const override {
    HopSummary summary = hops_;
    if (phase_ == Phase::kFlight) summary.max_hop_height = std::max(summary.max_hop_height, flight_.max_tip_height());
    if (summary.first_lift_off_time < 0.0 && terminal_ == Event::kLiftOff) summary.first_lift_off_time = time_;
    summary.impact_loss = impact_loss_;
    return summary;
  }
  Phase phase() const override { return phase_; }

 private:
  long work_units() const { return contact_->work_units() + own_work_; }

  /// A start that is already an event: R < 0 at release lifts off at once (the snapshot at t = 0
  /// is then the flight's or the skim's, never a contact state with R < 0); any other ends the run.
  void settle_start() {
    const Event at_start = contact_->event();
    if (at_start == Event::kLiftOff) {
      after_floor_event();
    } else if (at_start != Event::kNone) {
      end(at_start);
    }
  }

  /// The first key an update changes (for its refusal's message).
  std::string changed_key(const TopParameters& top, const IntegratorSettings& integrator) const {
    const TopParameters& p = config_.top;
    const std::pair<const char*, bool> keys[] = {
        {"mass", top.mass != p.mass},
        {"inertia_transverse", top.inertia_transverse != p.inertia_transverse},
        {"inertia_axial", top.inertia_axial != p.inertia_axial},
        {"tip_distance", top.tip_distance != p.tip_distance},
        {"gravity", top.gravity != p.gravity},
        {"friction", top.friction != p.friction},
        {"rim_radius", top.rim_radius != p.rim_radius},
        {"rim_distance", top.rim_distance != p.rim_distance},
        {"restitution", top.restitution != p.restitution},
        {"restitution_speed", top.restitution_speed != p.restitution_speed},
        {"step", integrator.step != config_.integrator.step},
        {"tolerance", integrator.tolerance != config_.integrator.tolerance},
    };
    for (const auto& [key, changed] : keys)
      if (changed) return key;
    return "integrator";
  }

  Event end(Event event) {
    terminal_ = event;
    return event;
  }

  /// A transition's row; it counts as one step (the work budget bounds a chain of them).
  void record(Event event) {
    // Transitions at one instant: a landing and its lift-off, a lift-off and its take-off, a skim's
    // end. More than kChatter of them means the floor can neither hold the tip nor let it go (a
    // stiff friction's R flipping sign with the state's last bit): the run ends with lift_off.
    same_instant_ = last_transition_time_ == time_ ? same_instant_ + 1 : 0;
    last_transition_time_ = time_;
    if (same_instant_ > kChatter) {
      end(Event::kLiftOff);
      return;
    }
    // A caller that never takes them (advance_to alone) keeps the newest kMaxPending.
    if (transitions_.size() >= kMaxPending) transitions_.erase(transitions_.begin(), transitions_.begin() + kMaxPending / 2);
    transitions_.push_back({event, snapshot()});
    ++finished_steps_;
    own_work_ += kWorkPerStep;
  }
  static constexpr std::size_t kMaxPending = 1 << 14;
  static constexpr int kChatter = 8;
  int same_instant_ = 0;
  double last_transition_time_ = -1.0;

  /// The state of the free top at a contact phase's state (its outputs, shifted to where the
  /// phase's model stands).
  FreeBody free_body_of(const Snapshot& s) const {
    FreeBody body;
    body.attitude = s.attitude;
    body.body_rates = s.body_rates;
    body.position = s.outputs.center_of_mass;
    body.velocity = s.outputs.center_of_mass_velocity;
    return body;
  }

  Snapshot flight_snapshot(const FreeBody& s) const {
    const TopParameters& p = config_.top;
    Snapshot out;
    out.time = time_;
    out.attitude = s.attitude;
    out.body_rates = s.body_rates;
    out.phase = Phase::kFlight;
    const Vector3 axis = s.attitude * Vector3::UnitZ();
    out.outputs.center_of_mass = s.position;
    out.outputs.center_of_mass_velocity = s.velocity;
    out.outputs.contact_point = s.position - p.tip_distance * axis;
    out.outputs.contact_point.z() = std::max(0.0, flight_.tip_height(time_));  // the closed form's, free of cancellation
    out.outputs.energy = kinetic_energy(p, s) + p.mass * p.gravity * s.position.z();
    const Vector3 momentum =
        s.attitude * Vector3(p.inertia_transverse * s.body_rates.x(), p.inertia_transverse * s.body_rates.y(),
                             p.inertia_axial * s.body_rates.z());
    out.outputs.vertical_angular_momentum = momentum.z();
    out.outputs.dissipated_energy = flight_work_ + impact_loss_;
    return out;
  }

  /// Flight from the contact phase's state at time_ (a lift-off or a take-off).
  void fly_from_floor() {
    const Snapshot s = snapshot();
    finished_steps_ += contact_->steps();
    flight_work_ = s.outputs.dissipated_energy - impact_loss_;
    flight_ = Flight(config_.top, time_, free_body_of(s), TipStart{});
    phase_ = Phase::kFlight;
  }

  /// The contact phase's driver reported kLiftOff: R < 0 ahead (contact), or the skim's end.
  void after_floor_event() {
    const State& y = contact_->state();
    if constexpr (kViscous) {
      if (phase_ == Phase::kSkim) {
        // The located state is the skim's last valid one: the function that ended it (the smaller of
        // the two in Viscous::contact_validity) is the one at zero.
        const Vector2 r = contact_->model().normal_force_range(y);
        const double back_to_sliding = Viscous::kSkimReturn * config_.top.mass * config_.top.gravity - r.y();
        if (r.x() <= back_to_sliding) {  // R0 reaches 0: the free tip rises, take-off
          fly_from_floor();
          ++hops_.take_offs;
          record(Event::kTakeOff);
        } else {  // the floor pushes again under full friction: sliding, no row
          restart_contact(Model(config_.top, config_.initial, false), y);
        }
        return;
      }
    }
    if (config_.after_lift_off == AfterLiftOff::kStop) {
      end(Event::kLiftOff);
      return;
    }
    if (hops_.first_lift_off_time < 0.0) hops_.first_lift_off_time = time_;
    bool flies = true;
    if constexpr (kFixedTip) {
      const Snapshot s = contact_->snapshot();
      flies = free_tip_vertical_acceleration(config_.top, s.attitude, s.body_rates) > 0.0;
      if (!flies) {
        // A pivot that may neither push nor let go is outside the model (HYBRID.md).
        end(Event::kLiftOff);
        return;
      }
    }
    // Viscous: a_f = -(det T / m) R0, so the tip flies where R0 < 0 and skims where friction alone
    // holds R down. At the located lift-off R0 >= R1 >= 0 by ulps where friction plays no part
    // (k = 0, or v_P = 0): a skim there would end at once, so R0 below the skim's own return
    // margin flies (a dive of at most eps / m, which the flight's start absorbs).
    if constexpr (kViscous)
      flies = contact_->model().normal_force_range(y).x() < Viscous::kSkimReturn * config_.top.mass * config_.top.gravity;
    ++hops_.lift_offs;
    if (flies) {
      fly_from_floor();
    } else if constexpr (kViscous) {
      restart_contact(Model(config_.top, config_.initial, true), y);
      if (terminal_ != Event::kNone) return;
    }
    record(Event::kLiftOff);
  }

  /// Restarts the contact phase at (time_, y) with `model`; a refusal of the configured closed form
  /// ends the run with the transition that led there.
  void restart_contact(const Model& model, const State& y) {
    finished_steps_ += phase_ == Phase::kFlight ? 0 : contact_->steps();
    try {
      contact_->restart(model, time_, y);
    } catch (const std::exception&) {
      end(phase_ == Phase::kFlight ? Event::kLanding : Event::kLiftOff);
      return;
    }
    phase_ = Phase::kContact;
    if constexpr (kViscous) {
      if (model.skimming()) phase_ = Phase::kSkim;
    }
  }

  /// The flight's first touch of the floor at touch.time.
  void touch_down(const Flight::Touch& touch) {
    time_ = touch.time;
    hops_.max_hop_height = std::max(hops_.max_hop_height, flight_.max_tip_height());
    if (flight_.cannot_rise()) {
      end(Event::kLiftOff);  // the free tip does not rise: no flight, and no contact either
      return;
    }
    const FreeBody before = flight_.at(time_);
    const double vertical = (before.attitude * Vector3::UnitZ()).z();
    if (touch.event == Event::kFallen || !(vertical > config_.top.fallen_vertical())) {
      end(Event::kFallen);  // the rim (or a needle's axis) on the floor
      return;
    }
    const Landing landing =
        land(config_.top, before, kFixedTip ? TangentialImpact::kStick : TangentialImpact::kNormalOnly);
    impact_loss_ += landing.kinetic_energy_loss;
    ++hops_.landings;
    if (landing.restitution > 0.0) {  // a bounce: flight goes on from the floor
      flight_ = Flight(config_.top, time_, landing.after, TipStart{0.0, landing.tip_speed_after});
      record(Event::kLanding);
      return;
    }
    // Plastic: the contact phase resumes from the state after the impulse.
    const FreeBody& s = landing.after;
    State y = State::Zero();
    set_attitude_and_rates(s.attitude, s.body_rates, y);
    if constexpr (kViscous) {
      y[Viscous::kX] = s.position.x();
      y[Viscous::kY] = s.position.y();
      y[Viscous::kVx] = s.velocity.x();
      y[Viscous::kVy] = s.velocity.y();
      y[Viscous::kWork] = flight_work_;
    }
    const Model model(config_.top, config_.initial);
    restart_contact(model, y);
    if (terminal_ != Event::kNone) return;
    // Where the phase's model stands G (fixed tip: over its pivot at the origin; frictionless: at
    // its G's fixed place), shifted to where the top landed.
    const Vector3 placed = model.outputs(y).center_of_mass;
    offset_ = s.position.template head<2>() - placed.template head<2>();
    record(Event::kLanding);
    const Event at_once = contact_->event();
    if (at_once == Event::kLiftOff) {
      // The floor cannot pull: the landing's row shows R = 0 (and no friction) where the
      // contact model's R is negative at once; the lift-off's row follows at the same time.
      transitions_.back().state.outputs.normal_force = 0.0;
      transitions_.back().state.outputs.contact_force = Vector3::Zero();
      after_floor_event();  // R < 0 at once: the lift-off rule at the same instant
    } else if (at_once != Event::kNone) {
      end(at_once);
    }
  }

  SceneConfig config_;
  std::unique_ptr<ContactPhase<Model>> contact_;
  Phase phase_ = Phase::kContact;
  Flight flight_;
  Vector2 offset_ = Vector2::Zero();  ///< the contact phase's horizontal shift of its model's positions
  double time_ = 0.0;
  Event terminal_ = Event::kNone;
  std::vector<Transition> transitions_;
  HopSummary hops_;
  long finished_steps_ = 0;   ///< the steps of the phases before the current contact phase
  long own_work_ = 0;         ///< work units of the flights' searches and the transitions
  double impact_loss_ = 0.0;  ///< [J] kinetic energy lost in the landings so far
  double flight_work_ = 0.0;  ///< [J] W at the last lift-off (constant in flight)
};

/// The scene's simulator: its contact phase alone with `after_lift_off: stop` (the seed's
/// model, unchanged), else the hybrid.
template <class Model>
std::unique_ptr<Simulator> make_scene_simulator(const SceneConfig& config) {
  if (config.after_lift_off == AfterLiftOff::kStop) return make_contact_phase<Model>(config);
  return std::make_unique<HybridSimulator<Model>>(config);
}

}  // namespace scene_factory
}  // namespace spinning_top
