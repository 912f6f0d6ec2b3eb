#pragma once
/// @file neighbour_filter.hpp
/// @brief The vectorised in-range filter of the neighbour search (neighbour_filter.cpp).
#include "engine/core/simd.hpp"
#include "engine/core/types.hpp"

namespace sph {

struct CandidateCache;
struct CandidateRanges;
class UniformGrid;

/// @brief Writes the particle indices j of the cached candidates (the 27 cells around xi, in
/// the grid's slot order) with |xi - x_j|^2 < r2 and j != self to dst, in that order, and
/// returns their count.
/// @warning dst must hold cache.count plus one vector (16 indices) of slack.
Index filter_candidates_simd(const CandidateCache& cache, const Vec3& xi, Index self, Real r2, Index* dst);

/// @brief The same filter read straight from the grid's slot-ordered coordinates (a grid built
/// with keep_coordinates), range by range, the last vector of each range masked: the same
/// lists, in the same order, as filtering a CandidateCache filled from these ranges.
/// @warning dst must hold ranges.total plus one vector (16 indices) of slack.
Index filter_ranges_simd(const UniformGrid& grid, const CandidateRanges& ranges, const Vec3& xi, Index self, Real r2,
                         Index* dst);

}  // namespace sph
