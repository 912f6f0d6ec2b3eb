#pragma once
/// @file nonpressure_forces_system.hpp
/// @brief PCISPH's non-pressure forces per unit mass (Ihmsen et al. 2010 sec. 3.4: as in
/// Becker & Teschner 2007): artificial viscosity (BT07 eq. 10-11, also against the boundary) and
/// cohesion surface tension (BT07 eq. 13). Only in a recipe when the scene asks for either.
#include "engine/graph/system.hpp"

namespace sph {

class NonpressureForcesSystem final : public System {
public:
    /// @param surface_tension kappa of Becker & Teschner 2007 (the scene's fluid.surface_tension).
    NonpressureForcesSystem(bool boundary, bool moving, double surface_tension = 0)
        : m_boundary(boundary), m_moving(moving), m_surface_tension(surface_tension) {}
    std::string name() const override { return "nonpressure_forces"; }
    Access access() const override;
    void register_components(World& w) override;
    void run(Context& ctx) override;

private:
    bool m_boundary, m_moving;
    double m_surface_tension;
};

}  // namespace sph
