// He et al. eq. 1: rho_i = sum_j m_j W_ij (self included), plus Akinci et al. 2012 eq. 6:
// + sum_b psi_b W_ib with psi_b = rho0 V_b. He eq. 2: Tait pressure (density_kernels.hpp).
// Individual stepping, He Alg. 2 lines 5-9: summation for active particles only; inactive
// particles carry rho_i(t_last) + (t - t_last) drho_i/dt from the asynchronous integration.
#include "systems/density/density_system.hpp"

#include <tbb/parallel_for.h>

#include "engine/components.hpp"
#include "engine/world.hpp"
#include "systems/density/density_kernels.hpp"

namespace sph {

Access DensitySystem::access() const {
    Access a{{res::fluid(comp::position.name), res::fluid_neighbours},
             {res::fluid(comp::density.name), res::fluid(comp::pressure.name)}};
    if (m_with_boundary)
        a.reads.insert(a.reads.end(), {res::boundary_neighbours, res::boundary(comp::position.name),
                                       res::boundary(comp::volume.name)});
    if (m_individual) {
        a.reads.push_back(res::active_set);
        a.writes.push_back(res::fluid(comp::density_last.name));
    }
    return a;
}

void DensitySystem::register_components(World& w) {
    w.fluid.store.add(comp::density);
    w.fluid.store.add(comp::pressure);
    if (m_individual) w.fluid.store.add(comp::density_last);
}

void DensitySystem::run(World& w) {
    const auto x = w.fluid.store.get(comp::position);
    auto rho = w.fluid.store.get(comp::density);
    auto p = w.fluid.store.get(comp::pressure);
    const bool has_boundary = m_with_boundary && w.boundary.size() > 0;
    const auto xb = w.boundary.store.get(comp::position);
    const std::span<const Real> vb = has_boundary ? w.boundary.store.get(comp::volume) : std::span<const Real>{};
    const CubicSpline& kernel = w.kernel;
    const Physics& ph = w.physics;
    const Real self = ph.mass * kernel.w(0);
    auto summation = [&](Index i) {
        const Vec3 xi = x[i];
        Real sum = 0;
        for (Index j : w.fluid_neighbours.of(i)) sum += kernel.w((xi - x[j]).norm());
        Real bsum = 0;
        if (has_boundary)
            for (Index b : w.boundary_neighbours.of(i)) bsum += vb[b] * kernel.w((xi - xb[b]).norm());
        rho[i] = self + ph.mass * sum + ph.rest_density * bsum;
        p[i] = tait_pressure(rho[i], ph.rest_density, ph.tait_b);
    };
    if (!m_individual) {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x.size(), 512), [&](const auto& r) {
            for (std::size_t i = r.begin(); i < r.end(); ++i) summation(Index(i));
        });
        return;
    }
    // Active particles only (He Alg. 2 lines 6-7); the summed density is also the base of
    // the interpolation rho_i(t) = rho_i(t_last) + (t - t_last) drho_i/dt (line 9), which the
    // asynchronous integration applies to every particle at the end of each step.
    const auto& active = w.active_set;
    auto rho_last = w.fluid.store.get(comp::density_last);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, active.size(), 256), [&](const auto& r) {
        for (std::size_t k = r.begin(); k < r.end(); ++k) {
            summation(active[k]);
            rho_last[active[k]] = rho[active[k]];
        }
    });
}

}  // namespace sph
