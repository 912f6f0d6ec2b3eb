// Ihmsen et al. 2010 eq. 2 / eq. 13: rho*_i = sum_j m_j W(x*_ij) [+ sum_b m_b W(x*_i - x_b)];
// eq. 3: p_i += delta (rho*_i - rho0), kept >= 0.
#include "systems/pcisph/pcisph_density_system.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <array>

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"
#include "systems/density/density_simd.hpp"
#include "systems/pcisph/pcisph_components.hpp"
#include "systems/pcisph/pcisph_kernels.hpp"
#include "systems/pcisph/pcisph_state.hpp"

namespace sph {

Access PcisphDensitySystem::access() const {
    return Access()
        .read(fluid(comp::predicted_position), res::fluid_neighbours, res::pcisph_delta)
        .write(fluid(comp::density), fluid(comp::pressure), fluid(comp::pressure_term), res::pcisph_errors)
        .read_if(m_ihmsen, res::boundary_neighbours, boundary(comp::position), boundary(comp::mass));
}

void PcisphDensitySystem::register_components(World& w) {
    w.fluid.store.add(comp::density);
    w.fluid.store.add(comp::pressure);
    w.fluid.store.add(comp::pressure_term);
    w.resources.add<PcisphErrors>(res::pcisph_errors.name, Lifetime::Scratch);
}

namespace {
struct ErrAcc {
    double sum = 0, max = 0;
};
}  // namespace

void PcisphDensitySystem::run(Context& ctx) {
    const auto xs = ctx.read(fluid(comp::predicted_position));
    auto rho = ctx.write(fluid(comp::density));
    auto p = ctx.write(fluid(comp::pressure));
    auto p_term = ctx.write(fluid(comp::pressure_term));
    const bool with_boundary = m_ihmsen && ctx.size(SetId::Boundary) > 0;
    const auto xb = with_boundary ? ctx.read(boundary(comp::position)) : std::span<const Vec3>{};
    const std::span<const Real> mb = with_boundary ? ctx.read(boundary(comp::mass)) : std::span<const Real>{};
    const NeighbourLists& fluid_nb = ctx.read(res::fluid_neighbours);
    const NeighbourLists* boundary_nb = with_boundary ? &ctx.read(res::boundary_neighbours) : nullptr;
    const CubicSpline& kernel = ctx.kernel();
    const Real m = ctx.physics().mass, rho0 = ctx.physics().rest_density, self = m * kernel.w(0);
    const Real delta = Real(ctx.read(res::pcisph_delta).delta);
    const std::size_t n = xs.size();
    // The vectorised sums (simulation.simd) take the same terms as the scalar loop below.
    const bool simd = ctx.physics().simd;
    KernelSumArgs sums;
    sums.x = xs.empty() ? nullptr : xs.data()->data();
    sums.fluid = &fluid_nb;
    if (with_boundary) {
        sums.xb = xb.data()->data();
        sums.weight_b = mb.data();
        sums.boundary = boundary_nb;
    }
    sums.kernel = &kernel;
    constexpr std::size_t kChunk = 256;
    const ErrAcc acc = tbb::parallel_deterministic_reduce(
        tbb::blocked_range<std::size_t>(0, n, 1024), ErrAcc{},
        [&](const auto& r, ErrAcc e) {
            std::array<Real, kChunk> fsum{}, bsums{};
            for (std::size_t i = r.begin(); i < r.end(); ++i) {
                const std::size_t c = (i - r.begin()) % kChunk;
                if (simd && c == 0) kernel_sums_simd(sums, nullptr, i, std::min(r.end(), i + kChunk), fsum.data(), bsums.data());
                Real sum = 0, bsum = 0;
                if (simd) {
                    sum = fsum[c];
                    bsum = with_boundary ? bsums[c] : Real(0);
                } else {
                    const Vec3 xi = xs[i];
                    for (Index j : fluid_nb.of(Index(i))) sum += kernel.w((xi - xs[j]).norm());
                    if (with_boundary)
                        for (Index b : boundary_nb->of(Index(i))) bsum += mb[b] * kernel.w((xi - xb[b]).norm());
                }
                const Real r_i = self + m * sum + bsum;  // eq. 13 (eq. 2 without the boundary)
                rho[i] = r_i;
                p[i] = pcisph_pressure_update(p[i], delta, r_i, rho0);  // eq. 3
                p_term[i] = p[i] / (r_i * r_i);                            // eq. 6's p_i / rho*_i^2
                const double err = std::max(0.0, double(r_i) / double(rho0) - 1.0);
                e.sum += err;
                e.max = std::max(e.max, err);
            }
            return e;
        },
        [](ErrAcc a, const ErrAcc& b) {
            a.sum += b.sum;
            a.max = std::max(a.max, b.max);
            return a;
        });
    PcisphErrors& errors = ctx.write(res::pcisph_errors);
    errors.pred_err_max = acc.max;
    errors.pred_err_avg = n ? acc.sum / double(n) : 0.0;
}

}  // namespace sph
