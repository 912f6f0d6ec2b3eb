// He et al. eq. 4: a_i = -sum_j m_j (p_i/rho_i^2 + p_j/rho_j^2) grad W_ij + g,
// plus Monaghan 1992 artificial viscosity -sum_j m_j Pi_ij grad W_ij (forces_kernels.hpp).
// Boundary (Akinci et al. 2012's volumes in He eq. 4's pair, the wall's side mirroring p_b = p_i,
// rho_b = rho_i: twice Akinci eq. 10's single p_i / rho_i^2 term; docs/methods.md, "Wall pressure"):
// a_i -= sum_b psi_b (2 p_i / rho_i^2) grad W_ib, psi_b = rho0 V_b; with `fluid.wall_pressure:
// extrapolated` (p_b, rho_b of WallPressureSystem, Adami et al. 2012 eq. 27)
// a_i -= sum_b psi_b (p_i / rho_i^2 + p_b / rho_b^2) grad W_ib. Viscosity against the wall
// uses the same Pi with rho_j = rho0 and the wall's velocity (zero for static walls): for a
// moving boundary, Pi_ib is evaluated with the relative velocity v_ib = v_i - v_b (Akinci et
// al. 2012 sec. 3.3, eq. 11-12: the boundary viscosity acts on the velocity relative to the
// rigid body), so a body drags the fluid along and fluid moving with it feels no friction.
// Corrected pressure gradient (scene `fluid.pressure_gradient: corrected`, Bonet & Lok 1999):
// grad W_ij in the pressure term becomes (L_i + L_j)/2 grad W_ij, symmetric in i and j, so
// F_ij = -F_ji still holds; against the boundary L_i grad W_ib.
// Laminar viscosity (Morris et al. 1997; forces_kernels.hpp laminar_coefficient) when
// Physics::kinematic_viscosity > 0: fluid pairs, and boundary pairs with v_ib unless the walls
// are free-slip (boundary_viscosity 0), rho_b = rho0.
// Continuity density (`fluid.density: continuity`): drho/dt is the density system's
// (density_system.hpp), so individual stepping leaves it alone here.
// Individual stepping (He Alg. 2 lines 10-13): active particles only, plus
// drho_i/dt = sum_j m_j v_ij . grad W_ij + sum_b psi_b v_ib . grad W_ib (He eq. 5) and
// Delta t_i^raw = min(lambda_v h/|v_i|, lambda_f sqrt(h/|a_i|)) (line 13; the same function
// as the global step, so that equal steps reproduce `global` exactly).
#include "systems/forces/forces_system.hpp"

#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <functional>

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"
#include "systems/forces/forces_kernels.hpp"
#include "systems/forces/forces_simd.hpp"
#include "systems/timestep/global_dt_system.hpp"
#include "systems/timestep/step_bound_simd.hpp"

namespace sph {

Access ForcesSystem::access() const {
    Access a = Access()
                   .read(fluid(comp::position), fluid(comp::velocity), fluid(comp::density), fluid(comp::pressure),
                         res::fluid_neighbours)
                   .write(fluid(comp::acceleration), counter::force_evaluations)
                   .read_if(m_with_boundary, res::boundary_neighbours, boundary(comp::position), boundary(comp::volume))
                   .read_if(m_with_boundary && m_moving_boundary, boundary(comp::velocity))
                   .read_if(m_extrapolated, boundary(comp::pressure), boundary(comp::density))
                   .read_if(m_corrected, fluid(comp::gradient_correction))
                   .read_if(m_individual, res::active_set)
                   .write_if(m_individual && !m_continuity, fluid(comp::drho_dt))
                   .write_if(m_individual, fluid(comp::dt_raw), fluid(comp::t_last));
    if (m_individual) a.rows(res::active_set);  // He Alg. 2 lines 10-14: the active rows only
    return a;
}

void ForcesSystem::register_components(World& w) {
    w.fluid.store.add(comp::acceleration);
    if (m_individual && !m_continuity) w.fluid.store.add(comp::drho_dt);
    if (m_individual) {
        w.fluid.store.add(comp::dt_raw);
        w.fluid.store.add(comp::t_last);
    }
}

void ForcesSystem::run(Context& ctx) {
    const auto x = ctx.read(fluid(comp::position));
    const auto v = ctx.read(fluid(comp::velocity));
    const auto rho = ctx.read(fluid(comp::density));
    const auto p = ctx.read(fluid(comp::pressure));
    auto acc = ctx.write(fluid(comp::acceleration));
    const bool has_boundary = m_with_boundary && ctx.size(SetId::Boundary) > 0;
    const auto xb = has_boundary ? ctx.read(boundary(comp::position)) : std::span<const Vec3>{};
    const std::span<const Real> vb = has_boundary ? ctx.read(boundary(comp::volume)) : std::span<const Real>{};
    const NeighbourLists& fluid_nb = ctx.read(res::fluid_neighbours);
    const NeighbourLists* boundary_nb = has_boundary ? &ctx.read(res::boundary_neighbours) : nullptr;
    // Boundary velocities (moving bodies; zero rows for static particles). Absent in static
    // scenes, whose arithmetic is then exactly the static formula.
    const std::span<const Vec3> vel_b =
        has_boundary && m_moving_boundary && ctx.has(SetId::Boundary, comp::velocity.name)
            ? ctx.read(boundary(comp::velocity))
            : std::span<const Vec3>{};
    const bool moving = !vel_b.empty();
    const CubicSpline& kernel = ctx.kernel();
    const Physics& ph = ctx.physics();
    const Real m = ph.mass, alpha = ph.viscosity, c = ph.speed_of_sound, h = ph.h, rho0 = ph.rest_density;
    const Real alpha_b = ph.boundary_viscosity;  // 0: free-slip walls (pressure force only)
    const Vec3 g = ph.gravity;
    // Extrapolated walls: p_b and rho_b of WallPressureSystem (Adami et al. 2012 eq. 27); else
    // mirrored, p_b / rho_b^2 = p_i / rho_i^2.
    const std::span<const Real> pb = m_extrapolated ? ctx.read(boundary(comp::pressure)) : std::span<const Real>{};
    const std::span<const Real> rhob = m_extrapolated ? ctx.read(boundary(comp::density)) : std::span<const Real>{};
    const Real nu4 = Real(4) * ph.kinematic_viscosity, eps_h2 = Real(0.01) * h * h;  // laminar viscosity
    std::span<Real> drho;
    std::span<double> dt_raw;
    if (m_individual && !m_continuity) drho = ctx.write(fluid(comp::drho_dt));
    if (m_individual) dt_raw = ctx.write(fluid(comp::dt_raw));
    const std::span<const Mat3> L = m_corrected ? ctx.read(fluid(comp::gradient_correction)) : std::span<const Mat3>{};
    const SteppingParams& stepping = m_stepping;
    // The mode and the gradient form are template parameters, so the `global`/`constant` loop
    // carries no per-neighbour branches for the individual-only sums or the correction.
    // He Alg. 2 line 13, computed exactly as the global step of eq. 6-8 (so that equal steps
    // reproduce `global`), from the particle's velocity and its new acceleration.
    const StepBound bound(stepping, h, c, ph.kinematic_viscosity);
    auto raw_step = [&](Index i) { dt_raw[i] = bound.of(v[i], acc[i]); };
    // Drho: drho_i/dt is wanted (individual stepping with the summation density).
    auto evaluate = [&]<bool Drho, bool Corrected>(Index i) {
        const Vec3 xi = x[i], vi = v[i];
        const Real rhoi = rho[i];
        const Real pi = p[i] / (rhoi * rhoi);
        Vec3 a = Vec3::Zero();
        Real div = 0;  // He eq. 5
        for (Index j : fluid_nb.of(i)) {
            const Vec3 xij = xi - x[j];
            const Real r2 = xij.squaredNorm();
            const Vec3 grad = kernel.grad(xij, std::sqrt(r2));
            const Vec3 vij = vi - v[j];
            const Real visc = alpha > 0 ? monaghan_pi(vij.dot(xij), r2, alpha, c, h, rhoi, rho[j]) : Real(0);
            if constexpr (Corrected)
                a -= (m * (pi + p[j] / (rho[j] * rho[j]))) * (Real(0.5) * (L[i] + L[j]) * grad) + (m * visc) * grad;
            else
                a -= (m * (pi + p[j] / (rho[j] * rho[j]) + visc)) * grad;
            if (nu4 > 0) a += (m * laminar_coefficient(xij.dot(grad), r2, nu4, rhoi, rho[j], eps_h2)) * vij;
            if constexpr (Drho) div += m * vij.dot(grad);
        }
        if (has_boundary) {
            for (Index b : boundary_nb->of(i)) {
                const Vec3 xib = xi - xb[b];
                const Real r2 = xib.squaredNorm();
                const Vec3 grad = kernel.grad(xib, std::sqrt(r2));
                const Vec3 vib = moving ? Vec3(vi - vel_b[b]) : vi;  // relative velocity v_i - v_b
                const Real visc = alpha_b > 0 ? monaghan_pi(vib.dot(xib), r2, alpha_b, c, h, rhoi, rho0) : Real(0);
                const Real pterm = pb.empty() ? Real(2) * pi : pi + pb[b] / (rhob[b] * rhob[b]);
                if constexpr (Corrected)
                    a -= (rho0 * vb[b] * pterm) * (L[i] * grad) + (rho0 * vb[b] * visc) * grad;
                else
                    a -= (rho0 * vb[b] * (pterm + visc)) * grad;
                if (nu4 > 0 && alpha_b > 0)  // no-slip walls: the laminar term against v_b
                    a += (rho0 * vb[b] * laminar_coefficient(xib.dot(grad), r2, nu4, rhoi, rho0, eps_h2)) * vib;
                if constexpr (Drho) div += rho0 * vb[b] * vib.dot(grad);  // He eq. 5, boundary term
            }
        }
        acc[i] = a + g;
        if constexpr (Drho) drho[i] = div;
    };
    // The vectorised loops (simulation.simd; step_bounds_simd for line 13, bit for bit
    // raw_step's); the scalar lambdas above are the reference they are tested against.
    const bool simd = ph.simd;
    ForcePairArgs vec;
    if (simd) {
        vec.x = x.empty() ? nullptr : x.data()->data();
        vec.v = v.empty() ? nullptr : v.data()->data();
        vec.rho = rho.data();
        vec.p = p.data();
        vec.fluid = &fluid_nb;
        if (has_boundary) {
            vec.xb = xb.data()->data();
            vec.volume_b = vb.data();
            vec.vel_b = moving ? vel_b.data()->data() : nullptr;
            vec.p_b = pb.empty() ? nullptr : pb.data();
            vec.rho_b = rhob.empty() ? nullptr : rhob.data();
            vec.boundary = boundary_nb;
        }
        vec.kernel = &kernel;
        vec.mass = m;
        vec.alpha = alpha;
        vec.alpha_b = alpha_b;
        vec.speed_of_sound = c;
        vec.h = h;
        vec.rest_density = rho0;
        for (int k = 0; k < 3; ++k) vec.gravity[k] = g[k];
        vec.acc = acc.empty() ? nullptr : acc.data()->data();
        vec.drho = drho.empty() ? nullptr : drho.data();
        vec.nu4 = nu4;
        vec.alpha_b_laminar = alpha_b > 0;
        vec.L = m_corrected && !L.empty() ? L.data()->data() : nullptr;
    }
    if (!m_individual) {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x.size(), 256), [&](const auto& r) {
            if (simd) return force_rows_simd(vec, nullptr, r.begin(), r.end());
            for (std::size_t i = r.begin(); i < r.end(); ++i) {
                if (m_corrected)
                    evaluate.template operator()<false, true>(Index(i));
                else
                    evaluate.template operator()<false, false>(Index(i));
            }
        });
        ctx.write(counter::force_evaluations) = x.size();
        return;
    }
    // He Alg. 2 lines 10-14: active particles only; each evaluation stamps t_last = t_sim.
    const auto& active = ctx.read(res::active_set);
    auto t_last = ctx.write(fluid(comp::t_last));
    const Tick now = ctx.clock().t_ticks;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, active.size(), 256), [&](const auto& r) {
            if (simd) {  // a_i, drho_i/dt and Delta t_i^raw of the whole range
                force_rows_simd(vec, active.data(), r.begin(), r.end());
                step_bounds_simd(bound, vec.v, vec.acc, x.size(), active.data(), r.begin(), r.end(), dt_raw.data());
            }
            for (std::size_t k = r.begin(); k < r.end(); ++k) {
                const Index i = active[k];
                if (!simd) {
                    if (m_continuity)
                        m_corrected ? evaluate.template operator()<false, true>(i)
                                    : evaluate.template operator()<false, false>(i);
                    else
                        m_corrected ? evaluate.template operator()<true, true>(i)
                                    : evaluate.template operator()<true, false>(i);
                    raw_step(i);
                }
                t_last[i] = now;
            }
        });
    ctx.write(counter::force_evaluations) = active.size();  // each active row once
}

}  // namespace sph
