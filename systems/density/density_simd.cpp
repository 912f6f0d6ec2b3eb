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
        fluid_sum[q - begin] = kernel_sum(d, k, a.x, xi, a.fluid->of(i).data(), a.fluid->count[i], nullptr);
        if (a.xb)
            boundary_sum[q - begin] =
                kernel_sum(d, k, a.xb, xi, a.boundary->of(i).data(), a.boundary->count[i], a.weight_b);
    }
}
#else
void KernelSums(const KernelSumArgs&, const Index*, std::size_t, std::size_t, Real*, Real*) {}
#endif

}  // namespace HWY_NAMESPACE
}  // namespace sph
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace sph {
HWY_EXPORT(KernelSums);
void kernel_sums_simd(const KernelSumArgs& a, const Index* rows, std::size_t begin, std::size_t end, Real* fluid_sum,
                      Real* boundary_sum) {
    HWY_DYNAMIC_DISPATCH(KernelSums)(a, rows, begin, end, fluid_sum, boundary_sum);
}
}  // namespace sph
#endif
