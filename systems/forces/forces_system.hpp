#pragma once
/// @file forces_system.hpp
/// @brief He et al. eq. 4: symmetric pressure force, Monaghan artificial viscosity, gravity,
/// and the boundary forces of Akinci et al. 2012 (pressure eq. 10, viscosity eq. 11).
/// With individual stepping (He Alg. 2 lines 10-13) only active particles are evaluated,
/// and each also gets drho/dt (He eq. 5) and its raw step Delta t_i^raw (line 13).
/// With moving boundaries (`moving_boundary`) the boundary velocity v_b enters the boundary
/// viscosity and the boundary term of drho/dt as the relative velocity v_i - v_b.
/// With `corrected` (scene `fluid.pressure_gradient`) the pressure terms use the corrected
/// gradient (L_i + L_j)/2 grad W_ij against fluid and L_i grad W_ib against the boundary
/// (Bonet & Lok 1999; L from GradientCorrectionSystem); viscosity keeps grad W.
/// With `continuity` (scene `fluid.density: continuity`) drho/dt belongs to the density system,
/// so individual stepping does not write it here. With Physics::kinematic_viscosity > 0 the
/// laminar term of Morris et al. 1997 is added (forces_kernels.hpp laminar_coefficient).
#include "engine/data/scene.hpp"
#include "engine/graph/system.hpp"

namespace sph {

class ForcesSystem final : public System {
public:
    /// @param stepping the step rules of Delta t_i^raw (individual stepping only).
    explicit ForcesSystem(bool with_boundary, bool individual = false, bool moving_boundary = false,
                          bool corrected = false, SteppingParams stepping = {}, bool continuity = false,
                          bool extrapolated_walls = false)
        : m_with_boundary(with_boundary),
          m_individual(individual),
          m_moving_boundary(moving_boundary),
          m_corrected(corrected),
          m_continuity(continuity),
          m_extrapolated(with_boundary && extrapolated_walls),
          m_stepping(stepping) {}
    std::string name() const override { return "forces"; }
    Access access() const override;
    void register_components(World& w) override;
    void run(Context& ctx) override;

private:
    bool m_with_boundary, m_individual, m_moving_boundary, m_corrected, m_continuity;
    bool m_extrapolated;  ///< the walls' pressure from WallPressureSystem, else mirrored (p_b = p_i)
    SteppingParams m_stepping;
};

}  // namespace sph
