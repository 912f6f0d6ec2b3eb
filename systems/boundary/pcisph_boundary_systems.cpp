// Ihmsen et al. 2010 sec. 3.2 (eq. 9-13) and sec. 3.4 (active boundary particles).
#include "systems/boundary/pcisph_boundary_systems.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "engine/components.hpp"
#include "engine/world.hpp"
#include "systems/pcisph/pcisph_kernels.hpp"

namespace sph {

Access BoundaryMassSystem::access() const {
    return {{res::boundary(comp::position.name), res::boundary(comp::volume.name), res::boundary_grid},
            {res::boundary(comp::mass.name), res::boundary(comp::self_density.name)}};
}

void BoundaryMassSystem::register_components(World& w) {
    w.boundary.store.add(comp::mass);
    w.boundary.store.add(comp::self_density);
}

void BoundaryMassSystem::run(World& w) {
    const auto x = w.boundary.store.get(comp::position);
    const auto vol = w.boundary.store.get(comp::volume);
    auto m = w.boundary.store.get(comp::mass);
    auto self = w.boundary.store.get(comp::self_density);
    const Real rho0 = w.physics.rest_density;
    for (std::size_t b = 0; b < x.size(); ++b) m[b] = rho0 * vol[b];
    const CubicSpline& kernel = w.kernel;
    const Real h2 = kernel.support() * kernel.support();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x.size(), 1024), [&](const auto& r) {
        for (std::size_t b = r.begin(); b < r.end(); ++b) {
            Real sum = 0;
            w.boundary_grid.for_each_candidate(x[b], [&](Index k, const Vec3& xk) {
                const Real d2 = (x[b] - xk).squaredNorm();
                if (d2 < h2) sum += m[k] * kernel.w(std::sqrt(d2));
            });
            self[b] = sum;
        }
    });
}

Access BoundaryActiveSystem::access() const { return {{res::boundary_neighbours}, {res::boundary_active}}; }

void BoundaryActiveSystem::run(World& w) {
    BoundaryActive& act = w.boundary_active;
    const std::size_t nb = w.boundary.size(), nf = w.fluid.size();
    m_count.assign(nb, 0);
    const NeighbourLists& lists = w.boundary_neighbours;
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
    w.step.boundary_active = act.set.size();
}

Access DirectForcingSystem::access() const {
    Access a{{res::boundary_neighbours, res::boundary(comp::position.name), res::boundary(comp::normal.name)}, {}};
    if (m_predicted) {
        a.reads.push_back(res::fluid(comp::predicted_position.name));
        a.writes.push_back(res::fluid(comp::predicted_position.name));
    } else {
        a.reads.insert(a.reads.end(), {res::fluid(comp::position.name), res::fluid(comp::velocity.name)});
        a.writes.insert(a.writes.end(), {res::fluid(comp::position.name), res::fluid(comp::velocity.name)});
        if (m_moving) a.reads.push_back(res::boundary(comp::velocity.name));
    }
    return a;
}

void DirectForcingSystem::run(World& w) {
    auto x = m_predicted ? w.fluid.store.get(comp::predicted_position) : w.fluid.store.get(comp::position);
    const std::span<Vec3> v = m_predicted ? std::span<Vec3>{} : w.fluid.store.get(comp::velocity);
    const auto xb = w.boundary.store.get(comp::position);
    const auto nb = w.boundary.store.get(comp::normal);
    const std::span<const Vec3> vb = (!m_predicted && m_moving && w.boundary.store.has(comp::velocity.name))
                                         ? std::span<const Vec3>(w.boundary.store.get(comp::velocity))
                                         : std::span<const Vec3>{};
    // r0 = h / 2, the rest distance and the boundary sampling (sec. 3.2).
    const Real r0 = Real(0.5) * w.physics.h;
    const Real friction = Real(w.scene.boundary.friction);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x.size(), 1024), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            DirectForcing df{r0};
            for (Index b : w.boundary_neighbours.of(Index(i)))
                df.add(x[i], xb[b], nb[b], vb.empty() ? Vec3::Zero() : vb[b]);
            if (!df.hit()) continue;
            x[i] = df.corrected(x[i]);                          // eq. 11
            if (!m_predicted) v[i] = df.velocity(v[i], friction);  // eq. 12
        }
    });
}

}  // namespace sph
