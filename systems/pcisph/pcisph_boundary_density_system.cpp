// Ihmsen et al. 2010 eq. 13 for boundary particles:
//   rho*_b = sum_b' m_b' W_bb' + 2 sum_j m_j W(x_b - x*_j).// A boundary is one particle layer thick, so a boundary particle sees fluid on one side only:
// the plain sum of eq. 13 stays near half of rho0 under fluid at rest and its pressure would
// never rise. We count the fluid term twice: mirrored across the boundary particle's tangent
// plane, each fluid neighbour j has an image at the same distance from x_b, which fills the
// empty half (the ghost-particle idea of sec. 2). Under fluid at rest on a flat wall rho*_b is
// then close to rho0 (test PcisphBoundary.RestDensityOnFlatWall), and p_b follows the
// compression of the fluid above it.
#include "systems/pcisph/pcisph_boundary_density_system.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"
#include "systems/pcisph/pcisph_components.hpp"
#include "systems/pcisph/pcisph_kernels.hpp"
#include "systems/pcisph/pcisph_state.hpp"

namespace sph {

Access PcisphBoundaryDensitySystem::access() const {
    return Access()
        .read(fluid(comp::predicted_position), res::boundary_active, boundary(comp::position), boundary(comp::self_density), res::pcisph_delta)
        .write(boundary(comp::density), boundary(comp::pressure));
}

void PcisphBoundaryDensitySystem::register_components(World& w) {
    w.boundary.store.add(comp::density);
    w.boundary.store.add(comp::pressure);
}

void PcisphBoundaryDensitySystem::run(Context& ctx) {
    const auto xs = ctx.read(fluid(comp::predicted_position));
    const auto xb = ctx.read(boundary(comp::position));
    const auto self = ctx.read(boundary(comp::self_density));
    auto rho = ctx.write(boundary(comp::density));
    auto p = ctx.write(boundary(comp::pressure));
    const BoundaryActive& act = ctx.read(res::boundary_active);
    const CubicSpline& kernel = ctx.kernel();
    const Real m = ctx.physics().mass, rho0 = ctx.physics().rest_density;
    const Real delta = Real(ctx.read(res::pcisph_delta).delta);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, act.set.size(), 512), [&](const auto& r) {
        for (std::size_t k = r.begin(); k < r.end(); ++k) {
            const Index b = act.set[k];
            Real sum = 0;
            for (Index e = act.start[k]; e < act.start[k + 1]; ++e) sum += kernel.w((xb[b] - xs[act.fluid[e]]).norm());
            const Real r_b = self[b] + Real(2) * m * sum;
            rho[b] = r_b;
            p[b] = pcisph_pressure_update(p[b], delta, r_b, rho0);
        }
    });
}

}  // namespace sph
