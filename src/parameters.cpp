#include "spinning_top/parameters.hpp"

#include <cmath>
#include <sstream>

namespace spinning_top {
namespace {

std::string format(double value) {
  std::ostringstream s;
  s.precision(17);
  s << value;
  return s.str();
}

void require_finite(const char* key, double value) {
  if (!std::isfinite(value)) throw InvalidParameter(key, "must be a finite number, got " + format(value));
}

void require_positive(const char* key, double value, const char* what) {
  require_finite(key, value);
  if (!(value > 0.0)) throw InvalidParameter(key, std::string(what) + " must be > 0, got " + format(value));
}

void require_non_negative(const char* key, double value, const char* what) {
  require_finite(key, value);
  if (!(value >= 0.0)) throw InvalidParameter(key, std::string(what) + " must be >= 0, got " + format(value));
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
  require_finite("initial/precession_rate", ic.precession_rate);
  require_finite("initial/nutation_rate", ic.nutation_rate);
  require_finite("initial/spin", ic.spin);
  require_finite("initial/heading", ic.heading);
  require_finite("initial/spin_angle", ic.spin_angle);
  require_finite("initial/velocity_x", ic.velocity_x);
  require_finite("initial/velocity_y", ic.velocity_y);
  // e_Zz = cos(tilt) > 0: the axis must start above the floor. |tilt| < pi/2 as documented, not
  // cos(tilt) > 0 alone, which also let 2 pi + 0.3 through.
  if (!(std::abs(ic.tilt) < 0.5 * M_PI && std::cos(ic.tilt) > 0.0))
    throw InvalidParameter("initial/tilt", "the axis must start above the floor: need |tilt| < pi/2 rad, got " +
                                               format(ic.tilt));
}

}  // namespace spinning_top
