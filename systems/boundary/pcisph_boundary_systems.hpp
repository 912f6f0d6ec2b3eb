#pragma once
/// @file pcisph_boundary_systems.hpp
/// @brief Boundary handling of Ihmsen et al. 2010 sec. 3.2 and 3.4: boundary mass and the
/// constant boundary part of its density (set-up), the active boundary particles (those near
/// fluid) with their fluid neighbours, and direct forcing (eq. 9-12) on predicted or final
/// positions.
#include "engine/graph/system.hpp"
#include "engine/core/types.hpp"

namespace sph {

/// @brief Set-up: m_b = rho0 V_b (Akinci's volume, so that eq. 13 gives a fluid particle at
/// rest next to a wall rho0) and sum_b' m_b' W_bb'.
class BoundaryMassSystem final : public System {
public:
    std::string name() const override { return "boundary_mass"; }
    Access access() const override;
    void register_components(World& w) override;
    void run(Context& ctx) override;
};

/// @brief Sec. 3.4: only boundary particles near fluid are active. Inverts the fluid->boundary
/// lists into boundary->fluid rows over the active set (ascending, deterministic).
class BoundaryActiveSystem final : public System {
public:
    std::string name() const override { return "boundary_active"; }
    Access access() const override;
    void register_components(World& w) override;
    void run(Context& ctx) override;

private:
    std::vector<Index> m_count;
};

/// @brief Direct forcing, Ihmsen eq. 9-11 (position) and, on final positions, eq. 12
/// (velocity: v = eps [v]_t in the boundary's frame). `predicted`: acts on x* inside the loop
/// ("predict world collision"); otherwise on x(t + dt) and v(t + dt) after integration.
class DirectForcingSystem final : public System {
public:
    /// @param friction the scene's boundary.friction (eq. 12's tangential factor).
    DirectForcingSystem(bool predicted, bool moving, double friction = 1.0)
        : m_predicted(predicted), m_moving(moving), m_friction(friction) {}
    std::string name() const override { return m_predicted ? "predict_collision" : "world_collision"; }
    Access access() const override;
    void run(Context& ctx) override;

private:
    bool m_predicted, m_moving;
    double m_friction;
};

}  // namespace sph
