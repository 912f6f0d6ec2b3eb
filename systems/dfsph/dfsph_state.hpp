#pragma once
/// @file dfsph_state.hpp
/// @brief The particle columns and resources of divergence-free SPH (Bender & Koschier 2015,
/// 2017), written in volumes: V = m / rho0 for fluid particles, the Akinci et al. 2012 volume
/// V_b for boundary particles, densities relative to rho0.
#include <cstdint>

#include "engine/core/access.hpp"
#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "systems/dfsph/dfsph_simd.hpp"

namespace sph::comp {

/// 1 / (|sum_j V_j grad W_ij + sum_b V_b grad W_ib|^2 + sum_j |V_j grad W_ij|^2), m^2: Bender &
/// Koschier 2017 eq. 11's alpha_i / rho_i in volume form (0 when the particle has no neighbour).
inline constexpr Component<Real> dfsph_factor{"dfsph_factor"};
/// The stiffness k_i (m^2/s^2) of the current solver pass: the velocity update is
/// v_i -= dt (sum_j V_j (k_i + k_j) grad W_ij + sum_b V_b k_i grad W_ib) (eq. 13 and 17 with
/// kappa_i / rho_i = k_i / rho0).
inline constexpr Component<Real> dfsph_kappa{"dfsph_kappa"};
/// The stiffness each solver applied over the last step, scaled to be independent of dt
/// (density solver: sum k dt^2; divergence solver: sum k dt): the warm start of the next step
/// (Bender & Koschier 2017 sec. 4.3). Kept, so rollbacks and checkpoints restore it.
inline constexpr Component<Real> dfsph_kappa_density{"dfsph_kappa_density"};
inline constexpr Component<Real> dfsph_kappa_divergence{"dfsph_kappa_divergence"};
/// With boundaries: sum_b V_b grad W_ib (1/m), so that a pass's boundary terms are
/// k_i sum_b V_b grad W_ib and v_i . sum_b V_b grad W_ib without visiting the boundary lists.
inline constexpr Component<Vec3> dfsph_boundary_gradient{"dfsph_boundary_gradient"};
/// With moving boundaries: sum_b V_b v_b . grad W_ib (1/s), the walls' part of the divergence.
inline constexpr Component<Real> dfsph_boundary_flux{"dfsph_boundary_flux"};

}  // namespace sph::comp

namespace sph {

/// @brief Which of the two solvers a pass belongs to.
enum class DfsphSolver { Density, Divergence };

/// @brief The last pass of each solver: its average error (relative to rho0; the divergence
/// solver's is dt times the average rate) and the passes it took this step.
struct DfsphErrors {
    double density_error = 0, divergence_error = 0;
    double density_error_max = 0;  ///< max over particles of max(rho*/rho0 - 1, 0) at the last pass
    int density_iterations = 0, divergence_iterations = 0;
};

namespace res {
inline constexpr Resource<DfsphErrors> dfsph_errors{"dfsph.errors"};
/// V grad W_ij of every fluid pair of the step (vectorised passes only), filled by dfsph_factor.
inline constexpr Resource<PairGradients> dfsph_gradients{"dfsph.pair_gradients"};
}  // namespace res

namespace counter {
inline constexpr Counter divergence_iterations{"divergence_iterations"};  ///< DFSPH divergence-solver passes
}  // namespace counter

}  // namespace sph
