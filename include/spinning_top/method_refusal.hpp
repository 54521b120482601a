// A method that cannot start from a state says so with a MethodRefusal: the closed form refuses a
// few degenerate states (integrators/exact.hpp). To a front end it is the bad value of the key
// `integrator`, with advice on what to use instead; `auto` catches it and runs its fallback from
// the same state, keeping the bare reason to say why (auto_driver.hpp).
#pragma once

#include <string>

#include "spinning_top/parameters.hpp"

namespace spinning_top {

class MethodRefusal : public InvalidParameter {
 public:
  /// what(): "integrator: <method>: <reason>; use <advice>".
  MethodRefusal(const std::string& method, std::string reason, const std::string& advice)
      : InvalidParameter("integrator", method + ": " + reason + "; use " + advice), reason_(std::move(reason)) {}
  /// Why the method refused the state, without the key, the method's name or the advice.
  const std::string& reason() const { return reason_; }

 private:
  std::string reason_;
};

}  // namespace spinning_top
