#pragma once
/// @file boundary_motion_system.hpp
/// @brief Kinematic rigid boundaries (Akinci et al. 2012 sec. 3: boundary particles are moved
/// with their rigid body and carry its velocity). At the start of each step every moving
/// body's particles are placed at x0 + d(t) with velocity v(t) (engine/motion.hpp, t = the
/// step's start time), its bounds and speed bound are updated for the wake rule of individual
/// stepping, and the boundary grid is rebuilt when a body's particle has crossed into another
/// cell since its last build (otherwise a build would give the same grid). Boundary particles
/// never integrate.
///
/// Cost per step: O(moving-body particles) for the positions and the cell test, plus, on the
/// steps where a particle changed cell, the grid's counting sort over *all* boundary particles
/// and its cells, O(N_b + cells) (UniformGrid::build). Only in the recipe when the scene has a
/// moving boundary.
#include <vector>

#include "engine/data/scene.hpp"
#include "engine/graph/system.hpp"

namespace sph {

class BoundaryMotionSystem final : public System {
public:
    /// @param boundaries the scene's boundaries (a moving body's motion is its boundary's).
    explicit BoundaryMotionSystem(std::vector<BoundaryDesc> boundaries) : m_boundaries(std::move(boundaries)) {}
    std::string name() const override { return "boundary_motion"; }
    Access access() const override;
    void register_components(World& w) override;
    void run(Context& ctx) override;

private:
    std::vector<BoundaryDesc> m_boundaries;
};

}  // namespace sph
