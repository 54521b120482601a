// A bound on the work of one advance_to() call, so that a front end stays responsive whatever
// the physics asks (a node's timer callback, a batch run's CPU): at most max_steps steps of work,
// and no step begun after the deadline. An advance that runs out returns with no event and
// time() short of its target; calling it again with the same target continues exactly where it
// stopped, so results never depend on where (or whether) a budget ran out.
//
// What a step is (issue 19): work, not a count of accepted steps, so that one budget bounds the
// time of every method within a few times. Work is counted in units of about one evaluation of
// the model's derivative, deterministically (counts, never a clock): each method charges what it
// does (integration/steppers.hpp), rejected attempts, Newton iterations, Jacobians, matrix
// factorizations, collocation sweeps and dense output included, linear algebra at its measured
// cost in evaluations (bench/budget_time.cpp). One step of the budget is kWorkPerStep units, the
// work of a dop853 step with its dense output and the driver's checks, and every accepted step
// costs at least one: a run's work is max(steps x kWorkPerStep, units charged). So a budget of N
// steps allows at most N accepted steps of any method, exactly N of the cheap ones (rk4, dopri5,
// dop853, whose slack also absorbs a few rejected attempts), and fewer where steps cost more
// (radau5 6-15 budget steps per step, rodas4 4, the splittings 1.3-3, gauss6 2). A restart
// inside a run (a hybrid contact phase's, where exact builds its solution again) counts its
// work too; a simulator's first start and reset() do not.
#pragma once

#include <algorithm>
#include <chrono>
#include <limits>

namespace spinning_top {

/// Work units in one step of the budget: a dop853 step (12 evaluations of the derivative), its
/// dense output (3) and the driver's checks after it (1).
inline constexpr long kWorkPerStep = 16;

struct WorkBudget {
  using Clock = std::chrono::steady_clock;

  /// Work units per call (kWorkPerStep per step; steps() converts).
  long max_work = std::numeric_limits<long>::max();
  Clock::time_point deadline = Clock::time_point::max();

  static WorkBudget unlimited() { return WorkBudget(); }
  /// n steps of work (n <= 0: none; anything beyond what a long holds in units: no limit).
  static WorkBudget steps(long n) {
    WorkBudget budget;
    budget.max_work = n <= 0 ? 0 : n >= std::numeric_limits<long>::max() / kWorkPerStep ? std::numeric_limits<long>::max()
                                                                                          : n * kWorkPerStep;
    return budget;
  }
  /// The next call's share of a run's allowance of max_steps steps (a whole number; infinity or
  /// anything beyond a long: no limit) of which `taken` are spent (Simulator::work()): the run
  /// stops where its allowance ends, whichever call that falls in.
  static WorkBudget steps_left(double max_steps, long taken) {
    if (!(max_steps < static_cast<double>(std::numeric_limits<long>::max()))) return unlimited();
    return steps(static_cast<long>(std::max(0.0, max_steps - static_cast<double>(taken))));
  }
  static WorkBudget until(Clock::time_point deadline) {
    WorkBudget budget;
    budget.deadline = deadline;
    return budget;
  }
  bool has_deadline() const { return deadline != Clock::time_point::max(); }
  /// What is left of it after `spent` units of work (the same deadline).
  WorkBudget after(long spent) const {
    WorkBudget left = *this;
    if (max_work != std::numeric_limits<long>::max()) left.max_work = std::max(0L, max_work - spent);
    return left;
  }
};

/// Run work, in steps of the budget: units rounded up (a fraction of a step counts as spent).
inline long work_in_steps(long units) { return units / kWorkPerStep + (units % kWorkPerStep != 0 ? 1 : 0); }

/// Counts a call's work against its budget. The clock is read every 16 steps only (a read costs
/// about as much as a cheap step), so a deadline is overrun by at most 16 steps.
class BudgetMeter {
 public:
  explicit BudgetMeter(const WorkBudget& budget) : budget_(budget) {}
  /// True if one more step may start after `spent` units of work in this call: the first step
  /// of a call with a budget of at least one step always may (the call makes progress), and a
  /// step may overrun the budget by its own work.
  bool allows_step(long spent) {
    if (spent >= budget_.max_work) return false;
    if (budget_.has_deadline() && (taken_ & 15) == 0 && taken_ > 0 && WorkBudget::Clock::now() >= budget_.deadline)
      return false;
    ++taken_;
    return true;
  }
  /// The same for work that costs one step of the budget per step (a flight's search for the
  /// floor, a transition), counted here.
  bool allows_step() {
    if (!allows_step(flat_)) return false;
    flat_ += kWorkPerStep;
    return true;
  }

 private:
  const WorkBudget& budget_;
  long taken_ = 0;
  long flat_ = 0;
};

}  // namespace spinning_top
