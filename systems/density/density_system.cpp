// He et al. eq. 1: rho_i = sum_j m_j W_ij (self included), plus Akinci et al. 2012 eq. 6:
// + sum_b psi_b W_ib with psi_b = rho0 V_b. He eq. 2: Tait pressure (density_kernels.hpp).
// Individual stepping, He Alg. 2 lines 5-9: summation for active particles only; inactive
// particles carry rho_i(t_last) + (t - t_last) drho_i/dt from the asynchronous integration.
#include "systems/density/density_system.hpp"

#include <tbb/parallel_for.h>

#include <array>

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
                   .write_if(m_individual, fluid(comp::density_last));
    if (m_individual) a.rows(res::active_set);  // He Alg. 2 lines 6-7: the active rows only
    return a;
}

void DensitySystem::register_components(World& w) {
    w.fluid.store.add(comp::density);
    w.fluid.store.add(comp::pressure);
    if (m_individual) w.fluid.store.add(comp::density_last);
}

void DensitySystem::run(Context& ctx) {
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

}  // namespace sph
