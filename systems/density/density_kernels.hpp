#pragma once
/// @file density_kernels.hpp
/// @brief Pure per-particle maths of the density phase (testable apart from the loops).
#include <algorithm>

#include "engine/core/types.hpp"

namespace sph {

/// @brief Tait equation of state, He et al. eq. 2 with gamma = 7:
/// p = B ((rho/rho0)^7 - 1), B = rho0 c_s^2 / 7. The density is clamped at rho0 from below,
/// so p >= 0: a free-surface particle lacks neighbours and would otherwise pull its
/// neighbours together (tensile instability); SPlisHSPlasH's WCSPH does the same.
inline Real tait_pressure(Real rho, Real rho0, Real b) {
    const Real x = std::max(rho, rho0) / rho0;
    const Real x2 = x * x, x4 = x2 * x2;
    return b * (x4 * x2 * x - Real(1));
}

}  // namespace sph
