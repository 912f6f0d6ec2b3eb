#pragma once
/// @file density_simd.hpp
/// @brief The vectorised kernel sums of the density phases (density_simd.cpp): for each row i,
/// sum_j W(|x_i - x_j|) over its fluid list and sum_b w_b W(|x_i - x_b|) over its boundary
/// list, the same terms as the scalar loops (reassociated across vector lanes). WCSPH's
/// summation density (He eq. 1, Akinci eq. 6) and PCISPH's predicted density (Ihmsen eq. 13)
/// are these two sums.
#include <cstddef>

#include "engine/core/grid.hpp"
#include "engine/core/kernel.hpp"
#include "engine/core/types.hpp"

namespace sph {

struct KernelSumArgs {
    const Real* x = nullptr;               ///< fluid positions, xyz per particle
    const NeighbourLists* fluid = nullptr;
    const Real* xb = nullptr;              ///< boundary positions, xyz (nullptr: no boundary sum)
    const Real* weight_b = nullptr;        ///< w_b per boundary particle
    const NeighbourLists* boundary = nullptr;
    const CubicSpline* kernel = nullptr;
};

/// @brief For k in [begin, end) and i = rows ? rows[k] : k: fluid_sum[k - begin] =
/// sum_j W(|x_i - x_j|) and, with a boundary, boundary_sum[k - begin] = sum_b w_b W(|x_i - x_b|).
void kernel_sums_simd(const KernelSumArgs& a, const Index* rows, std::size_t begin, std::size_t end, Real* fluid_sum,
                      Real* boundary_sum);

/// @brief The continuity density's drho_i/dt (density_kernels.hpp: He eq. 5 plus the delta-SPH
/// diffusion), the formula of DensitySystem's scalar `rate`, vectorised across the lists.
struct ContinuityRateArgs {
    const Real* x = nullptr;    ///< fluid positions, xyz per particle
    const Real* v = nullptr;    ///< fluid velocities, xyz per particle
    const Real* rho = nullptr;  ///< fluid densities (all > 0)
    const NeighbourLists* fluid = nullptr;
    const Real* xb = nullptr;        ///< boundary positions (nullptr: no boundary term)
    const Real* volume_b = nullptr;
    const Real* vel_b = nullptr;     ///< boundary velocities, xyz (nullptr: static walls)
    const NeighbourLists* boundary = nullptr;
    const CubicSpline* kernel = nullptr;
    Real mass = 0, rest_density = 0;
    Real diffusion = 0;        ///< delta h c_s (0: no diffusion term)
    Real eps_h2 = 0;           ///< 0.01 h^2
    Real g_h[3] = {0, 0, 0};   ///< (rho0 / c_s^2) g: rho^H_ij = g_h . x_ij
};

/// @brief out[k - begin] = drho_i/dt for k in [begin, end), i = rows ? rows[k] : k.
void continuity_rates_simd(const ContinuityRateArgs& a, const Index* rows, std::size_t begin, std::size_t end,
                           Real* out);

}  // namespace sph
