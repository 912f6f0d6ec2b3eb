#pragma once
/// @file forces_kernels.hpp
/// @brief Pure pairwise maths of the force phase.
#include "engine/core/types.hpp"

namespace sph {

/// @brief Monaghan (1992) artificial viscosity Pi_ij for an approaching pair (v_ij . x_ij < 0),
/// zero otherwise: Pi_ij = -alpha c_s h (v_ij . x_ij) / (rho_bar (|x_ij|^2 + 0.01 h^2)), with
/// rho_bar = (rho_i + rho_j) / 2 and h the kernel support (Becker & Teschner 2007, eq. 11).
inline Real monaghan_pi(Real vx, Real r2, Real alpha, Real c_s, Real h, Real rho_i, Real rho_j) {
    if (vx >= Real(0)) return Real(0);
    const Real nu = Real(2) * alpha * h * c_s / (rho_i + rho_j);
    return -nu * vx / (r2 + Real(0.01) * h * h);
}

}  // namespace sph
