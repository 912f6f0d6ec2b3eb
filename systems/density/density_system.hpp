#pragma once
/// @file density_system.hpp
/// @brief He et al. eq. 1 (summation density) plus the boundary contribution of Akinci et al.
/// 2012 eq. 6, then the Tait pressure (He eq. 2). With individual stepping (He Alg. 2
/// lines 5-9) only active particles are summed, and the sum is kept as their base density;
/// the interpolation of line 9 happens in the asynchronous integration.
/// With `continuity` (scene `fluid.density: continuity`) the density is integrated instead:
/// each evaluated row first advances its density over the time since it was last set,
///   rho_i(t) = rho_i(t_0) + (t - t_0) D_i,  D_i = drho_i/dt (He eq. 5) + delta-SPH diffusion
/// (density_kernels.hpp continuity_rate), with D_i taken at the current positions and at the
/// velocities that carried the particles there. That makes the density update use the same
/// velocity as the position update of the symplectic Euler step (rho moves with x): taking D
/// from the previous evaluation instead (the velocity before the kick) is an explicit Euler step
/// of the acoustic mode, which grows by (1 + (omega dt)^2)^(1/2) per step and blew a resting tank
/// up in 0.8 s. t_0 is the previous step (global, constant; a kept resource) or the particle's
/// last evaluation t_last (individual, binned; D_i is then also the slope of He Alg. 2 line 9
/// until its next evaluation). A row without a density yet (0: the first step, or a row an
/// emitter just added) starts from its summation density, at least rho0 (a free-surface
/// particle lacks neighbours; its deficit would stay in the integrated density).
#include <cstdint>
#include <vector>

#include "engine/graph/system.hpp"

namespace sph {

/// @brief The time up to which the integrated density of `global` and `constant` runs is set.
struct DensityClock {
    std::int64_t t_ticks = 0;
};
namespace res {
inline constexpr Resource<DensityClock> density_clock{"fluid.density_clock"};
}  // namespace res

class DensitySystem final : public System {
public:
    /// @param with_boundary add the boundary contribution (only when the scene has one).
    /// @param individual sum only the active set.
    /// @param continuity integrate the density (sum only rows that have none yet).
    /// @param moving_boundary the boundary has velocities (the boundary term of He eq. 5).
    explicit DensitySystem(bool with_boundary, bool individual = false, bool continuity = false,
                           bool moving_boundary = false)
        : m_with_boundary(with_boundary),
          m_individual(individual),
          m_continuity(continuity),
          m_moving_boundary(moving_boundary) {}
    std::string name() const override { return "density"; }
    Access access() const override;
    void register_components(World& w) override;
    void run(Context& ctx) override;

private:
    void run_continuity(Context& ctx);
    bool m_with_boundary, m_individual, m_continuity, m_moving_boundary;
    std::vector<Real> m_next;  ///< individual continuity: the active rows' new densities (scratch)
};

}  // namespace sph
