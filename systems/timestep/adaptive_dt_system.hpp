#pragma once
/// @file adaptive_dt_system.hpp
/// @brief Ihmsen et al. 2010 sec. 3.3 at the end of a step: shock detection (eq. 25-27) with a
/// rollback request and the step of eq. 24, else the +-0.2 % rule of eq. 16-23 for the next
/// step. Tracks v^max and F^max (eq. 14-15) over the kept steps.
#include "engine/data/scene.hpp"
#include "engine/graph/system.hpp"
#include "systems/timestep/adaptive_controller.hpp"

namespace sph {

/// @brief The controller's parameters from the scene (eta, eta_max, delta_shock, dt_max); h is
/// left 0 (the systems take it from the world's physics when they run).
AdaptiveParams adaptive_params(const Scene& scene);

class AdaptiveDtSystem final : public System {
public:
    explicit AdaptiveDtSystem(AdaptiveParams params) : m_params(params) {}
    std::string name() const override { return "adaptive_dt"; }
    Access access() const override;
    /// @brief Registers the controller it writes (also registered by pcisph_dt, which reads it).
    void register_components(World& w) override;
    void run(Context& ctx) override;

private:
    AdaptiveParams m_params;
};

}  // namespace sph
