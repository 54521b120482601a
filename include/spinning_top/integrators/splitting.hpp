// Geometric integrator for the fixed-tip top: splitting of the Hamiltonian about the pivot
//   H = T + V,  T = (L_X^2 + L_Y^2) / (2 A0) + L_Z^2 / (2 C)  (free symmetric top),
//               V = m g h e_Zz                                  (gravity),
// where each part is integrated exactly (the scene's own flows, FixedTip::free_rotation and
// FixedTip::gravity_kick), composed into a symmetric scheme of order 4, 6 or 8.
// Both flows are Poisson maps of the heavy top's Lie-Poisson structure, so every composition
// is a Lie-Poisson integrator: it conserves omega_Z and the vertical angular momentum L_z
// exactly (each flow does) and, being symmetric, has a modified Hamiltonian that is
// conserved: the energy error stays bounded with no drift (Hairer, Lubich, Wanner, Geometric
// Numerical Integration, 2nd ed. 2006, sec. IX.8 and X). The splitting of the rigid body into
// its free motion and a potential kick is that of Dullweber, Leimkuhler, McLachlan,
// J. Chem. Phys. 107 (1997) 5840, and Touma & Wisdom, Astron. J. 107 (1994) 1189; with the
// symmetric top the free flow is exact in closed form.
#pragma once

#include <type_traits>

#include "spinning_top/scenes/fixed_tip.hpp"

namespace spinning_top {

// Splitting schemes: kick(b_0) rotate(a_0) kick(b_1) ... rotate(a_{s-1}) kick(b_s), symmetric
// (a and b palindromic), sum a = sum b = 1.

/// Blanes & Moan, "Practical symplectic partitioned Runge-Kutta and Runge-Kutta-Nystrom
/// methods", J. Comput. Appl. Math. 142 (2002) 313, method S6 (order 4, 6 stages): its
/// leading error coefficients are about 100 times smaller than Yoshida's triple jump's.
/// The cheap gravity kick takes the 7 outer coefficients a_i of the paper, the free rotation
/// the 6 inner b_i.
struct BlanesMoan4 {
  static constexpr int kOrder = 4;
  static constexpr const char* kName = "splitting4";
  static constexpr int kRotations = 6;
  static constexpr double kick[kRotations + 1] = {
      0.0792036964311957, 0.353172906049774, -0.0420650803577195,
      1.0 - 2.0 * (0.0792036964311957 + 0.353172906049774 - 0.0420650803577195),
      -0.0420650803577195, 0.353172906049774, 0.0792036964311957};
  static constexpr double rotate[kRotations] = {
      0.209515106613362, -0.143851773179818, 0.5 - (0.209515106613362 - 0.143851773179818),
      0.5 - (0.209515106613362 - 0.143851773179818), -0.143851773179818, 0.209515106613362};
};

// Symmetric compositions of Strang steps S(tau) = kick(tau/2) rotate(tau) kick(tau/2) with
// weights gamma_i; neighbouring half kicks merge, so s Strang steps cost s rotations.

/// Kahan & Li, "Composition constants for raising the orders of unconventional schemes for
/// ordinary differential equations", Math. Comp. 66 (1997) 1089: order 6 with 9 Strang
/// steps (s9odr6a; also Hairer, Lubich, Wanner, GNI, eq. V.3.11). Much smaller error than
/// Yoshida's 7-stage sixth-order method.
struct KahanLi6 {
  static constexpr int kOrder = 6;
  static constexpr const char* kName = "splitting6";
  static constexpr int kStrangSteps = 9;
  static constexpr double gamma[kStrangSteps] = {
      0.39216144400731413928, 0.33259913678935943860, -0.70624617255763935981,
      0.082213596293550800230, 0.79854399093482996340, 0.082213596293550800230,
      -0.70624617255763935981, 0.33259913678935943860, 0.39216144400731413928};
};

/// Kahan & Li (1997), order 8 with 15 Strang steps (s15odr8; GNI eq. V.3.14).
struct KahanLi8 {
  static constexpr int kOrder = 8;
  static constexpr const char* kName = "splitting8";
  static constexpr int kStrangSteps = 15;
  static constexpr double gamma[kStrangSteps] = {
      0.74167036435061295345,  -0.40910082580003159400, 0.19075471029623837995,
      -0.57386247111608226666, 0.29906418130365592384,  0.33462491824529818378,
      0.31529309239676659663,  -0.79688793935291635402, 0.31529309239676659663,
      0.33462491824529818378,  0.29906418130365592384,  -0.57386247111608226666,
      0.19075471029623837995,  -0.40910082580003159400, 0.74167036435061295345};
};

namespace detail {
template <class Scheme, class = void>
struct IsStrangComposition : std::false_type {};
template <class Scheme>
struct IsStrangComposition<Scheme, std::void_t<decltype(Scheme::kStrangSteps)>> : std::true_type {};
/// The free rotations of one step of the scheme.
template <class Scheme>
constexpr long rotations_per_step() {
  if constexpr (IsStrangComposition<Scheme>::value)
    return Scheme::kStrangSteps;
  else
    return Scheme::kRotations;
}
}  // namespace detail

/// One-step method for FixedStepDriver: step(model, y, dt). Only the fixed tip has this
/// exactly solvable split (for the frictionless top the kinetic energy depends on the
/// attitude through 1/2 m v_Gz^2; see doc/integrators.md).
template <class Model, class Scheme>
class Splitting;

template <class Scheme>
class Splitting<FixedTip, Scheme> {
 public:
  using State = FixedTip::State;
  static constexpr int kOrder = Scheme::kOrder;
  static constexpr const char* kName = Scheme::kName;
  /// Work units per step (work_budget.hpp): a free rotation with its gravity kick costs about 3
  /// evaluations of the fixed tip's derivative (its sines and cosines; measured by
  /// bench/budget_time.cpp).
  static constexpr long kWorkPerStep = 3 * detail::rotations_per_step<Scheme>();

  void step(const FixedTip& model, State& y, double dt) const {
    if constexpr (detail::IsStrangComposition<Scheme>::value) {
      double pending_kick = 0.5 * Scheme::gamma[0];
      for (int i = 0; i < Scheme::kStrangSteps; ++i) {
        model.gravity_kick(pending_kick * dt, y);
        model.free_rotation(Scheme::gamma[i] * dt, y);
        pending_kick = 0.5 * (Scheme::gamma[i] + (i + 1 < Scheme::kStrangSteps ? Scheme::gamma[i + 1] : 0.0));
      }
      model.gravity_kick(pending_kick * dt, y);
    } else {
      for (int i = 0; i < Scheme::kRotations; ++i) {
        model.gravity_kick(Scheme::kick[i] * dt, y);
        model.free_rotation(Scheme::rotate[i] * dt, y);
      }
      model.gravity_kick(Scheme::kick[Scheme::kRotations] * dt, y);
    }
  }
};

}  // namespace spinning_top
