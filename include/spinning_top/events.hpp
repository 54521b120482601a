// Validity events of the contact model (PHYSICS.md, "Validity of the model"), and their
// location within a step.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <string>

#include "spinning_top/kinematics.hpp"

namespace spinning_top {

enum class Event {
  kNone,
  kLiftOff,    ///< R < 0: the floor would have to pull the tip down
  kFallen,     ///< e_Zz <= 0: the axis has reached the floor
  kNonFinite,  ///< the solution could not be continued with finite values
};

/// "lift_off", "fallen", "non_finite", or "" for kNone (the CSV and ROS spelling).
const char* to_string(Event event);

/// The event functions g(y) = (R, e_Zz): the model is valid while both are positive. The
/// first to turn negative (or e_Zz to reach zero) ends the run.
template <class Model>
Eigen::Vector2d event_functions(const Model& model, const typename Model::State& y) {
  return Eigen::Vector2d(model.normal_force(y), vertical_in_body(y).z());
}

inline Event triggered_event(const Eigen::Vector2d& g) {
  if (!std::isfinite(g[0]) || !std::isfinite(g[1])) return Event::kNonFinite;
  if (g[1] <= 0.0) return Event::kFallen;
  if (g[0] < 0.0) return Event::kLiftOff;
  return Event::kNone;
}

/// Finds, in (t_lo, t_hi], where an event function turns from valid at t_lo to triggered
/// at t_hi, by the Illinois variant of regula falsi on state_at(t) (superlinear, and
/// bracketing like bisection). Every event function that triggers at t_hi is located and
/// the earliest wins. Returns the last valid time (at most a few ulps of t before the
/// root), so the state reported with the event is still a valid one.
template <class Model, class StateAt>
double locate_event(const Model& model, double t_lo, const Eigen::Vector2d& g_lo, double t_hi,
                    const Eigen::Vector2d& g_hi, const StateAt& state_at, Event& which) {
  double best_t = t_hi;
  which = Event::kNone;
  for (int i = 0; i < 2; ++i) {
    const bool fires = (i == 0) ? (g_hi[0] < 0.0) : (g_hi[1] <= 0.0);
    if (!fires) continue;
    double a = t_lo, fa = g_lo[i], b = t_hi, fb = g_hi[i];
    int side = 0;
    const double tolerance = 4e-15 * std::max(1.0, std::abs(t_hi)) + 1e-300;
    for (int iteration = 0; iteration < 200 && (b - a) > tolerance; ++iteration) {
      double c = (fa - fb != 0.0) ? b - fb * (b - a) / (fb - fa) : 0.5 * (a + b);
      if (!(c > a && c < b)) c = 0.5 * (a + b);
      const double fc = event_functions(model, state_at(c))[i];
      const bool triggered = (i == 0) ? (fc < 0.0) : (fc <= 0.0);
      if (!std::isfinite(fc) || triggered) {
        b = c;
        fb = std::isfinite(fc) ? fc : fb;
        if (side == -1) fa *= 0.5;  // Illinois: halve the stale end's weight
        side = -1;
      } else {
        a = c;
        fa = fc;
        if (side == +1) fb *= 0.5;
        side = +1;
      }
    }
    if (a < best_t || which == Event::kNone) {
      best_t = a;
      which = (i == 0) ? Event::kLiftOff : Event::kFallen;
    }
  }
  return best_t;
}

}  // namespace spinning_top
