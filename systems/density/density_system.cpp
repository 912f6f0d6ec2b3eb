// He et al. eq. 1: rho_i = sum_j m_j W_ij (self included), plus Akinci et al. 2012 eq. 6:
// + sum_b psi_b W_ib with psi_b = rho0 V_b. He eq. 2: Tait pressure (density_kernels.hpp).
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
    return a;
}

void DensitySystem::register_components(World& w) {
    w.fluid.store.add(comp::density);
    w.fluid.store.add(comp::pressure);
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
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x.size(), 512), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            const Vec3 xi = x[i];
            Real sum = 0;
            for (Index j : w.fluid_neighbours.of(Index(i))) sum += kernel.w((xi - x[j]).norm());
            Real bsum = 0;
            if (has_boundary)
                for (Index b : w.boundary_neighbours.of(Index(i))) bsum += vb[b] * kernel.w((xi - xb[b]).norm());
            rho[i] = self + ph.mass * sum + ph.rest_density * bsum;
            p[i] = tait_pressure(rho[i], ph.rest_density, ph.tait_b);
        }
    });
}

}  // namespace sph
