#pragma once
/// @file components.hpp
/// @brief The particle attributes shared by the methods. A method registers only those it uses.
#include <cstdint>

#include "engine/core/component_store.hpp"

namespace sph::comp {

inline constexpr Component<Vec3> position{"position"};
inline constexpr Component<Vec3> velocity{"velocity"};
inline constexpr Component<Vec3> acceleration{"acceleration"};
inline constexpr Component<Real> density{"density"};
inline constexpr Component<Real> pressure{"pressure"};
/// Stable particle identity, kept through every permutation (diagnostics and output).
inline constexpr Component<std::uint32_t> id{"id"};

// Individual time stepping (He et al. Alg. 2).
inline constexpr Component<double> dt{"dt"};          ///< Delta t_i after spreading (line 16), s
inline constexpr Component<double> dt_raw{"dt_raw"};  ///< Delta t_i^raw (line 13), s
inline constexpr Component<std::int64_t> t_last{"t_last"};  ///< last evaluation, ticks (line 14)
inline constexpr Component<Real> drho_dt{"drho_dt"};        ///< He eq. 5
inline constexpr Component<std::uint8_t> active{"active"};  ///< 1 when evaluated this step
/// Set by a system that disturbs a particle between evaluations (a wall contact): the
/// particle is made active at the next step so its base state follows the change.
inline constexpr Component<std::uint8_t> wake{"wake"};
/// Base state at the last evaluation; every particle is integrated from it (lines 19-21).
inline constexpr Component<Vec3> position_last{"position_last"};
inline constexpr Component<Vec3> velocity_last{"velocity_last"};
inline constexpr Component<Real> density_last{"density_last"};

// Binned stepping (engine/core/timeline.hpp): the particle's bin (a step of 2^bin quanta) and
// the time its step ends, in quanta. `dt` holds the bin's step in seconds for the outputs.
inline constexpr Component<std::uint8_t> bin{"bin"};
inline constexpr Component<std::uint64_t> ti_end{"ti_end"};

// WCSPH with `fluid.pressure_gradient: corrected` (Bonet & Lok 1999): L_i, the inverse of the
// kernel-gradient moment matrix M_i = -sum_j V_j grad W_ij (x_ij)^T, eigenvalues clamped.
inline constexpr Component<Mat3> gradient_correction{"gradient_correction"};

// A method's own columns are declared beside its systems (systems/<method>/).

// Boundary particles (Akinci et al. 2012).
inline constexpr Component<Real> volume{"volume"};  ///< V_b = 1 / sum_k W_bk (Akinci eq. 4)
inline constexpr Component<Vec3> normal{"normal"};
/// Moving boundaries only (registered when the scene has one): the sampled position x0 of each
/// boundary particle, at displacement zero; the particle is at x0 + d(t). The boundary store
/// also gets a `velocity` column (the body's v(t); zero for static particles).
inline constexpr Component<Vec3> rest_position{"rest_position"};

}  // namespace sph::comp
