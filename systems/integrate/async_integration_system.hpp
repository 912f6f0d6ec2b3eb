#pragma once
/// @file async_integration_system.hpp
/// @brief Asynchronous integration, He et al. Alg. 2 lines 18-21: every fluid particle is
/// advanced to t_sim + Delta t_sim from its state at its last evaluation (the base state,
/// captured when it is active), never by accumulating increments. Line 9's interpolation
/// rho_i = rho_i(t_last) + (t - t_last) drho_i/dt and the Tait pressure are applied in the
/// same pass, so every particle carries density and pressure at the new time.
#include "engine/graph/system.hpp"

namespace sph {

class AsyncIntegrationSystem final : public System {
public:
    /// @param active_only binned stepping's lazy drift: the active rows' new base state only
    /// (x_last = x, v_last = v at t_sim); every row is brought to a later time from its base
    /// when a step reads it (DriftSystem, DriftRowsSystem, the collision net) or by
    /// World::synchronise.
    explicit AsyncIntegrationSystem(bool active_only = false) : m_active_only(active_only) {}
    std::string name() const override { return "async_integrate"; }
    Access access() const override;
    void register_components(World& w) override;
    void run(Context& ctx) override;

private:
    bool m_active_only;
};

}  // namespace sph
