// The kernel sums of He et al. eq. 1 + Akinci et al. 2012 eq. 6 (WCSPH summation density) and
// Ihmsen et al. 2010 eq. 13 (PCISPH predicted density), vectorised across each particle's
// neighbour list: 16 (AVX-512) or 8 (AVX2) neighbours per iteration, positions gathered from
// the xyz rows. Compiled per target, chosen at run time (engine/core/simd.hpp).
#include "engine/core/simd_targets.hpp"

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "systems/density/density_simd.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

#include "engine/core/kernel_simd-inl.hpp"
#include "systems/density/density_simd.hpp"

HWY_BEFORE_NAMESPACE();
namespace sph {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

#ifndef SPH_DOUBLE
/// sum_j w_j W(|x_i - x_j|) over one list (w_j = 1 without weights), positions gathered from
/// the xyz rows at `x`.
template <class D>
HWY_INLINE Real kernel_sum(D d, const KernelV<D>& k, const Real* x, const Broadcast3<D>& xi, const Index* list,
                           std::size_t count, const Real* weight) {
    auto sum = hn::Zero(d);
    for (std::size_t k0 = 0; k0 < count; k0 += hn::Lanes(d)) {
        const PairChunk<D> c = pair_chunk(d, x, xi, list, k0, count);
        auto w = k.w(d, hn::Sqrt(c.r2));
        if (weight) w = hn::Mul(hn::GatherIndex(d, weight, c.j), w);
        sum = hn::Add(sum, hn::IfThenElseZero(c.in, w));
    }
    return hn::GetLane(hn::SumOfLanes(d, sum));
}

void KernelSums(const KernelSumArgs& a, const Index* rows, std::size_t begin, std::size_t end, Real* fluid_sum,
                Real* boundary_sum) {
    hn::ScalableTag<Real> d;
    const KernelV<decltype(d)> k(d, *a.kernel);
    const bool sparse = rows_are_sparse(rows, begin, end);
    for (std::size_t q = begin; q < end; ++q) {
        const Index i = rows ? rows[q] : Index(q);
        prefetch_ahead(*a.fluid, a.x, rows, sparse, q, end);
        const Broadcast3<decltype(d)> xi = broadcast3(d, a.x + 3 * std::size_t(i));
        fluid_sum[q - begin] = kernel_sum(d, k, a.x, xi, a.fluid->of(i).data(), a.fluid->size_of(Index(i)), nullptr);
        if (a.xb)
            boundary_sum[q - begin] =
                kernel_sum(d, k, a.xb, xi, a.boundary->of(i).data(), a.boundary->size_of(Index(i)), a.weight_b);
    }
}
// He eq. 5 plus the delta-SPH term of density_kernels.hpp:
// D_i = m sum_j v_ij . grad W_ij + rho0 sum_b V_b v_ib . grad W_ib
//     + delta h c_s m sum_j (rho_i - rho_j - g_h . x_ij) (x_ij . grad W_ij) / (rho_j (r^2 + 0.01 h^2)).
void ContinuityRates(const ContinuityRateArgs& a, const Index* rows, std::size_t begin, std::size_t end, Real* out) {
    hn::ScalableTag<Real> d;
    using D = decltype(d);
    const KernelV<D> k(d, *a.kernel);
    const auto eps_h2 = hn::Set(d, a.eps_h2);
    const auto ghx = hn::Set(d, a.g_h[0]), ghy = hn::Set(d, a.g_h[1]), ghz = hn::Set(d, a.g_h[2]);
    const bool diffusive = a.diffusion > 0;
    const bool sparse = rows_are_sparse(rows, begin, end);
    for (std::size_t q = begin; q < end; ++q) {
        const Index i = rows ? rows[q] : Index(q);
        prefetch_ahead(*a.fluid, a.x, rows, sparse, q, end);
        const Broadcast3<D> xi = broadcast3(d, a.x + 3 * std::size_t(i));
        const Broadcast3<D> vi = broadcast3(d, a.v + 3 * std::size_t(i));
        const auto rhoi = hn::Set(d, a.rho[i]);
        auto div = hn::Zero(d), diffused = hn::Zero(d);
        const Index* list = a.fluid->of(i).data();
        const std::size_t count = a.fluid->size_of(Index(i));
        for (std::size_t k0 = 0; k0 < count; k0 += hn::Lanes(d)) {
            const PairChunk<D> c = pair_chunk(d, a.x, xi, list, k0, count);
            const auto s = hn::IfThenElseZero(c.in, k.grad_factor(d, hn::Sqrt(c.r2)));  // grad W = x_ij s
            const Broadcast3<D> vj = gather3(d, a.v, c.j3);
            const auto vx = dot3(hn::Sub(vi.x, vj.x), hn::Sub(vi.y, vj.y), hn::Sub(vi.z, vj.z), c.dx, c.dy, c.dz);
            div = hn::MulAdd(vx, s, div);
            if (diffusive) {
                const auto rhoj = hn::GatherIndex(d, a.rho, c.j);
                const auto rho_h = dot3(ghx, ghy, ghz, c.dx, c.dy, c.dz);
                const auto t = hn::Mul(hn::Sub(hn::Sub(rhoi, rhoj), rho_h), hn::Mul(s, c.r2));
                diffused = hn::Add(diffused, hn::Div(t, hn::Mul(rhoj, hn::Add(c.r2, eps_h2))));
            }
        }
        Real total = a.mass * hn::GetLane(hn::SumOfLanes(d, div));
        if (diffusive) total += a.diffusion * a.mass * hn::GetLane(hn::SumOfLanes(d, diffused));
        if (a.xb) {
            auto bdiv = hn::Zero(d);
            const Index* blist = a.boundary->of(i).data();
            const std::size_t bcount = a.boundary->size_of(Index(i));
            for (std::size_t k0 = 0; k0 < bcount; k0 += hn::Lanes(d)) {
                const PairChunk<D> c = pair_chunk(d, a.xb, xi, blist, k0, bcount);
                const auto s = hn::IfThenElseZero(c.in, k.grad_factor(d, hn::Sqrt(c.r2)));
                Broadcast3<D> vib = vi;
                if (a.vel_b) {
                    const Broadcast3<D> vb = gather3(d, a.vel_b, c.j3);
                    vib = {hn::Sub(vi.x, vb.x), hn::Sub(vi.y, vb.y), hn::Sub(vi.z, vb.z)};
                }
                const auto vx = dot3(vib.x, vib.y, vib.z, c.dx, c.dy, c.dz);
                bdiv = hn::MulAdd(hn::Mul(hn::GatherIndex(d, a.volume_b, c.j), vx), s, bdiv);
            }
            total += a.rest_density * hn::GetLane(hn::SumOfLanes(d, bdiv));
        }
        out[q - begin] = total;
    }
}
#else
void KernelSums(const KernelSumArgs&, const Index*, std::size_t, std::size_t, Real*, Real*) {}
void ContinuityRates(const ContinuityRateArgs&, const Index*, std::size_t, std::size_t, Real*) {}
#endif

}  // namespace HWY_NAMESPACE
}  // namespace sph
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace sph {
HWY_EXPORT(KernelSums);
HWY_EXPORT(ContinuityRates);
void continuity_rates_simd(const ContinuityRateArgs& a, const Index* rows, std::size_t begin, std::size_t end,
                           Real* out) {
    HWY_DYNAMIC_DISPATCH(ContinuityRates)(a, rows, begin, end, out);
}
void kernel_sums_simd(const KernelSumArgs& a, const Index* rows, std::size_t begin, std::size_t end, Real* fluid_sum,
                      Real* boundary_sum) {
    HWY_DYNAMIC_DISPATCH(KernelSums)(a, rows, begin, end, fluid_sum, boundary_sum);
}
}  // namespace sph
#endif
