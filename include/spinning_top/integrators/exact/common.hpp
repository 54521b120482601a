// What the closed forms of the exact integrator (../exact.hpp) share: the complex type and the
// constants of their numerics.
#pragma once

#include <complex>
#include <cstdio>
#include <limits>
#include <string>

namespace spinning_top {
namespace exact_detail {

using Complex = std::complex<double>;
constexpr double kPi = 3.14159265358979323846;
constexpr double kEpsilon = std::numeric_limits<double>::epsilon();

/// A number in a refusal's message.
inline std::string format(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.3g", value);
  return buffer;
}

}  // namespace exact_detail
}  // namespace spinning_top
