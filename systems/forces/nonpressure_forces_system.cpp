// Becker & Teschner 2007 (cited by Ihmsen et al. 2010 sec. 3.4):
//  viscosity, eq. 10-11: a_i -= sum_j m_j Pi_ij grad W_ij, Pi_ij = -nu (v_ij . x_ij) /
//    (|x_ij|^2 + 0.01 h^2) for approaching pairs, nu = 2 alpha h c_s / (rho_i + rho_j); with
//    PCISPH rho_i = rho_j = rho0 to within eta, so rho0 is used. Against the boundary the same
//    term with psi_b = rho0 V_b and the relative velocity v_i - v_b (Akinci et al. 2012).
//  surface tension, eq. 13 (cohesion): a_i -= kappa sum_j (m_j / m_i) x_ij W_ij.
#include "systems/forces/nonpressure_forces_system.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "engine/components.hpp"
#include "engine/world.hpp"
#include "systems/forces/forces_kernels.hpp"

namespace sph {

Access NonpressureForcesSystem::access() const {
    Access a{{res::fluid(comp::position.name), res::fluid(comp::velocity.name), res::fluid_neighbours},
             {res::fluid(comp::nonpressure_acceleration.name)}};
    if (m_boundary)
        a.reads.insert(a.reads.end(),
                       {res::boundary_neighbours, res::boundary(comp::position.name), res::boundary(comp::volume.name)});
    if (m_boundary && m_moving) a.reads.push_back(res::boundary(comp::velocity.name));
    return a;
}

void NonpressureForcesSystem::register_components(World& w) { w.fluid.store.add(comp::nonpressure_acceleration); }

void NonpressureForcesSystem::run(World& w) {
    const auto x = w.fluid.store.get(comp::position);
    const auto v = w.fluid.store.get(comp::velocity);
    auto out = w.fluid.store.get(comp::nonpressure_acceleration);
    const bool with_boundary = m_boundary && w.boundary.size() > 0;
    const auto xb = w.boundary.store.get(comp::position);
    const std::span<const Real> vol = with_boundary ? w.boundary.store.get(comp::volume) : std::span<const Real>{};
    const std::span<const Vec3> velb = with_boundary && m_moving && w.boundary.store.has(comp::velocity.name)
                                           ? std::span<const Vec3>(w.boundary.store.get(comp::velocity))
                                           : std::span<const Vec3>{};
    const CubicSpline& kernel = w.kernel;
    const Physics& ph = w.physics;
    const Real m = ph.mass, alpha = ph.viscosity, c = ph.speed_of_sound, h = ph.h, rho0 = ph.rest_density;
    const Real kappa = Real(w.scene.fluid.surface_tension);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x.size(), 512), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            const Vec3 xi = x[i], vi = v[i];
            Vec3 a = Vec3::Zero();
            for (Index j : w.fluid_neighbours.of(Index(i))) {
                const Vec3 xij = xi - x[j];
                const Real r2 = xij.squaredNorm(), d = std::sqrt(r2);
                if (alpha > 0) {
                    const Real pi = monaghan_pi((vi - v[j]).dot(xij), r2, alpha, c, h, rho0, rho0);
                    if (pi != Real(0)) a -= (m * pi) * kernel.grad(xij, d);
                }
                if (kappa > 0) a -= (kappa * kernel.w(d)) * xij;
            }
            if (with_boundary && alpha > 0)
                for (Index b : w.boundary_neighbours.of(Index(i))) {
                    const Vec3 xib = xi - xb[b];
                    const Real r2 = xib.squaredNorm();
                    const Vec3 vib = velb.empty() ? vi : Vec3(vi - velb[b]);
                    const Real pi = monaghan_pi(vib.dot(xib), r2, alpha, c, h, rho0, rho0);
                    if (pi != Real(0)) a -= (rho0 * vol[b] * pi) * kernel.grad(xib, std::sqrt(r2));
                }
            out[i] = a;
        }
    });
}

}  // namespace sph
