// He et al. eq. 4: a_i = -sum_j m_j (p_i/rho_i^2 + p_j/rho_j^2) grad W_ij + g,
// plus Monaghan 1992 artificial viscosity -sum_j m_j Pi_ij grad W_ij (forces_kernels.hpp).
// Boundary (Akinci et al. 2012 eq. 10 with pressure mirroring p_b = p_i, rho_b = rho_i):
// a_i -= sum_b psi_b (2 p_i / rho_i^2) grad W_ib, psi_b = rho0 V_b; viscosity against the wall
// uses the same Pi with rho_j = rho0 and the wall's velocity (zero for static walls).
#include "systems/forces/forces_system.hpp"

#include <tbb/parallel_for.h>

#include "engine/components.hpp"
#include "engine/world.hpp"
#include "systems/forces/forces_kernels.hpp"

namespace sph {

Access ForcesSystem::access() const {
    Access a{{res::fluid(comp::position.name), res::fluid(comp::velocity.name), res::fluid(comp::density.name),
              res::fluid(comp::pressure.name), res::fluid_neighbours},
             {res::fluid(comp::acceleration.name)}};
    if (m_with_boundary)
        a.reads.insert(a.reads.end(), {res::boundary_neighbours, res::boundary(comp::position.name),
                                       res::boundary(comp::volume.name)});
    return a;
}

void ForcesSystem::register_components(World& w) { w.fluid.store.add(comp::acceleration); }

void ForcesSystem::run(World& w) {
    const auto x = w.fluid.store.get(comp::position);
    const auto v = w.fluid.store.get(comp::velocity);
    const auto rho = w.fluid.store.get(comp::density);
    const auto p = w.fluid.store.get(comp::pressure);
    auto acc = w.fluid.store.get(comp::acceleration);
    const bool has_boundary = m_with_boundary && w.boundary.size() > 0;
    const auto xb = w.boundary.store.get(comp::position);
    const std::span<const Real> vb = has_boundary ? w.boundary.store.get(comp::volume) : std::span<const Real>{};
    const CubicSpline& kernel = w.kernel;
    const Physics& ph = w.physics;
    const Real m = ph.mass, alpha = ph.viscosity, c = ph.speed_of_sound, h = ph.h, rho0 = ph.rest_density;
    const Vec3 g = ph.gravity;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x.size(), 256), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            const Vec3 xi = x[i], vi = v[i];
            const Real rhoi = rho[i];
            const Real pi = p[i] / (rhoi * rhoi);
            Vec3 a = Vec3::Zero();
            for (Index j : w.fluid_neighbours.of(Index(i))) {
                const Vec3 xij = xi - x[j];
                const Real r2 = xij.squaredNorm();
                const Vec3 grad = kernel.grad(xij, std::sqrt(r2));
                const Real visc = alpha > 0 ? monaghan_pi((vi - v[j]).dot(xij), r2, alpha, c, h, rhoi, rho[j]) : Real(0);
                a -= (m * (pi + p[j] / (rho[j] * rho[j]) + visc)) * grad;
            }
            if (has_boundary) {
                for (Index b : w.boundary_neighbours.of(Index(i))) {
                    const Vec3 xib = xi - xb[b];
                    const Real r2 = xib.squaredNorm();
                    const Vec3 grad = kernel.grad(xib, std::sqrt(r2));
                    const Real visc = alpha > 0 ? monaghan_pi(vi.dot(xib), r2, alpha, c, h, rhoi, rho0) : Real(0);
                    a -= (rho0 * vb[b] * (Real(2) * pi + visc)) * grad;
                }
            }
            acc[i] = a + g;
        }
    });
}

}  // namespace sph
