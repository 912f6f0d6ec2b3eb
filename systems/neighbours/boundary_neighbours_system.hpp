#pragma once
/// @file boundary_neighbours_system.hpp
/// @brief Fluid->boundary neighbour lists (independent of the fluid lists: the two run concurrently).
#include <vector>

#include "engine/core/types.hpp"
#include "engine/graph/system.hpp"

namespace sph {

/// @brief Fluid->boundary neighbour lists (r < h) against the boundary grid (built once for
/// static boundaries, every step by boundary_motion when a body moves), of every fluid
/// particle or of the active ones.
class BoundaryNeighbourSystem final : public System {
public:
    /// @param keep_others the other particles keep their lists (individual); false: binned.
    /// @param from_base binned with lazy positions (drift_system.hpp): the active rows' positions
    /// are computed from their base state (the expressions the drift writes, so the same bits)
    /// instead of read, so that this search does not wait for the fluid grid's placement of
    /// the rows and overlaps its build, as it does when the positions are drifted first.
    explicit BoundaryNeighbourSystem(bool individual = false, bool keep_others = true, bool from_base = false)
        : m_individual(individual), m_keep_others(keep_others), m_from_base(from_base) {}
    std::string name() const override { return "boundary_neighbours"; }
    Access access() const override;
    void run(Context& ctx) override;

private:
    bool m_individual;
    bool m_keep_others;
    bool m_from_base;
    std::vector<Vec3> m_query;  ///< from_base: the active rows' positions (other rows unread)
};

}  // namespace sph
