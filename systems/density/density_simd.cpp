// He et al. eq. 1 (rho_i = sum_j m_j W_ij, self included) + Akinci et al. 2012 eq. 6
// (+ rho0 sum_b V_b W_ib) and the Tait pressure of He eq. 2, vectorised across each
// particle's neighbour list: 16 (AVX-512) or 8 (AVX2) neighbours per iteration, positions
// gathered from the xyz rows. Compiled per target, chosen at run time (simd.hpp).
#include "engine/core/simd_targets.hpp"

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "systems/density/density_simd.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

#include "engine/core/kernel_simd-inl.hpp"
#include "systems/density/density_kernels.hpp"
#include "systems/density/density_simd.hpp"

HWY_BEFORE_NAMESPACE();
namespace sph {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

#ifndef SPH_DOUBLE
/// sum_j W(|x_i - x_j|) over one list, positions gathered from the xyz rows at `x`.
template <class D>
HWY_INLINE Real kernel_sum(D d, const KernelV<D>& k, const Real* x, const Real* xi, const Index* list,
                           std::size_t count, const Real* weight) {
    const hn::RebindToSigned<D> di;
    const auto vx = hn::Set(d, xi[0]), vy = hn::Set(d, xi[1]), vz = hn::Set(d, xi[2]);
    auto sum = hn::Zero(d);
    for (std::size_t k0 = 0; k0 < count; k0 += hn::Lanes(d)) {
        hn::Mask<decltype(di)> in;
        const auto j = load_neighbours(di, list, k0, count, in);
        const auto j3 = hn::Add(hn::ShiftLeft<1>(j), j);
        const auto dx = hn::Sub(vx, hn::GatherIndex(d, x, j3));
        const auto dy = hn::Sub(vy, hn::GatherIndex(d, x + 1, j3));
        const auto dz = hn::Sub(vz, hn::GatherIndex(d, x + 2, j3));
        auto w = k.w(d, hn::Sqrt(norm2(dx, dy, dz)));
        if (weight) w = hn::Mul(hn::GatherIndex(d, weight, j), w);
        sum = hn::Add(sum, hn::IfThenElseZero(hn::RebindMask(d, in), w));
    }
    return hn::GetLane(hn::SumOfLanes(d, sum));
}

void DensityRows(const DensityPairArgs& a, const Index* rows, std::size_t begin, std::size_t end) {
    hn::ScalableTag<Real> d;
    const KernelV<decltype(d)> k(d, *a.kernel);
    for (std::size_t q = begin; q < end; ++q) {
        const Index i = rows ? rows[q] : Index(q);
        const Real* xi = a.x + 3 * std::size_t(i);
        const Real sum = kernel_sum(d, k, a.x, xi, a.fluid->of(i).data(), a.fluid->count[i], nullptr);
        Real bsum = 0;
        if (a.xb) bsum = kernel_sum(d, k, a.xb, xi, a.boundary->of(i).data(), a.boundary->count[i], a.volume_b);
        const Real rho = a.self + a.mass * sum + a.rest_density * bsum;
        a.rho[i] = rho;
        a.pressure[i] = tait_pressure(rho, a.rest_density, a.tait_b);
        if (a.rho_last) a.rho_last[i] = rho;
    }
}
#else
void DensityRows(const DensityPairArgs&, const Index*, std::size_t, std::size_t) {}
#endif

}  // namespace HWY_NAMESPACE
}  // namespace sph
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace sph {
HWY_EXPORT(DensityRows);
void density_rows_simd(const DensityPairArgs& a, const Index* rows, std::size_t begin, std::size_t end) {
    HWY_DYNAMIC_DISPATCH(DensityRows)(a, rows, begin, end);
}
}  // namespace sph
#endif
