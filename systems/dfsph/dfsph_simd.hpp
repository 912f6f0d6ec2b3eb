#pragma once
/// @file dfsph_simd.hpp
/// @brief DFSPH's pair loops (Bender & Koschier 2017), vectorised across each particle's
/// neighbour list with the formulas of the scalar loops in dfsph_systems.cpp (reassociated
/// across vector lanes). Volumes: V = m / rho0 for fluid neighbours, the Akinci volume V_b for
/// boundary ones.
///
/// The factor pass stores V grad W_ij of every fluid pair (PairGradients) and the boundary's
/// sums per particle; the solver passes, 5-10 per step, then read them instead of evaluating
/// the kernel again, and never visit the boundary lists (the boundary's part of a pass is a
/// per-particle constant times k_i or v_i: the walls do not move within a step).
#include <cstddef>
#include <vector>

#include "engine/core/grid.hpp"
#include "engine/core/kernel.hpp"
#include "engine/core/types.hpp"

namespace sph {

/// @brief V grad W_ij of every entry of compact fluid neighbour lists, laid out like them: for
/// row i in block b = i / kBlock with n entries, entry e = start[i] + k has its x, y, z
/// components at blocks[b][e], [n + e], [2 n + e].
struct PairGradients {
    std::vector<std::vector<Real>> blocks;
    /// @brief Sizes the blocks to the lists (their slack included); keeps the allocations.
    void shape_like(const NeighbourLists& lists);
    std::size_t bytes() const;
};

struct DfsphPairArgs {
    const Real* x = nullptr;  ///< fluid positions, xyz per particle
    const Real* v = nullptr;  ///< fluid velocities, xyz per particle
    const NeighbourLists* fluid = nullptr;
    const PairGradients* grads = nullptr;  ///< the stored V grad W_ij (solver passes)
    const Real* xb = nullptr;  ///< boundary positions (nullptr: no boundary terms)
    const Real* volume_b = nullptr;
    const Real* vel_b = nullptr;  ///< boundary velocities (nullptr: static walls)
    const NeighbourLists* boundary = nullptr;
    const CubicSpline* kernel = nullptr;
    Real volume = 0;  ///< V = m / rho0 of a fluid particle
    /// Viscosity in the factor pass (NonpressureForcesSystem's Becker & Teschner 2007 eq. 10-11
    /// with rho_i = rho_j = rho0, and Akinci's boundary term with alpha_b, the walls' alpha):
    /// alpha or alpha_b > 0 and `acc` set.
    Real mass = 0, rest_density = 0, alpha = 0, alpha_b = 0, speed_of_sound = 0, h = 0;
    Real* acc = nullptr;  ///< written with the viscous acceleration (xyz per particle)
};

/// @brief For rows i in [begin, end): w_sum[i - begin] = sum_j W_ij, wb_sum = sum_b V_b W_ib,
/// grad_sum (xyz) = sum_j V grad W_ij, grad_sq = sum_j |V grad W_ij|^2, grad_b (xyz) =
/// sum_b V_b grad W_ib, flux_b = sum_b V_b v_b . grad W_ib (moving walls; 0 without vel_b);
/// `grads` (shaped like a.fluid) receives V grad W_ij of every fluid entry; with a.acc, the
/// viscous acceleration of row i is written to a.acc (the pass reads the pairs anyway).
void dfsph_factor_sums_simd(const DfsphPairArgs& a, std::size_t begin, std::size_t end, Real* w_sum, Real* wb_sum,
                            Real* grad_sum, Real* grad_sq, Real* grad_b, Real* flux_b, PairGradients& grads);

/// @brief div[i - begin] = sum_j (v_i - v_j) . V grad W_ij from the stored gradients (the fluid
/// part of the rate of relative compression; the caller adds the boundary's).
void dfsph_divergence_simd(const DfsphPairArgs& a, std::size_t begin, std::size_t end, Real* div);

/// @brief acc (xyz per row i - begin) = sum_j (k_i + k_j) V grad W_ij from the stored gradients
/// (the caller adds the boundary's k_i sum_b V_b grad W_ib).
void dfsph_pressure_simd(const DfsphPairArgs& a, const Real* kappa, std::size_t begin, std::size_t end, Real* acc);

}  // namespace sph
