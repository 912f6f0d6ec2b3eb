// He et al. eq. 1: rho_i = sum_j m_j W_ij (self included), plus Akinci et al. 2012 eq. 6:
// + sum_b psi_b W_ib with psi_b = rho0 V_b. He eq. 2: Tait pressure (density_kernels.hpp).
// Individual stepping, He Alg. 2 lines 5-9: summation for active particles only; inactive
// particles carry rho_i(t_last) + (t - t_last) drho_i/dt from the asynchronous integration.
#include "systems/density/density_system.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"
#include "systems/density/density_kernels.hpp"
#include "systems/density/density_simd.hpp"

namespace sph {

Access DensitySystem::access() const {
    Access a = Access()
                   .read(fluid(comp::position), res::fluid_neighbours)
                   .write(fluid(comp::density), fluid(comp::pressure))
                   .read_if(m_with_boundary, res::boundary_neighbours, boundary(comp::position), boundary(comp::volume))
                   .read_if(m_individual, res::active_set)
                   .write_if(m_individual, fluid(comp::density_last))
                   .read_if(m_continuity, fluid(comp::velocity))
                   .write_if(m_continuity, fluid(comp::drho_dt))
                   .read_if(m_continuity && m_individual, fluid(comp::t_last))
                   .write_if(m_continuity && !m_individual, res::density_clock)
                   .read_if(m_continuity && m_with_boundary && m_moving_boundary, boundary(comp::velocity));
    if (m_individual) a.rows(res::active_set);  // He Alg. 2 lines 6-7: the active rows only
    return a;
}

void DensitySystem::register_components(World& w) {
    w.fluid.store.add(comp::density);
    w.fluid.store.add(comp::pressure);
    if (m_individual) w.fluid.store.add(comp::density_last);
    if (m_continuity) w.fluid.store.add(comp::drho_dt);
    if (m_continuity && !m_individual) w.resources.add<DensityClock>(res::density_clock.name, Lifetime::Kept);
}

void DensitySystem::run(Context& ctx) {
    if (m_continuity) return run_continuity(ctx);
    const auto x = ctx.read(fluid(comp::position));
    auto rho = ctx.write(fluid(comp::density));
    auto p = ctx.write(fluid(comp::pressure));
    const bool has_boundary = m_with_boundary && ctx.size(SetId::Boundary) > 0;
    const auto xb = has_boundary ? ctx.read(boundary(comp::position)) : std::span<const Vec3>{};
    const std::span<const Real> vb = has_boundary ? ctx.read(boundary(comp::volume)) : std::span<const Real>{};
    const NeighbourLists& fluid_nb = ctx.read(res::fluid_neighbours);
    const NeighbourLists* boundary_nb = has_boundary ? &ctx.read(res::boundary_neighbours) : nullptr;
    const CubicSpline& kernel = ctx.kernel();
    const Physics& ph = ctx.physics();
    const Real self = ph.mass * kernel.w(0);
    auto summation = [&](Index i) {
        const Vec3 xi = x[i];
        Real sum = 0;
        for (Index j : fluid_nb.of(i)) sum += kernel.w((xi - x[j]).norm());
        Real bsum = 0;
        if (has_boundary)
            for (Index b : boundary_nb->of(i)) bsum += vb[b] * kernel.w((xi - xb[b]).norm());
        rho[i] = self + ph.mass * sum + ph.rest_density * bsum;
        p[i] = tait_pressure(rho[i], ph.rest_density, ph.tait_b);
    };
    // The vectorised loop (simulation.simd) takes the same two sums over the same lists; the
    // scalar lambda above is the reference it is tested against.
    KernelSumArgs sums;
    sums.x = x.empty() ? nullptr : x.data()->data();
    sums.fluid = &fluid_nb;
    if (has_boundary) {
        sums.xb = xb.data()->data();
        sums.weight_b = vb.data();
        sums.boundary = boundary_nb;
    }
    sums.kernel = &kernel;
    auto vectorised = [&](const Index* rows, std::size_t begin, std::size_t end, std::span<Real> rho_last) {
        constexpr std::size_t kChunk = 256;
        std::array<Real, kChunk> sum{}, bsum{};
        for (std::size_t b = begin; b < end; b += kChunk) {
            const std::size_t e = std::min(end, b + kChunk);
            kernel_sums_simd(sums, rows, b, e, sum.data(), bsum.data());
            for (std::size_t k = b; k < e; ++k) {
                const Index i = rows ? rows[k] : Index(k);
                rho[i] = self + ph.mass * sum[k - b] + ph.rest_density * (has_boundary ? bsum[k - b] : Real(0));
                p[i] = tait_pressure(rho[i], ph.rest_density, ph.tait_b);
                if (!rho_last.empty()) rho_last[i] = rho[i];
            }
        }
    };
    if (!m_individual) {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x.size(), 512), [&](const auto& r) {
            if (ph.simd) return vectorised(nullptr, r.begin(), r.end(), {});
            for (std::size_t i = r.begin(); i < r.end(); ++i) summation(Index(i));
        });
        return;
    }
    // Active particles only (He Alg. 2 lines 6-7); the summed density is also the base of
    // the interpolation rho_i(t) = rho_i(t_last) + (t - t_last) drho_i/dt (line 9), which the
    // asynchronous integration applies to every particle at the end of each step.
    const auto& active = ctx.read(res::active_set);
    auto rho_last = ctx.write(fluid(comp::density_last));
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, active.size(), 256), [&](const auto& r) {
        if (ph.simd) return vectorised(active.data(), r.begin(), r.end(), rho_last);
        for (std::size_t k = r.begin(); k < r.end(); ++k) {
            summation(active[k]);
            rho_last[active[k]] = rho[active[k]];
        }
    });
}

void DensitySystem::run_continuity(Context& ctx) {
    const auto x = ctx.read(fluid(comp::position));
    const auto v = ctx.read(fluid(comp::velocity));
    auto rho = ctx.write(fluid(comp::density));
    auto p = ctx.write(fluid(comp::pressure));
    auto drho = ctx.write(fluid(comp::drho_dt));
    const bool has_boundary = m_with_boundary && ctx.size(SetId::Boundary) > 0;
    const auto xb = has_boundary ? ctx.read(boundary(comp::position)) : std::span<const Vec3>{};
    const std::span<const Real> vb = has_boundary ? ctx.read(boundary(comp::volume)) : std::span<const Real>{};
    const std::span<const Vec3> vel_b =
        has_boundary && m_moving_boundary && ctx.has(SetId::Boundary, comp::velocity.name)
            ? ctx.read(boundary(comp::velocity))
            : std::span<const Vec3>{};
    const NeighbourLists& fluid_nb = ctx.read(res::fluid_neighbours);
    const NeighbourLists* boundary_nb = has_boundary ? &ctx.read(res::boundary_neighbours) : nullptr;
    const CubicSpline& kernel = ctx.kernel();
    const Physics& ph = ctx.physics();
    const Real m = ph.mass, rho0 = ph.rest_density, c = ph.speed_of_sound, h = ph.h;
    const Real diffusion = ph.density_diffusion * h * c, eps_h2 = Real(0.01) * h * h;
    const Vec3 g_h = (rho0 / (c * c)) * ph.gravity;  // rho^H_ij = g_h . x_ij
    const Real floor_rho = continuity_density_floor(rho0);
    // A row without a density (0) starts from its summation, at least rho0; its D_i is then
    // still computed (the slope of individual stepping's interpolation) but not applied.
    auto summation = [&](Index i) {
        const Vec3 xi = x[i];
        Real sum = 0, bsum = 0;
        for (Index j : fluid_nb.of(i)) sum += kernel.w((xi - x[j]).norm());
        if (has_boundary)
            for (Index b : boundary_nb->of(i)) bsum += vb[b] * kernel.w((xi - xb[b]).norm());
        return std::max(m * (kernel.w(0) + sum) + rho0 * bsum, rho0);
    };
    auto start = [&](Index i) { rho[i] = summation(i); };
    // A row with no fluid neighbour (a droplet, alone or against a wall) takes the summation
    // density, as a started row does: max(m W(0) + rho0 sum_b V_b W_ib, rho0) (Akinci et al.
    // 2012 eq. 6, with the volumes V_b of their eq. 4). Its continuity density has nothing to relax it (no pair, no
    // diffusion), and the boundary term integrated over its own long steps does not return to
    // where it started after a wall contact: evaluated at each step's end it overshoots on the way
    // in and undershoots on the way out, so the droplet leaves every contact denser than it came
    // and its extra pressure throws it back faster (docs/methods.md, "A droplet takes the
    // summation density"). The summation density is a function of position: the wall force on
    // such a row is conservative.
    auto isolated = [&](Index i) { return fluid_nb.of(i).empty(); };
    auto rate = [&](Index i) {
        const Vec3 xi = x[i], vi = v[i];
        const Real rhoi = rho[i];
        Real div = 0, diffused = 0;
        for (Index j : fluid_nb.of(i)) {
            const Vec3 xij = xi - x[j];
            const Real r2 = xij.squaredNorm();
            const Vec3 grad = kernel.grad(xij, std::sqrt(r2));
            div += (vi - v[j]).dot(grad);
            if (diffusion > 0) diffused += diffusion_term(rhoi, rho[j], g_h.dot(xij), xij.dot(grad), r2, eps_h2);
        }
        Real bdiv = 0;
        if (has_boundary)
            for (Index b : boundary_nb->of(i)) {
                const Vec3 xib = xi - xb[b];
                const Vec3 vib = vel_b.empty() ? vi : Vec3(vi - vel_b[b]);
                bdiv += vb[b] * vib.dot(kernel.grad(xib, xib.norm()));
            }
        return m * div + rho0 * bdiv + diffusion * m * diffused;
    };
    // The vectorised rates (simulation.simd): the same formula; the scalar `rate` is the reference.
    ContinuityRateArgs vec;
    vec.x = x.empty() ? nullptr : x.data()->data();
    vec.v = v.empty() ? nullptr : v.data()->data();
    vec.rho = rho.data();
    vec.fluid = &fluid_nb;
    if (has_boundary) {
        vec.xb = xb.data()->data();
        vec.volume_b = vb.data();
        vec.vel_b = vel_b.empty() ? nullptr : vel_b.data()->data();
        vec.boundary = boundary_nb;
    }
    vec.kernel = &kernel;
    vec.mass = m;
    vec.rest_density = rho0;
    vec.diffusion = diffusion;
    vec.eps_h2 = eps_h2;
    for (int k = 0; k < 3; ++k) vec.g_h[k] = g_h[k];
    // D_i of rows[k] (or row k), k in [begin, end), into drho.
    auto rates = [&](const Index* rows, std::size_t begin, std::size_t end) {
        if (!ph.simd) {
            for (std::size_t k = begin; k < end; ++k) {
                const Index i = rows ? rows[k] : Index(k);
                drho[i] = rate(i);
            }
            return;
        }
        constexpr std::size_t kChunk = 256;
        std::array<Real, kChunk> out{};
        for (std::size_t b = begin; b < end; b += kChunk) {
            const std::size_t e = std::min(end, b + kChunk);
            continuity_rates_simd(vec, rows, b, e, out.data());
            for (std::size_t k = b; k < e; ++k) drho[rows ? rows[k] : Index(k)] = out[k - b];
        }
    };
    const Tick now = ctx.clock().t_ticks;
    if (!m_individual) {
        // Every row: D_i from the densities of time t_0 (all rows read before any is advanced).
        DensityClock& clock = ctx.write(res::density_clock);
        const Real dt = Real(to_seconds(now - clock.t_ticks));
        // A started row is marked by a NaN pressure until the last pass sets it.
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x.size(), 1024), [&](const auto& r) {
            for (std::size_t i = r.begin(); i < r.end(); ++i)
                if (rho[i] == Real(0)) start(Index(i)), p[i] = std::numeric_limits<Real>::quiet_NaN();
        });
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x.size(), 256), [&](const auto& r) {
            rates(nullptr, r.begin(), r.end());
        });
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x.size(), 2048), [&](const auto& r) {
            for (std::size_t i = r.begin(); i < r.end(); ++i) {
                if (isolated(Index(i))) rho[i] = summation(Index(i));
                else if (!std::isnan(p[i])) rho[i] = std::max(rho[i] + dt * drho[i], floor_rho);
                p[i] = tait_pressure(rho[i], rho0, ph.tait_b);
            }
        });
        clock.t_ticks = now;
        return;
    }
    // Active rows: D_i from the interpolated densities of every row at t (He Alg. 2 line 9), then
    // rho_i(t) = rho_i(t_last) + (t - t_last) D_i, the new base of the interpolation.
    const auto& active = ctx.read(res::active_set);
    auto rho_last = ctx.write(fluid(comp::density_last));
    const auto t_last = ctx.read(fluid(comp::t_last));
    // New rows (density 0) are started first, so that no rate reads a density of 0.
    std::vector<Real>& next = m_next;  // kept between steps: no allocation per step
    next.resize(active.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, active.size(), 1024), [&](const auto& r) {
        for (std::size_t k = r.begin(); k < r.end(); ++k) {
            const Index i = active[k];
            next[k] = rho[i] == Real(0) ? Real(-1) : Real(0);  // -1 marks a row summed now
            if (next[k] < 0) start(i);
        }
    });
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, active.size(), 256), [&](const auto& r) {
        rates(active.data(), r.begin(), r.end());
        for (std::size_t k = r.begin(); k < r.end(); ++k) {
            const Index i = active[k];
            if (isolated(i)) {
                next[k] = summation(i);
                drho[i] = 0;  // held until its next evaluation, not interpolated
            } else {
                next[k] = next[k] < 0 ? rho[i] : std::max(rho_last[i] + Real(to_seconds(now - t_last[i])) * drho[i], floor_rho);
            }
        }
    });
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, active.size(), 1024), [&](const auto& r) {
        for (std::size_t k = r.begin(); k < r.end(); ++k) {
            const Index i = active[k];
            rho[i] = rho_last[i] = next[k];
            p[i] = tait_pressure(rho[i], rho0, ph.tait_b);
        }
    });
}

}  // namespace sph
