#pragma once
/// @file density_simd.hpp
/// @brief The vectorised density loop (density_simd.cpp): He et al. eq. 1 plus Akinci et al.
/// 2012 eq. 6 and the Tait pressure of eq. 2, for a range of rows, with the same formulas
/// as DensitySystem's scalar loop (the sums reassociated across vector lanes).
#include <cstddef>

#include "engine/core/grid.hpp"
#include "engine/core/kernel.hpp"
#include "engine/core/types.hpp"

namespace sph {

struct DensityPairArgs {
    const Real* x = nullptr;               ///< fluid positions, xyz per particle
    const NeighbourLists* fluid = nullptr;
    const Real* xb = nullptr;              ///< boundary positions (nullptr: no boundary term)
    const Real* volume_b = nullptr;
    const NeighbourLists* boundary = nullptr;
    const CubicSpline* kernel = nullptr;
    Real self = 0, mass = 0, rest_density = 0, tait_b = 0;
    Real* rho = nullptr;
    Real* pressure = nullptr;
    Real* rho_last = nullptr;              ///< also written when not null (individual stepping)
};

/// @brief Density and pressure of rows[k] (or of row k when rows is null), k in [begin, end).
void density_rows_simd(const DensityPairArgs& a, const Index* rows, std::size_t begin, std::size_t end);

}  // namespace sph
