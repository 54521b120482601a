// Physical parameters and initial conditions of a symmetric top, with validation.
// Units are SI (REP-103). Symbols follow doc/spec/PHYSICS.md.
#pragma once

#include <cmath>
#include <stdexcept>
#include <string>

#include "spinning_top/defaults.hpp"

namespace spinning_top {

/// The rigid body and its environment. Defaults: defaults.def (the toy top of config/*.yaml).
struct TopParameters {
  double mass = defaults::kMass;  ///< m [kg]
  double inertia_transverse = defaults::kInertiaTransverse;  ///< A [kg m^2], transverse principal moment about G
  double inertia_axial = defaults::kInertiaAxial;  ///< C [kg m^2], moment about the symmetry axis
  double tip_distance = defaults::kTipDistance;  ///< h [m], distance from the tip P to the centre of mass G
  double gravity = defaults::kGravity;  ///< g [m/s^2]
  double friction = defaults::kFriction;  ///< k [N s/m], viscous friction F = -k v_P (viscous scene)
  /// The body's rim (HYBRID.md, "fallen"): a circle of radius b centred on the axis at distance a
  /// from the tip. b = 0 is a needle: the top has fallen when its axis reaches the floor.
  double rim_radius = defaults::kRimRadius;      ///< b [m]
  double rim_distance = defaults::kRimDistance;  ///< a [m]
  /// Landings (HYBRID.md, "landing"): v_Pz+ = -e v_Pz-, plastic (e = 0) below restitution_speed.
  double restitution = defaults::kRestitution;               ///< e in [0, 1)
  double restitution_speed = defaults::kRestitutionSpeed;    ///< [m/s]

  /// A0 = A + m h^2: transverse moment about the tip (parallel-axis theorem).
  double inertia_about_tip() const { return inertia_transverse + mass * tip_distance * tip_distance; }
  /// e_Zz at which the rim touches the floor while the tip is on it: the lowest rim point's height
  /// above the tip, a e_Zz - b sqrt(1 - e_Zz^2), is zero at e_Zz = b / sqrt(a^2 + b^2); 0 for a needle.
  double fallen_vertical() const { return rim_radius > 0.0 ? rim_radius / std::hypot(rim_distance, rim_radius) : 0.0; }
};

/// Initial state in z-x-z Euler angles (Goldstein): q0 = Rz(heading) Rx(tilt) Rz(spin_angle).
/// Defaults: defaults.def (the toy top's start, tilted and spinning), as the key table's: a state
/// upright or at rest sets its tilt and spin.
struct InitialConditions {
  double tilt = defaults::kTilt;  ///< theta0 [rad], angle of the axis from the vertical
  double precession_rate = defaults::kPrecessionRate;  ///< phidot0 [rad/s]
  double nutation_rate = defaults::kNutationRate;  ///< thetadot0 [rad/s]
  double spin = defaults::kSpin;  ///< omega_Z [rad/s], body rate about the axis (constant of motion)
  double heading = defaults::kHeading;  ///< phi0 [rad]
  double spin_angle = defaults::kSpinAngle;  ///< psi0 [rad]
  double velocity_x = defaults::kVelocityX;  ///< G's horizontal velocity [m/s] (viscous scene only)
  double velocity_y = defaults::kVelocityY;  ///< G's horizontal velocity [m/s] (viscous scene only)
};

/// Thrown for a parameter that cannot describe a physical top. parameter() is the
/// configuration key (e.g. "inertia_axial"), what() says why.
class InvalidParameter : public std::invalid_argument {
 public:
  InvalidParameter(std::string parameter, const std::string& reason)
      : std::invalid_argument(parameter + ": " + reason), parameter_(std::move(parameter)) {}
  const std::string& parameter() const { return parameter_; }

 private:
  std::string parameter_;
};

/// Throws InvalidParameter unless: all finite and within +-1e30 (so that the model's products and
/// quotients of keys, m h^2 / A, m g h, m v^2, stay finite); m, A, C >= 1e-30 (they divide); h, g, k, a, b >= 0;
/// C <= 2A; b > 0 only with a > 0; e in [0, 1); restitution_speed >= 0.
void validate(const TopParameters& parameters);

/// Throws InvalidParameter unless all values are finite, the angles within +-1e30, G's speeds
/// within +-1e6 m/s (the rates' motion bound, 1e6 rad/s, on a 1 m lever: validate(SceneConfig)
/// bounds the rates) and the axis starts above the floor (|tilt| < pi/2).
void validate(const InitialConditions& initial);

}  // namespace spinning_top
