// The node's simulated time and its pacing against a wall clock, without ROS (unit-tested in
// test_tick_clock.cpp): tick n is at exactly anchor + n / rate (no accumulated rounding), and at
// a real-time factor f the ticks due by wall time w are those whose slots (one every
// 1 / (rate f) wall seconds from the pacing anchor) have come, so ticks a busy machine missed are
// taken late instead of dropped: the simulated time keeps up with the wall clock.
#pragma once

namespace spinning_top {

class TickClock {
 public:
  /// Throws std::invalid_argument unless rate > 0 and real_time_factor >= 0 (both finite).
  TickClock(double rate, double real_time_factor);

  double rate() const { return rate_; }
  double real_time_factor() const { return real_time_factor_; }
  /// Ticks taken since the start.
  long ticks() const { return ticks_; }
  /// [s] simulated time of the last tick taken (0 before the first).
  double time() const { return time_at(ticks_); }
  /// [s] simulated time of the next tick.
  double next_time() const { return time_at(ticks_ + 1); }
  /// The first tick of the current rate (0, or the tick of the last set_pace()): from it on,
  /// the time between two ticks is their difference / rate() with one rounding.
  long rate_since() const { return time_anchor_tick_; }
  /// The next tick is taken: time() becomes next_time().
  void take() { ++ticks_; }

  /// New rate and factor: the next tick comes one new period after the last one, and pacing
  /// starts again at wall_now.
  void set_pace(double rate, double real_time_factor, double wall_now);
  /// Pacing starts again at wall_now (start, resume): the next tick is due one period later.
  void anchor(double wall_now);
  /// Ticks due at wall_now [s] and not yet taken (0 at factor 0, where there is no pace). A tick
  /// counts as due from half a period before its slot, so timer jitter does not split ticks.
  long due(double wall_now) const;
  /// [wall s] how far the ticks taken are behind the wall clock (0 when on time).
  double lag(double wall_now) const;
  /// Gives up the ticks due beyond `max_lag` wall seconds (an overload the machine cannot catch
  /// up): pacing re-anchors so that only max_lag remains due. Returns the ticks given up.
  long give_up_beyond(double wall_now, double max_lag);

 private:
  double time_at(long tick) const {
    return time_anchor_ + static_cast<double>(tick - time_anchor_tick_) / rate_;
  }
  double slots_since_anchor(double wall_now) const {
    return (wall_now - wall_anchor_) * rate_ * real_time_factor_;
  }

  double rate_, real_time_factor_;
  long ticks_ = 0;
  double time_anchor_ = 0.0;  // simulated time of tick time_anchor_tick_
  long time_anchor_tick_ = 0;
  double wall_anchor_ = 0.0;  // wall time from which ticks after wall_anchor_tick_ are due
  long wall_anchor_tick_ = 0;
};

}  // namespace spinning_top
