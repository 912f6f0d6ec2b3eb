#pragma once
/// @file components.hpp
/// @brief The particle attributes the engine knows. A method registers only those it uses.
#include <cstdint>

#include "engine/component_store.hpp"

namespace sph::comp {

inline constexpr Component<Vec3> position{"position"};
inline constexpr Component<Vec3> velocity{"velocity"};
inline constexpr Component<Vec3> acceleration{"acceleration"};
inline constexpr Component<Real> density{"density"};
inline constexpr Component<Real> pressure{"pressure"};
/// Stable particle identity, kept through every permutation (diagnostics and output).
inline constexpr Component<std::uint32_t> id{"id"};

// Boundary particles (Akinci et al. 2012).
inline constexpr Component<Real> volume{"volume"};  ///< V_b = 1 / sum_k W_bk (Akinci eq. 4)
inline constexpr Component<Vec3> normal{"normal"};

}  // namespace sph::comp
