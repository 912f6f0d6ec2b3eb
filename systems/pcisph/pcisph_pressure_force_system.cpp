// Ihmsen et al. 2010 eq. 6: F^p_i/m_i = -sum_j m_j (p_i/rho*_i^2 + p_j/rho*_j^2) grad W_ij
//                                        -sum_b m_b (p_i/rho*_i^2 + p_b/rho*_b^2) grad W_ib.
#include "systems/pcisph/pcisph_pressure_force_system.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"
#include "systems/forces/forces_simd.hpp"
#include "systems/pcisph/pcisph_components.hpp"
#include "systems/pcisph/pcisph_kernels.hpp"
#include "systems/pcisph/pcisph_state.hpp"

namespace sph {

Access PcisphPressureForceSystem::access() const {
    return Access()
        .read(fluid(comp::position), fluid(comp::density), fluid(comp::pressure), fluid(comp::pressure_term),
              res::fluid_neighbours)
        .write(fluid(comp::pressure_acceleration))
        .read_if(m_ihmsen, res::boundary_neighbours, boundary(comp::position), boundary(comp::mass),
                 boundary(comp::density), boundary(comp::pressure));
}

void PcisphPressureForceSystem::run(Context& ctx) {
    const auto x = ctx.read(fluid(comp::position));
    const auto rho = ctx.read(fluid(comp::density));
    const auto p = ctx.read(fluid(comp::pressure));
    auto ap = ctx.write(fluid(comp::pressure_acceleration));
    const bool with_boundary = m_ihmsen && ctx.size(SetId::Boundary) > 0;
    std::span<const Vec3> xb;
    std::span<const Real> mb, rhob, pb;
    const NeighbourLists& fluid_nb = ctx.read(res::fluid_neighbours);
    const NeighbourLists* boundary_nb = nullptr;
    if (with_boundary) {
        xb = ctx.read(boundary(comp::position));
        mb = ctx.read(boundary(comp::mass));
        rhob = ctx.read(boundary(comp::density));
        pb = ctx.read(boundary(comp::pressure));
        boundary_nb = &ctx.read(res::boundary_neighbours);
    }
    const CubicSpline& kernel = ctx.kernel();
    const Real m = ctx.physics().mass;
    // The vectorised loop (simulation.simd) sums the same terms as the scalar loop below.
    PressurePairArgs vec;
    vec.x = x.empty() ? nullptr : x.data()->data();
    vec.p_term = ctx.read(fluid(comp::pressure_term)).data();
    vec.fluid = &fluid_nb;
    if (with_boundary) {
        vec.xb = xb.data()->data();
        vec.mass_b = mb.data();
        vec.rho_b = rhob.data();
        vec.p_b = pb.data();
        vec.boundary = boundary_nb;
    }
    vec.kernel = &kernel;
    vec.mass = m;
    vec.acc = ap.empty() ? nullptr : ap.data()->data();
    const bool simd = ctx.physics().simd;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x.size(), 512), [&](const auto& r) {
        if (simd) return pressure_force_rows_simd(vec, r.begin(), r.end());
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            const Vec3 xi = x[i];
            const Real pi = p[i] / (rho[i] * rho[i]);
            Vec3 a = Vec3::Zero();
            for (Index j : fluid_nb.of(Index(i))) {
                const Real pj = p[j] / (rho[j] * rho[j]);
                if (pi == Real(0) && pj == Real(0)) continue;
                const Vec3 xij = xi - x[j];
                a -= (m * (pi + pj)) * kernel.grad(xij, xij.norm());
            }
            if (with_boundary)
                for (Index b : boundary_nb->of(Index(i))) {
                    const Real pbb = pb[b] / (rhob[b] * rhob[b]);
                    if (pi == Real(0) && pbb == Real(0)) continue;
                    const Vec3 xib = xi - xb[b];
                    a -= (mb[b] * (pi + pbb)) * kernel.grad(xib, xib.norm());
                }
            ap[i] = a;
        }
    });
}

}  // namespace sph
