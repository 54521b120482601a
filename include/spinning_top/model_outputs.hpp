// What every scene model reports about one state, besides its derivative.
#pragma once

#include "spinning_top/kinematics.hpp"

namespace spinning_top {

/// Quantities derived from a state (world frame, SI units). Scenes that do not have a
/// quantity report its neutral value (no friction: zero force, zero dissipated energy).
struct ModelOutputs {
  double normal_force = 0.0;             ///< R [N], vertical force of the floor on the tip
  Vector3 contact_force = Vector3::Zero();  ///< horizontal floor force on the tip [N]: the pivot's
                                           ///< reaction (fixed tip) or friction (viscous)
  Vector3 center_of_mass = Vector3::Zero();           ///< G [m]
  Vector3 center_of_mass_velocity = Vector3::Zero();  ///< dG/dt [m/s]
  Vector3 contact_point = Vector3::Zero();            ///< tip P on the floor [m], z = 0
  double energy = 0.0;                   ///< E = 1/2 m |v_G|^2 + 1/2 (A w_perp^2 + C w_Z^2) + m g z_G [J]
  double vertical_angular_momentum = 0.0;  ///< L_z [kg m^2/s] (conserved in fixed tip, frictionless)
  double dissipated_energy = 0.0;        ///< work done against friction since t = 0 [J] (viscous)
};

}  // namespace spinning_top
