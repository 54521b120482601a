// A bound on the work of one advance_to() call, so that a front end stays responsive whatever
// the physics asks (a node's timer callback, a batch run's CPU): at most max_steps integration
// steps, and no step begun after the deadline. An advance that runs out returns with no event
// and time() short of its target; calling it again with the same target continues exactly where
// it stopped, so results never depend on where (or whether) a budget ran out.
#pragma once

#include <algorithm>
#include <chrono>
#include <limits>

namespace spinning_top {

struct WorkBudget {
  using Clock = std::chrono::steady_clock;

  /// Steps per call: fixed-step substeps, or accepted adaptive steps (a step's rejected attempts
  /// count with it).
  long max_steps = std::numeric_limits<long>::max();
  Clock::time_point deadline = Clock::time_point::max();

  static WorkBudget unlimited() { return WorkBudget(); }
  static WorkBudget steps(long n) {
    WorkBudget budget;
    budget.max_steps = n;
    return budget;
  }
  /// The next call's share of a run's allowance of max_steps steps (a whole number; infinity or
  /// anything beyond a long: no limit) of which `taken` are spent: the run stops where its
  /// allowance ends, whichever call that falls in.
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
};

/// Counts a call's steps against its budget. The clock is read every 16 steps only (a read costs
/// about as much as a cheap step), so a deadline is overrun by at most 16 steps.
class BudgetMeter {
 public:
  explicit BudgetMeter(const WorkBudget& budget) : budget_(budget) {}
  /// True if one more step may start.
  bool allows_step() {
    if (taken_ >= budget_.max_steps) return false;
    if (budget_.has_deadline() && (taken_ & 15) == 0 && taken_ > 0 && WorkBudget::Clock::now() >= budget_.deadline)
      return false;
    ++taken_;
    return true;
  }

 private:
  const WorkBudget& budget_;
  long taken_ = 0;
};

}  // namespace spinning_top
