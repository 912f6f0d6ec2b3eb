// Akinci et al. 2012 ("Versatile rigid-fluid coupling"), eq. 4: V_b = 1 / sum_k W(x_b - x_k).
#include "systems/boundary/boundary_volume_system.hpp"

#include <tbb/parallel_for.h>

#include "engine/components.hpp"
#include "engine/world.hpp"

namespace sph {

Access BoundaryVolumeSystem::access() const {
    return {{res::boundary(comp::position.name), res::boundary_grid}, {res::boundary(comp::volume.name)}};
}

void BoundaryVolumeSystem::register_components(World& w) { w.boundary.store.add(comp::volume); }

void BoundaryVolumeSystem::run(World& w) {
    const auto x = w.boundary.store.get(comp::position);
    auto vol = w.boundary.store.get(comp::volume);
    const CubicSpline& kernel = w.kernel;
    const Real h2 = kernel.support() * kernel.support();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x.size(), 1024), [&](const auto& r) {
        for (std::size_t b = r.begin(); b < r.end(); ++b) {
            Real sum = 0;
            w.boundary_grid.for_each_candidate(x[b], [&](Index, const Vec3& xk) {
                const Real d2 = (x[b] - xk).squaredNorm();
                if (d2 < h2) sum += kernel.w(std::sqrt(d2));
            });
            vol[b] = Real(1) / sum;  // sum >= W(0) > 0: b is its own neighbour
        }
    });
}

}  // namespace sph
