#pragma once
/// @file pcisph_components.hpp
/// @brief The particle columns of PCISPH (Solenthaler & Pajarola 2009; Ihmsen et al. 2010 Alg. 2).
#include "engine/data/components.hpp"

namespace sph::comp {

inline constexpr Component<Vec3> predicted_position{"predicted_position"};  ///< x*(t + dt)
inline constexpr Component<Vec3> pressure_acceleration{"pressure_acceleration"};  ///< F^p / m, eq. 6
/// p_i / rho*_i^2, the per-particle factor of eq. 6, written with p by the density pass so that
/// the (vectorised) pressure-force pass gathers one value per neighbour instead of two.
inline constexpr Component<Real> pressure_term{"pressure_term"};
/// Viscosity and surface tension per unit mass (only when the scene asks for them).
inline constexpr Component<Vec3> nonpressure_acceleration{"nonpressure_acceleration"};
/// Boundary: m_b = rho0 V_b (eq. 13 with Akinci's volume) and the boundary part of its own
/// density, sum_b' m_b' W_bb' over its own rigid object (constant: BoundaryMassSystem).
inline constexpr Component<Real> mass{"mass"};
inline constexpr Component<Real> self_density{"self_density"};

}  // namespace sph::comp
