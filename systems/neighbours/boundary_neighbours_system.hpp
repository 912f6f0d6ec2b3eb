#pragma once
/// @file boundary_neighbours_system.hpp
/// @brief Fluid->boundary neighbour lists (independent of the fluid lists: the two run concurrently).
#include "engine/graph/system.hpp"

namespace sph {

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
