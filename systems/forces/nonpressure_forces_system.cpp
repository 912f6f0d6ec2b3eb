// Becker & Teschner 2007 (cited by Ihmsen et al. 2010 sec. 3.4):
//  viscosity, eq. 10-11: a_i -= sum_j m_j Pi_ij grad W_ij, Pi_ij = -nu (v_ij . x_ij) /
//    (|x_ij|^2 + 0.01 h^2) for approaching pairs, nu = 2 alpha h c_s / (rho_i + rho_j); with
//    PCISPH rho_i = rho_j = rho0 to within eta, so rho0 is used. Against the boundary the same
//    term with psi_b = rho0 V_b and the relative velocity v_i - v_b (Akinci et al. 2012).
//  surface tension, eq. 13 (cohesion): a_i -= kappa sum_j (m_j / m_i) x_ij W_ij.
#include "systems/forces/nonpressure_forces_system.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "engine/data/components.hpp"
#include "systems/pcisph/pcisph_components.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"
#include "systems/forces/forces_kernels.hpp"
#include "systems/forces/forces_simd.hpp"

namespace sph {

Access NonpressureForcesSystem::access() const {
    return Access()
        .read(fluid(comp::position), fluid(comp::velocity), res::fluid_neighbours)
        .write(fluid(comp::nonpressure_acceleration))
        .read_if(m_boundary, res::boundary_neighbours, boundary(comp::position), boundary(comp::volume))
        .read_if(m_boundary && m_moving, boundary(comp::velocity));
}

void NonpressureForcesSystem::register_components(World& w) { w.fluid.store.add(comp::nonpressure_acceleration); }

void NonpressureForcesSystem::run(Context& ctx) {
    const auto x = ctx.read(fluid(comp::position));
    const auto v = ctx.read(fluid(comp::velocity));
    auto out = ctx.write(fluid(comp::nonpressure_acceleration));
    const bool with_boundary = m_boundary && ctx.size(SetId::Boundary) > 0;
    const auto xb = with_boundary ? ctx.read(boundary(comp::position)) : std::span<const Vec3>{};
    const std::span<const Real> vol = with_boundary ? ctx.read(boundary(comp::volume)) : std::span<const Real>{};
    const std::span<const Vec3> velb = with_boundary && m_moving && ctx.has(SetId::Boundary, comp::velocity.name)
                                           ? ctx.read(boundary(comp::velocity))
                                           : std::span<const Vec3>{};
    const NeighbourLists& fluid_nb = ctx.read(res::fluid_neighbours);
    const NeighbourLists* boundary_nb = with_boundary ? &ctx.read(res::boundary_neighbours) : nullptr;
    const CubicSpline& kernel = ctx.kernel();
    const Physics& ph = ctx.physics();
    const Real m = ph.mass, alpha = ph.viscosity, c = ph.speed_of_sound, h = ph.h, rho0 = ph.rest_density;
    const Real alpha_b = ph.boundary_viscosity;  // against the walls (0: free-slip)
    const Real kappa = Real(m_surface_tension);
    // The vectorised loop (simulation.simd) sums the same terms as the scalar loop below.
    NonpressurePairArgs vec;
    vec.x = x.empty() ? nullptr : x.data()->data();
    vec.v = v.empty() ? nullptr : v.data()->data();
    vec.fluid = &fluid_nb;
    if (with_boundary) {
        vec.xb = xb.data()->data();
        vec.volume_b = vol.data();
        vec.vel_b = velb.empty() ? nullptr : velb.data()->data();
        vec.boundary = boundary_nb;
    }
    vec.kernel = &kernel;
    vec.mass = m;
    vec.alpha = alpha;
    vec.alpha_b = alpha_b;
    vec.speed_of_sound = c;
    vec.h = h;
    vec.rest_density = rho0;
    vec.kappa = kappa;
    vec.acc = out.empty() ? nullptr : out.data()->data();
    const bool simd = ph.simd;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x.size(), 512), [&](const auto& r) {
        if (simd) return nonpressure_rows_simd(vec, r.begin(), r.end());
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            const Vec3 xi = x[i], vi = v[i];
            Vec3 a = Vec3::Zero();
            for (Index j : fluid_nb.of(Index(i))) {
                const Vec3 xij = xi - x[j];
                const Real r2 = xij.squaredNorm(), d = std::sqrt(r2);
                if (alpha > 0) {
                    const Real pi = monaghan_pi((vi - v[j]).dot(xij), r2, alpha, c, h, rho0, rho0);
                    if (pi != Real(0)) a -= (m * pi) * kernel.grad(xij, d);
                }
                if (kappa > 0) a -= (kappa * kernel.w(d)) * xij;
            }
            if (with_boundary && alpha_b > 0)
                for (Index b : boundary_nb->of(Index(i))) {
                    const Vec3 xib = xi - xb[b];
                    const Real r2 = xib.squaredNorm();
                    const Vec3 vib = velb.empty() ? vi : Vec3(vi - velb[b]);
                    const Real pi = monaghan_pi(vib.dot(xib), r2, alpha_b, c, h, rho0, rho0);
                    if (pi != Real(0)) a -= (rho0 * vol[b] * pi) * kernel.grad(xib, std::sqrt(r2));
                }
            out[i] = a;
        }
    });
}

}  // namespace sph
