// Akinci et al. 2012 ("Versatile rigid-fluid coupling"), eq. 4: V_b = 1 / sum_k W(x_b - x_k),
// scaled by gamma = s^3 sum_plane W (boundary_volume_gamma): see the header.
#include "systems/boundary/boundary_volume_system.hpp"

#include <tbb/parallel_for.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"

namespace sph {

Real boundary_volume_gamma(const CubicSpline& kernel, Real spacing) {
    const int reach = static_cast<int>(std::ceil(kernel.support() / spacing)) + 1;
    double sum = 0;
    for (int j = -reach; j <= reach; ++j)
        for (int i = -reach; i <= reach; ++i) sum += kernel.w(Real(spacing * std::sqrt(double(i * i + j * j))));
    return Real(double(spacing) * spacing * spacing * sum);
}

std::vector<std::uint32_t> boundary_objects(std::size_t n, const std::vector<MovingBody>& bodies) {
    std::vector<std::uint32_t> group;
    if (bodies.empty()) return group;
    group.assign(n, 0);
    for (std::size_t k = 0; k < bodies.size(); ++k)
        for (std::size_t i = bodies[k].begin; i < bodies[k].end; ++i) group[i] = std::uint32_t(k + 1);
    return group;
}

Access BoundaryVolumeSystem::access() const {
    return Access()
        .read(boundary(comp::position), res::boundary_grid, res::moving_bodies)
        .write(boundary(comp::volume));
}

void BoundaryVolumeSystem::register_components(World& w) { w.boundary.store.add(comp::volume); }

void BoundaryVolumeSystem::run(Context& ctx) {
    const auto x = ctx.read(boundary(comp::position));
    auto vol = ctx.write(boundary(comp::volume));
    const CubicSpline& kernel = ctx.kernel();
    const Real h2 = kernel.support() * kernel.support();
    const Real gamma = boundary_volume_gamma(kernel, ctx.physics().spacing);
    // Moving bodies: Akinci eq. 4 sums over the boundary particles k of the particle's *own*
    // rigid object only: the static boundaries form one group, each moving body another. A
    // body's volumes then depend only on its own sampling, are invariant under its rigid
    // translation, and are computed once here rather than every step; the alternative (the sum
    // over every boundary particle, recomputed per step) would let a body passing a wall shrink
    // both its own and the wall's psi_b = rho0 V_b and so weaken both walls exactly where the
    // fluid between them is squeezed. Static scenes have one group (every particle), unchanged.
    const std::vector<std::uint32_t> group = boundary_objects(x.size(), ctx.read(res::moving_bodies));
    const UniformGrid& grid = ctx.read(res::boundary_grid);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x.size(), 1024), [&](const auto& r) {
        for (std::size_t b = r.begin(); b < r.end(); ++b) {
            Real sum = 0;
            grid.for_each_candidate(x[b], x, [&](Index k, const Vec3& xk) {
                if (!group.empty() && group[k] != group[b]) return;
                const Real d2 = (x[b] - xk).squaredNorm();
                if (d2 < h2) sum += kernel.w(std::sqrt(d2));
            });
            vol[b] = gamma / sum;  // sum >= W(0) > 0: b is its own neighbour
        }
    });
}

}  // namespace sph
