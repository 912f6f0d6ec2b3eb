#pragma once
/// @file global_dt_system.hpp
/// @brief Globally adaptive step, He et al. eq. 6-8:
/// dt = min(lambda_v h / v_max, lambda_f sqrt(h / a_max)), optionally also the acoustic
/// condition dt <= lambda_c h / (c_s + v_max), and never above dt_max.
#include "engine/core/types.hpp"
#include "engine/data/scene.hpp"
#include "engine/graph/system.hpp"

namespace sph {

/// @brief The step of He eq. 6-8 (+ acoustic) for given maxima; infinity-safe for v = a = 0.
/// With a laminar viscosity nu > 0 (fluid.kinematic_viscosity) also the viscous diffusion limit
/// of Morris et al. 1997 (eq. 12), dt <= 0.125 h_s^2 / nu with h_s = h / 2 the smoothing length.
double global_time_step(const SteppingParams& p, double h, double c_s, double v_max, double a_max, double nu = 0);

class GlobalDtSystem final : public System {
public:
    explicit GlobalDtSystem(const SteppingParams& stepping) : m_stepping(stepping) {}
    std::string name() const override { return "global_dt"; }
    Access access() const override;
    void run(Context& ctx) override;

private:
    SteppingParams m_stepping;
};


}  // namespace sph
