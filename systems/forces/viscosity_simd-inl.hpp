// Monaghan 1992's artificial viscosity Pi_ij (forces_kernels.hpp monaghan_pi) on Highway
// vectors, shared by the vectorised force loops (forces_simd.cpp, dfsph_simd.cpp). Included
// inside the HWY_NAMESPACE of a Highway translation unit (once per compiled target), hence the
// toggle guard instead of #pragma once.
#if defined(SPH_VISCOSITY_SIMD_INL_HPP_) == defined(HWY_TARGET_TOGGLE)
#ifdef SPH_VISCOSITY_SIMD_INL_HPP_
#undef SPH_VISCOSITY_SIMD_INL_HPP_
#else
#define SPH_VISCOSITY_SIMD_INL_HPP_
#endif

#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace sph {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

/// Monaghan's Pi for approaching pairs (v.x < 0), zero otherwise (monaghan_pi): with
/// alpha_2hc = 2 alpha h c_s and rho_sum = rho_i + rho_j, Pi = -(alpha_2hc / rho_sum) v.x / (r^2 + 0.01 h^2).
template <class V>
HWY_INLINE V monaghan(V vx, V r2, V alpha_2hc, V rho_sum, V eps_h2) {
    const V nu = hn::Div(alpha_2hc, rho_sum);
    const V pi = hn::Div(hn::Neg(hn::Mul(nu, vx)), hn::Add(r2, eps_h2));
    return hn::IfThenElseZero(hn::Lt(vx, hn::Zero(hn::DFromV<V>())), pi);
}

}  // namespace HWY_NAMESPACE
}  // namespace sph
HWY_AFTER_NAMESPACE();

#endif  // SPH_VISCOSITY_SIMD_INL_HPP_
