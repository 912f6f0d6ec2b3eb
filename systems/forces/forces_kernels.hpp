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


/// @brief Laminar viscosity of Morris et al. 1997 (eq. 8), in the form of Lo & Shao 2002 used by
/// DualSPHysics: a_i += sum_j m_j c_ij v_ij with
/// c_ij = 4 nu (x_ij . grad W_ij) / ((rho_i + rho_j) (r^2 + 0.01 h^2)). This is Brookshaw's
/// Laplacian nu lap(v) (2 sum_j V_j v_ij x_ij . grad W_ij / r^2) with V_j = 2 m_j / (rho_i + rho_j).
/// Returns c_ij (per unit mass m_j); `xgrad` = x_ij . grad W_ij (negative), `nu4` = 4 nu.
inline Real laminar_coefficient(Real xgrad, Real r2, Real nu4, Real rho_i, Real rho_j, Real eps_h2) {
    return nu4 * xgrad / ((rho_i + rho_j) * (r2 + eps_h2));
}

}  // namespace sph
