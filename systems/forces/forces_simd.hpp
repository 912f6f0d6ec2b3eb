#pragma once
/// @file forces_simd.hpp
/// @brief The vectorised force loop (forces_simd.cpp): He et al. eq. 4 with Monaghan's
/// artificial viscosity, the Akinci et al. 2012 boundary terms and He eq. 5's drho/dt, for a
/// range of rows, with the formulas of ForcesSystem's scalar loop (the symmetric pressure
/// gradient, or the corrected one of Bonet & Lok 1999 when `L` is given).
#include <cstddef>

#include "engine/core/grid.hpp"
#include "engine/core/kernel.hpp"
#include "engine/core/types.hpp"

namespace sph {

struct ForcePairArgs {
    const Real* x = nullptr;    ///< fluid positions, xyz per particle
    const Real* v = nullptr;    ///< fluid velocities, xyz per particle
    const Real* rho = nullptr;
    const Real* p = nullptr;
    const NeighbourLists* fluid = nullptr;
    const Real* xb = nullptr;        ///< boundary positions (nullptr: no boundary terms)
    const Real* volume_b = nullptr;
    const Real* vel_b = nullptr;     ///< boundary velocities, xyz (nullptr: static walls)
    const Real* p_b = nullptr;       ///< extrapolated wall pressure and density (nullptr: mirrored, p_b = p_i)
    const Real* rho_b = nullptr;
    const NeighbourLists* boundary = nullptr;
    const CubicSpline* kernel = nullptr;
    Real mass = 0, alpha = 0, alpha_b = 0, speed_of_sound = 0, h = 0, rest_density = 0;
    Real gravity[3] = {0, 0, 0};
    Real* acc = nullptr;   ///< written: a_i (xyz per particle), gravity included
    Real* drho = nullptr;  ///< written when not null: drho_i/dt (He eq. 5)
    Real nu4 = 0;          ///< 4 nu of the laminar term (forces_kernels.hpp laminar_coefficient); 0: none
    bool alpha_b_laminar = false;  ///< the laminar term also acts against the boundary (no-slip walls)
    /// The gradient correction L_i, 9 per particle (Eigen's column-major Mat3), or nullptr for
    /// the symmetric gradient: the pressure term's grad W_ij becomes (L_i + L_j)/2 grad W_ij and
    /// grad W_ib becomes L_i grad W_ib (forces_system.cpp).
    const Real* L = nullptr;
};

/// @brief a_i (and drho_i/dt) of rows[k] (or of row k when rows is null), k in [begin, end).
void force_rows_simd(const ForcePairArgs& a, const Index* rows, std::size_t begin, std::size_t end);

/// @brief The moment matrices of the gradient correction (Bonet & Lok 1999;
/// gradient_correction_system.hpp): M_i = -sum_j V_j grad W_ij x_ij^T over fluid (V_j = m /
/// rho_j) and boundary (V_b) neighbours, the formula of GradientCorrectionSystem's scalar loop.
/// grad W_ij = s x_ij, so M_i = -sum_j V_j s x_ij x_ij^T is symmetric: six sums.
struct MomentPairArgs {
    const Real* x = nullptr;  ///< fluid positions, xyz per particle
    const Real* rho = nullptr;
    const NeighbourLists* fluid = nullptr;
    const Real* xb = nullptr;  ///< boundary positions (nullptr: no boundary term)
    const Real* volume_b = nullptr;
    const NeighbourLists* boundary = nullptr;
    const CubicSpline* kernel = nullptr;
    Real mass = 0;
    Mat3* moment = nullptr;  ///< written: M_i per particle
};

/// @brief M_i of rows[k] (or of row k when rows is null), k in [begin, end).
void moment_rows_simd(const MomentPairArgs& a, const Index* rows, std::size_t begin, std::size_t end);

/// @brief PCISPH's pressure acceleration (Ihmsen et al. 2010 eq. 6 with the boundary's
/// density and pressure, eq. 9-13), the formulas of PcisphPressureForceSystem's scalar loop.
struct PressurePairArgs {
    const Real* x = nullptr;       ///< fluid positions, xyz per particle
    const Real* p_term = nullptr;  ///< p_i / rho_i^2 per fluid particle
    const NeighbourLists* fluid = nullptr;
    const Real* xb = nullptr;  ///< boundary positions (nullptr: no boundary term)
    const Real* mass_b = nullptr;
    const Real* rho_b = nullptr;
    const Real* p_b = nullptr;
    const NeighbourLists* boundary = nullptr;
    const CubicSpline* kernel = nullptr;
    Real mass = 0;
    Real* acc = nullptr;  ///< written: the pressure acceleration, xyz per particle
};

/// @brief PCISPH's non-pressure accelerations (Becker & Teschner 2007 eq. 10-11 viscosity with
/// rho_i = rho_j = rho0, Akinci et al. 2012 against the boundary, eq. 13 cohesion), the
/// formulas of NonpressureForcesSystem's scalar loop.
struct NonpressurePairArgs {
    const Real* x = nullptr;  ///< fluid positions, xyz per particle
    const Real* v = nullptr;  ///< fluid velocities, xyz per particle
    const NeighbourLists* fluid = nullptr;
    const Real* xb = nullptr;  ///< boundary positions (nullptr: no boundary term)
    const Real* volume_b = nullptr;
    const Real* vel_b = nullptr;  ///< boundary velocities, xyz (nullptr: static walls)
    const NeighbourLists* boundary = nullptr;
    const CubicSpline* kernel = nullptr;
    Real mass = 0, alpha = 0, speed_of_sound = 0, h = 0, rest_density = 0, kappa = 0;
    Real alpha_b = 0;     ///< Monaghan alpha against boundary particles (fluid.boundary_viscosity)
    Real* acc = nullptr;  ///< written, xyz per particle
};

/// @brief The non-pressure acceleration of rows [begin, end).
void nonpressure_rows_simd(const NonpressurePairArgs& a, std::size_t begin, std::size_t end);

/// @brief The pressure acceleration of rows [begin, end).
void pressure_force_rows_simd(const PressurePairArgs& a, std::size_t begin, std::size_t end);

}  // namespace sph
