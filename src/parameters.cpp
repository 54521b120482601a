#include "spinning_top/parameters.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace spinning_top {
namespace {

/// A number as a message shows it: the shortest text that reads back as the same double (at most
/// 17 significant digits, so 1e300 is "1e+300", never its 301 digits), which is how a user wrote it.
std::string format(double value) {
  char text[32];
  for (int digits = 6; digits <= 17; ++digits) {
    std::snprintf(text, sizeof text, "%.*g", digits, value);
    if (std::strtod(text, nullptr) == value) break;
  }
  return text;
}

/// The largest magnitude of any length, mass, moment of inertia, acceleration, friction
/// coefficient or angle [SI]: far beyond any top (the Sun's mass is 2e30 kg, the observable
/// universe 9e26 m across), and small enough that the model's expressions, products and quotients
/// of up to five keys and the rates (m h^2 / A in R, m g h, m v^2, A + m h^2), stay below 1e160
/// and finite however the keys combine. Before, m = 1e100 kg on h = 1e100 m with A = 1e-100 made
/// R = inf / inf = NaN; A = C = 1e300 at a spin of 1e6 rad/s made E = inf. Rates have a tighter
/// bound, kMaxMotionRate (simulator.cpp), and G's speed kMaxSpeed.
constexpr double kMaxMagnitude = 1e30;
/// The least mass and moments of inertia: they divide (1/m, h^2/A, m g h/A, m h^2/A).
constexpr double kLeastPositive = 1e-30;
/// G's initial horizontal speed [m/s]: at most 1e6 m/s, the motion bound of the rates (1e6 rad/s,
/// kMaxMotionRate) on a lever of 1 m. Far beyond any top (a rifle bullet flies at 1e3 m/s), and
/// the kinetic energy m v^2 / 2 stays finite for any mass accepted; 1e300 m/s gave E = inf.
constexpr double kMaxSpeed = 1e6;

void require_finite(const char* key, double value) {
  if (!std::isfinite(value)) throw InvalidParameter(key, "must be a finite number, got " + format(value));
  if (!(std::abs(value) <= kMaxMagnitude))
    throw InvalidParameter(key, "must lie within +-" + format(kMaxMagnitude) + " (every key does, so that the energy and "
                                "forces stay finite), got " + format(value));
}

void require_positive(const char* key, double value, const char* what) {
  require_finite(key, value);
  if (!(value > 0.0)) throw InvalidParameter(key, std::string(what) + " must be > 0, got " + format(value));
  if (!(value >= kLeastPositive))
    throw InvalidParameter(key, std::string(what) + " must be at least " + format(kLeastPositive) +
                                    " (it divides: a smaller one overflows the motion rates), got " + format(value));
}

void require_non_negative(const char* key, double value, const char* what) {
  require_finite(key, value);
  if (!(value >= 0.0)) throw InvalidParameter(key, std::string(what) + " must be >= 0, got " + format(value));
}

/// A rate: finite here; its bound is the motion bound (validate(SceneConfig), kMaxMotionRate).
void require_finite_rate(const char* key, double value) {
  if (!std::isfinite(value)) throw InvalidParameter(key, "must be a finite number, got " + format(value));
}

void require_speed(const char* key, double value) {
  require_finite_rate(key, value);
  if (!(std::abs(value) <= kMaxSpeed))
    throw InvalidParameter(key, "G's speed would be " + format(value) + " m/s; the simulator takes at most " +
                                    format(kMaxSpeed) + " m/s (as it takes rates up to 1e6 rad/s)");
}

}  // namespace

void validate(const TopParameters& p) {
  require_positive("mass", p.mass, "the mass m [kg]");
  require_positive("inertia_transverse", p.inertia_transverse, "the transverse moment of inertia A [kg m^2]");
  require_positive("inertia_axial", p.inertia_axial, "the axial moment of inertia C [kg m^2]");
  require_non_negative("tip_distance", p.tip_distance, "the tip distance h [m]");
  require_non_negative("gravity", p.gravity, "the gravitational acceleration g [m/s^2]");
  require_non_negative("friction", p.friction, "the friction coefficient k [N s/m]");
  require_non_negative("rim_radius", p.rim_radius, "the rim radius b [m]");
  require_non_negative("rim_distance", p.rim_distance, "the rim distance a [m]");
  if (p.rim_radius > 0.0 && !(p.rim_distance > 0.0))
    throw InvalidParameter("rim_distance", "a rim of radius b > 0 needs a > 0 (with a = 0 the rim is around the tip: "
                                           "the top would stand on it)");
  require_non_negative("restitution", p.restitution, "the coefficient of restitution e");
  if (!(p.restitution < 1.0))
    throw InvalidParameter("restitution", "must be < 1 (e = 1 bounces for ever), got " + format(p.restitution));
  require_non_negative("restitution_speed", p.restitution_speed, "the speed below which landings are plastic [m/s]");
  // A = integral of (y^2 + z^2) dm and C = integral of (x^2 + y^2) dm, so 2A - C = 2 integral z^2 dm >= 0.
  if (p.inertia_axial > 2.0 * p.inertia_transverse)
    throw InvalidParameter("inertia_axial", "C = " + format(p.inertia_axial) + " exceeds 2A = " +
                                                format(2.0 * p.inertia_transverse) +
                                                ": no rigid body has C > 2A (triangle inequality of inertia)");
}

void validate(const InitialConditions& ic) {
  require_finite("initial/tilt", ic.tilt);
  require_finite_rate("initial/precession_rate", ic.precession_rate);
  require_finite_rate("initial/nutation_rate", ic.nutation_rate);
  require_finite_rate("initial/spin", ic.spin);
  require_finite("initial/heading", ic.heading);
  require_finite("initial/spin_angle", ic.spin_angle);
  require_speed("initial/velocity_x", ic.velocity_x);
  require_speed("initial/velocity_y", ic.velocity_y);
  // e_Zz = cos(tilt) > 0: the axis must start above the floor. |tilt| < pi/2 as documented, not
  // cos(tilt) > 0 alone, which also let 2 pi + 0.3 through.
  if (!(std::abs(ic.tilt) < 0.5 * M_PI && std::cos(ic.tilt) > 0.0))
    throw InvalidParameter("initial/tilt", "the axis must start above the floor: need |tilt| < pi/2 rad, got " +
                                               format(ic.tilt));
}

}  // namespace spinning_top
