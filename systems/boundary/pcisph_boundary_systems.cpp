// Ihmsen et al. 2010 sec. 3.2 (eq. 9-13) and sec. 3.4 (active boundary particles).
#include "systems/boundary/pcisph_boundary_systems.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"
#include "systems/pcisph/pcisph_kernels.hpp"
#include "systems/pcisph/pcisph_state.hpp"

namespace sph {

Access BoundaryMassSystem::access() const {
    return Access()
        .read(boundary(comp::position), boundary(comp::volume), res::boundary_grid)
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
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x.size(), 1024), [&](const auto& r) {
        for (std::size_t b = r.begin(); b < r.end(); ++b) {
            Real sum = 0;
            grid.for_each_candidate(x[b], [&](Index k, const Vec3& xk) {
                const Real d2 = (x[b] - xk).squaredNorm();
                if (d2 < h2) sum += m[k] * kernel.w(std::sqrt(d2));
            });
            self[b] = sum;
        }
    });
}

Access BoundaryActiveSystem::access() const {
    return Access().read(res::boundary_neighbours).write(res::boundary_active, counter::boundary_active);
}

void BoundaryActiveSystem::register_components(World& w) {
    w.resources.add<BoundaryActive>(res::boundary_active.name, Lifetime::Scratch);
}

void BoundaryActiveSystem::run(Context& ctx) {
    BoundaryActive& act = ctx.write(res::boundary_active);
    const std::size_t nb = ctx.size(SetId::Boundary), nf = ctx.size(SetId::Fluid);
    m_count.assign(nb, 0);
    const NeighbourLists& lists = ctx.read(res::boundary_neighbours);
    for (std::size_t i = 0; i < nf; ++i)
        for (Index b : lists.of(Index(i))) ++m_count[b];
    act.set.clear();
    act.start.assign(1, 0);
    for (std::size_t b = 0; b < nb; ++b)
        if (m_count[b] > 0) {
            act.set.push_back(Index(b));
            act.start.push_back(act.start.back() + m_count[b]);
        }
    // m_count becomes each active particle's write cursor (its row start).
    for (std::size_t k = 0; k < act.set.size(); ++k) m_count[act.set[k]] = act.start[k];
    act.fluid.resize(act.start.back());
    for (std::size_t i = 0; i < nf; ++i)  // ascending i: rows come out sorted
        for (Index b : lists.of(Index(i))) act.fluid[m_count[b]++] = Index(i);
    ctx.write(counter::boundary_active) = act.set.size();
}

Access DirectForcingSystem::access() const {
    return Access()
        .read(res::boundary_neighbours, boundary(comp::position), boundary(comp::normal))
        .write_if(m_predicted, fluid(comp::predicted_position))
        .write_if(!m_predicted, fluid(comp::position), fluid(comp::velocity))
        .read_if(!m_predicted && m_moving, boundary(comp::velocity));
}

void DirectForcingSystem::run(Context& ctx) {
    auto x = m_predicted ? ctx.write(fluid(comp::predicted_position)) : ctx.write(fluid(comp::position));
    const std::span<Vec3> v = m_predicted ? std::span<Vec3>{} : ctx.write(fluid(comp::velocity));
    const auto xb = ctx.read(boundary(comp::position));
    const auto nb = ctx.read(boundary(comp::normal));
    const std::span<const Vec3> vb = (!m_predicted && m_moving && ctx.has(SetId::Boundary, comp::velocity.name))
                                         ? ctx.read(boundary(comp::velocity))
                                         : std::span<const Vec3>{};
    const NeighbourLists& lists = ctx.read(res::boundary_neighbours);
    // r0 = h / 2, the rest distance and the boundary sampling (sec. 3.2).
    const Real r0 = Real(0.5) * ctx.physics().h;
    const Real friction = Real(m_friction);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x.size(), 1024), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            DirectForcing df{r0};
            for (Index b : lists.of(Index(i)))
                df.add(x[i], xb[b], nb[b], vb.empty() ? Vec3::Zero() : vb[b]);
            if (!df.hit()) continue;
            x[i] = df.corrected(x[i]);                          // eq. 11
            if (!m_predicted) v[i] = df.velocity(v[i], friction);  // eq. 12
        }
    });
}

}  // namespace sph
