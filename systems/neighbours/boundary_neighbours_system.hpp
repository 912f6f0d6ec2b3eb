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
    /// @param keep_others the other particles keep their lists (individual); false: binned.
    explicit BoundaryNeighbourSystem(bool individual = false, bool keep_others = true)
        : m_individual(individual), m_keep_others(keep_others) {}
    std::string name() const override { return "boundary_neighbours"; }
    Access access() const override;
    void run(Context& ctx) override;

private:
    bool m_individual;
    bool m_keep_others;
};

}  // namespace sph
