// Ihmsen et al. 2010 sec. 3.2, eq. 13: m_b = rho0 V_b (Akinci et al. 2012 eq. 4 volume) and the
// boundary part of a boundary particle's density, sum_b' m_b' W_bb', over the particle's own
// rigid object (the static boundaries, or one moving body; boundary_objects), as the volumes
// are: constant under the bodies' rigid motion, so computed once. (Over every boundary particle
// it would be the value at t = 0, kept as a body moves away from or towards a wall.)
#include "systems/pcisph/boundary_mass_system.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"
#include "systems/boundary/boundary_volume_system.hpp"
#include "systems/pcisph/pcisph_components.hpp"
#include "systems/pcisph/pcisph_kernels.hpp"
#include "systems/pcisph/pcisph_state.hpp"

namespace sph {

Access BoundaryMassSystem::access() const {
    return Access()
        .read(boundary(comp::position), boundary(comp::volume), res::boundary_grid, res::moving_bodies)
        .write(boundary(comp::mass), boundary(comp::self_density));
}

void BoundaryMassSystem::register_components(World& w) {
    w.boundary.store.add(comp::mass);
    w.boundary.store.add(comp::self_density);
}

void BoundaryMassSystem::run(Context& ctx) {
    const auto x = ctx.read(boundary(comp::position));
    const auto vol = ctx.read(boundary(comp::volume));
    auto m = ctx.write(boundary(comp::mass));
    auto self = ctx.write(boundary(comp::self_density));
    const Real rho0 = ctx.physics().rest_density;
    for (std::size_t b = 0; b < x.size(); ++b) m[b] = rho0 * vol[b];
    const CubicSpline& kernel = ctx.kernel();
    const Real h2 = kernel.support() * kernel.support();
    const UniformGrid& grid = ctx.read(res::boundary_grid);
    const std::vector<std::uint32_t> group = boundary_objects(x.size(), ctx.read(res::moving_bodies));
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x.size(), 1024), [&](const auto& r) {
        for (std::size_t b = r.begin(); b < r.end(); ++b) {
            Real sum = 0;
            grid.for_each_candidate(x[b], x, [&](Index k, const Vec3& xk) {
                if (!group.empty() && group[k] != group[b]) return;
                const Real d2 = (x[b] - xk).squaredNorm();
                if (d2 < h2) sum += m[k] * kernel.w(std::sqrt(d2));
            });
            self[b] = sum;
        }
    });
}

}  // namespace sph
