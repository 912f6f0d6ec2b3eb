#pragma once
/// @file neighbour_filter.hpp
/// @brief The vectorised in-range filter of the neighbour search (neighbour_filter.cpp).
#include "engine/core/simd.hpp"
#include "engine/core/types.hpp"

namespace sph {

class UniformGrid;
struct CandidateRanges;

/// @brief Writes the particle indices j of the candidates in `ranges` (the 27 cells around xi,
/// UniformGrid::candidate_ranges) with |xi - x_j|^2 < r2 and j != self to dst, in slot order,
/// and returns their count.
/// @warning dst must hold ranges.total plus one vector (16 indices) of slack.
Index filter_candidates_simd(const UniformGrid& grid, const CandidateRanges& ranges, const Vec3& xi, Index self, Real r2,
                             Index* dst);

}  // namespace sph
