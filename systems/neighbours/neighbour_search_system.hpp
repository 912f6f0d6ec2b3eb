#pragma once
/// @file neighbour_search_system.hpp
/// @brief He et al. Alg. 1 line 3 / Alg. 2 line 4: find neighbours. The fluid grid is rebuilt
/// every step; fluid->fluid and fluid->boundary lists are built by two independent systems
/// (they run concurrently in the graph).
#include "engine/system.hpp"

namespace sph {

/// @brief Sorts the fluid particles into the uniform grid (cell size h).
class FluidGridSystem final : public System {
public:
    std::string name() const override { return "fluid_grid"; }
    Access access() const override;
    void run(World& w) override;
};

/// @brief Fluid->fluid neighbour lists (r < h, self excluded) of every fluid particle.
class FluidNeighbourSystem final : public System {
public:
    std::string name() const override { return "fluid_neighbours"; }
    Access access() const override;
    void run(World& w) override;
};

/// @brief Fluid->boundary neighbour lists (r < h) against the static boundary grid.
class BoundaryNeighbourSystem final : public System {
public:
    std::string name() const override { return "boundary_neighbours"; }
    Access access() const override;
    void run(World& w) override;
};

}  // namespace sph
