// What the benchmark programs share: CPU clocks, CSV quoting and number formatting, and Boost.Odeint
// included without GCC 12's false warnings. Header-only; bench/ only.
#pragma once

#include <time.h>

#include <cstdio>
#include <string>

// GCC 12 flags odeint's copy of a stepper's scratch state (rkf78's m_x_tmp, overwritten before
// use) as uninitialized, depending on inlining: a false positive inside Boost.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <boost/numeric/odeint.hpp>
#pragma GCC diagnostic pop

namespace spinning_top {
namespace bench {

/// CPU time of the process [s] (what one run of a method costs, whatever else the machine runs).
inline double cpu_seconds() {
  timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

/// CPU time of the calling thread [s] (short intervals: re-initialisations, single requests).
inline double thread_cpu_seconds() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

/// A CSV field, quoted (RFC 4180) where it holds a comma, a quote or a newline (the integrators'
/// descriptions do).
inline std::string csv_field(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string quoted = "\"";
  for (const char ch : text) {
    if (ch == '"') quoted += '"';
    quoted += ch;
  }
  return quoted + "\"";
}

/// One number through a printf format, e.g. formatted("%.3g", x).
inline std::string formatted(const char* format, double value) {
  char text[64];
  std::snprintf(text, sizeof text, format, value);
  return text;
}

}  // namespace bench
}  // namespace spinning_top
