#pragma once
/// @file fluid_neighbours_system.hpp
/// @brief He et al. Alg. 1 line 3 / Alg. 2 lines 3-4: fluid->fluid neighbour lists.
#include "engine/core/grid.hpp"
#include "engine/graph/system.hpp"

namespace sph {

class Context;

/// @brief The rows a neighbour system builds lists for: every row, or with per-particle
/// stepping the active set (`keep_others`: the other rows keep their lists, He's scheme).
QuerySubset active_query_subset(const Context& ctx, bool individual, bool keep_others);

/// @brief Fluid->fluid neighbour lists (r < h, self excluded) of every fluid particle, or
/// with individual stepping of the active ones only (He Alg. 2 lines 3-4); inactive
/// particles keep their last lists.
class FluidNeighbourSystem final : public System {
public:
    /// @param keep_others the other particles keep their lists (individual); false: binned.
    explicit FluidNeighbourSystem(bool individual = false, bool keep_others = true)
        : m_individual(individual), m_keep_others(keep_others) {}
    std::string name() const override { return "fluid_neighbours"; }
    Access access() const override;
    void run(Context& ctx) override;

private:
    bool m_individual;
    bool m_keep_others;
};

}  // namespace sph
