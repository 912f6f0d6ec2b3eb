#pragma once
/// @file wall_pressure_system.hpp
/// @brief The pressure and density of the boundary particles that fluid reads this step, for
/// WCSPH with `fluid.wall_pressure: extrapolated` (the default with the continuity density):
///
///   p_b   = max(0, sum_f (p_f + rho_f g . (x_b - x_f)) W_bf / sum_f W_bf)     (Adami, Hu & Adams 2012, eq. 27)
///   rho_b = rho0 (p_b / B + 1)^(1/7)                                          (He eq. 2 inverted)
///
/// over the fluid particles f within the support of b (p_b = 0, rho_b = rho0 with none). The force
/// system then uses a_i -= sum_b psi_b (p_i / rho_i^2 + p_b / rho_b^2) grad W_ib.
///
/// Why: with pressure mirroring (p_b = p_i, the force 2 p_i / rho_i^2 psi_b grad W_ib) the wall
/// force is not the gradient of any energy: a particle's own pressure, which its other neighbours
/// set, doubles the wall's push. With the continuity density and no artificial viscosity a resting
/// tank gains energy without bound (docs/results/validation.md, "Wall pressure"). The
/// extrapolated p_b is a property of the fluid around b, like a mirrored ghost particle's, and
/// keeps the hydrostatic wall pressure (a resting column needs p_b = p_f + rho g d at the wall).
///
/// Rows: the boundary particles in the boundary lists of the rows evaluated this step. In
/// `global`/`constant` every fluid row is evaluated and its list is current, so the sums are
/// gathered from those lists (one pass over the fluid-boundary pairs); in `individual`/`binned`
/// only the active rows' lists are, so each boundary row they reach is summed over the fluid grid,
/// which holds every fluid row at this step's time.
/// A moving body's acceleration (the a_b of Adami eq. 27) is not included: p_b is the fluid's
/// hydrostatic extrapolation in the body's frame at rest.
#include <tbb/enumerable_thread_specific.h>

#include <cstdint>
#include <vector>

#include "engine/graph/system.hpp"

namespace sph {

class WallPressureSystem final : public System {
public:
    explicit WallPressureSystem(bool individual) : m_individual(individual) {}
    std::string name() const override { return "wall_pressure"; }
    Access access() const override;
    void register_components(World& w) override;
    void run(Context& ctx) override;

private:
    bool m_individual;
    std::vector<std::uint8_t> m_mark;  ///< per boundary row: listed this step (reset after use)
    std::vector<std::int64_t> m_num, m_den;  ///< `global`/`constant`: fixed-point sums (reset after use)
    tbb::enumerable_thread_specific<std::vector<Index>> m_found;  ///< the rows each worker claimed
    std::vector<Index> m_rows;         ///< per-particle modes: the rows listed this step, ascending
};

}  // namespace sph
