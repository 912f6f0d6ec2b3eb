#pragma once
/// @file neighbour_filter.hpp
/// @brief The vectorised in-range filter of the neighbour search (neighbour_filter.cpp).
#include "engine/core/simd.hpp"
#include "engine/core/types.hpp"

namespace sph {

class UniformGrid;

/// @brief Writes the sorted-order indices j of the candidates around xi (the 27 cells) with
/// |xi - x_j|^2 < r2 and j != self to dst, in slot order, and returns their count.
/// @warning dst must hold the candidates' count plus one vector (16 indices) of slack.
Index filter_candidates_simd(const UniformGrid& grid, const Vec3& xi, Index self, Real r2, Index* dst);

}  // namespace sph
