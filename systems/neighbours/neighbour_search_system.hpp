#pragma once
/// @file neighbour_search_system.hpp
/// @brief He et al. Alg. 1 line 3 / Alg. 2 line 4: find neighbours. The fluid grid is rebuilt
/// every step; fluid->fluid and fluid->boundary lists are built by two independent systems
/// (they run concurrently in the graph).
#include "engine/graph/system.hpp"

namespace sph {

/// @brief Sorts the fluid particles into the uniform grid (cell size h).
class FluidGridSystem final : public System {
public:
    std::string name() const override { return "fluid_grid"; }
    Access access() const override;
    void run(Context& ctx) override;
};

/// @brief Fluid->fluid neighbour lists (r < h, self excluded) of every fluid particle, or
/// with individual stepping of the active ones only (He Alg. 2 lines 3-4); inactive
/// particles keep their last lists.
class FluidNeighbourSystem final : public System {
public:
    explicit FluidNeighbourSystem(bool individual = false) : m_individual(individual) {}
    std::string name() const override { return "fluid_neighbours"; }
    Access access() const override;
    void run(Context& ctx) override;

private:
    bool m_individual;
};

/// @brief Fluid->boundary neighbour lists (r < h) against the boundary grid (built once for
/// static boundaries, every step by boundary_motion when a body moves), of every fluid
/// particle or of the active ones.
class BoundaryNeighbourSystem final : public System {
public:
    explicit BoundaryNeighbourSystem(bool individual = false) : m_individual(individual) {}
    std::string name() const override { return "boundary_neighbours"; }
    Access access() const override;
    void run(Context& ctx) override;

private:
    bool m_individual;
};

}  // namespace sph
