#include "spinning_top/tick_clock.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace spinning_top {
namespace {

void check_pace(double rate, double real_time_factor) {
  if (!(std::isfinite(rate) && rate > 0.0))
    throw std::invalid_argument("TickClock: the rate must be finite and > 0");
  if (!(std::isfinite(real_time_factor) && real_time_factor >= 0.0))
    throw std::invalid_argument("TickClock: the real-time factor must be finite and >= 0");
}

}  // namespace

TickClock::TickClock(double rate, double real_time_factor) : rate_(rate), real_time_factor_(real_time_factor) {
  check_pace(rate, real_time_factor);
}

void TickClock::set_pace(double rate, double real_time_factor, double wall_now) {
  check_pace(rate, real_time_factor);
  time_anchor_ = time();
  time_anchor_tick_ = ticks_;
  rate_ = rate;
  real_time_factor_ = real_time_factor;
  anchor(wall_now);
}

void TickClock::anchor(double wall_now) {
  wall_anchor_ = wall_now;
  wall_anchor_tick_ = ticks_;
}

long TickClock::due(double wall_now) const {
  if (real_time_factor_ == 0.0) return 0;
  const double slots = std::floor(slots_since_anchor(wall_now) + 0.5);
  const double taken = static_cast<double>(ticks_ - wall_anchor_tick_);
  return slots > taken ? static_cast<long>(std::min(slots - taken, 1e15)) : 0;
}

double TickClock::lag(double wall_now) const {
  if (real_time_factor_ == 0.0) return 0.0;
  const double behind = slots_since_anchor(wall_now) - static_cast<double>(ticks_ - wall_anchor_tick_);
  return std::max(0.0, behind / (rate_ * real_time_factor_));
}

long TickClock::give_up_beyond(double wall_now, double max_lag) {
  if (real_time_factor_ == 0.0) return 0;
  const long allowed = static_cast<long>(std::floor(max_lag * rate_ * real_time_factor_));
  const long excess = due(wall_now) - allowed;
  if (excess <= 0) return 0;
  // Move the anchor forward by the given-up slots: they are no longer due.
  wall_anchor_ += static_cast<double>(excess) / (rate_ * real_time_factor_);
  return excess;
}

}  // namespace spinning_top
