// What the closed forms of the exact integrator (../exact.hpp) share: the complex type and the
// constants of their numerics, the motion they answer with, the extremes they report, and the
// start they are built from.
#pragma once

#include <complex>
#include <cstdio>
#include <limits>
#include <string>

#include "spinning_top/kinematics.hpp"

namespace spinning_top {
namespace exact_detail {

using Complex = std::complex<double>;
constexpr double kPi = 3.14159265358979323846;
constexpr double kEpsilon = std::numeric_limits<double>::epsilon();

/// The attitude as Cayley-Klein pair, q = (Re alpha, Re beta, Im beta, Im alpha), and the
/// transverse body rate Omega = omega_X + i omega_Y.
struct Motion {
  Complex alpha, beta, omega;
};

/// The extremes of the motion over [t0, t] (ExactSolution::range_until): the largest 1 - u
/// (u = e_Zz = cos tilt) and the least R / m. Each closed form finds them without sampling, so
/// that no peak between two samples is missed.
struct Range {
  double one_minus_u_max = 0.0;            ///< 1 - cos(largest tilt)
  double least_normal_force_per_mass = 0.0;  ///< [m/s^2]
};

/// What a closed form is built from: the top's constants as the quadrature writes them (exact/
/// quadrature.hpp, item 1: the scenes differ only in A' and alpha_D) and the start, its attitude
/// on the unit sphere.
struct Start {
  double t0 = 0.0;
  double transverse = 0.0;    ///< A' [kg m^2]: A0 about the tip (fixed tip), A about G (frictionless)
  double alpha_d = 0.0;       ///< m h^2 / A (frictionless), 0 (fixed tip)
  double kappa = 0.0;         ///< 2 m g h / A' [1/s^2]
  double gravity = 0.0, tip_distance = 0.0;
  double spin = 0.0;          ///< wZ [rad/s], a constant of motion
  double axial = 0.0;         ///< C [kg m^2]
  double fallen_vertical = 0.0;  ///< e_Zz where the rim reaches the floor (TopParameters::fallen_vertical)
  Quaternion q0 = Quaternion::Identity();
  double wx0 = 0.0, wy0 = 0.0;  ///< omega_X, omega_Y at t0 [rad/s]
};

/// A number in a refusal's message.
inline std::string format(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.3g", value);
  return buffer;
}

}  // namespace exact_detail
}  // namespace spinning_top
