// He et al. Alg. 2 line 13: Delta t_i^raw = min(dt_max, lambda_v h / |v_i|, lambda_f sqrt(h / |a_i|),
// lambda_c h / (c_s + |v_i|)) (eq. 6-8 per particle, the acoustic bound when on), StepBound's
// arithmetic across a vector of rows (step_bound_simd.hpp states the exactness contract).
#include "engine/core/simd_targets.hpp"

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "systems/timestep/step_bound_simd.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

#include <climits>
#include <cmath>

#include "systems/timestep/step_bound_simd.hpp"

HWY_BEFORE_NAMESPACE();
namespace sph {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

#ifndef SPH_DOUBLE
/// |x_i| in double of the lanes' rows (xyz floats gathered at 3 i): sqrt(double(x^2 + (y^2 + z^2))),
/// the float squared norm of Eigen's Vector3f::squaredNorm.
template <class DD, class VI>
HWY_INLINE hn::Vec<DD> norm(DD dd, const float* x, VI i3) {
    const hn::Rebind<float, DD> df;
    const auto cx = hn::GatherIndex(df, x, i3);
    const auto cy = hn::GatherIndex(df, x + 1, i3);
    const auto cz = hn::GatherIndex(df, x + 2, i3);
    const auto s = hn::Add(hn::Mul(cx, cx), hn::Add(hn::Mul(cy, cy), hn::Mul(cz, cz)));
    return hn::Sqrt(hn::PromoteTo(dd, s));
}

void StepBounds(const StepBound& b, const Real* v, const Real* a, std::size_t n, const Index* rows, std::size_t begin,
                std::size_t end, double* dt_raw) {
    const hn::ScalableTag<double> dd;
    const hn::Rebind<std::int32_t, decltype(dd)> di;
    const std::size_t N = hn::Lanes(dd);
    std::size_t k = begin;
    // 32-bit gather offsets (3 i): rows beyond INT32_MAX / 3 take the scalar loop below.
    if (n <= std::size_t(INT32_MAX / 3)) {
        const auto cap = hn::Set(dd, b.cap), lambda_vh = hn::Set(dd, b.lambda_vh), lambda_f = hn::Set(dd, b.lambda_f);
        const auto h = hn::Set(dd, b.h), lambda_ch = hn::Set(dd, b.lambda_ch), c_s = hn::Set(dd, b.c_s);
        const auto zero = hn::Zero(dd);
        const auto three = hn::Set(di, 3);
        HWY_ALIGN std::int32_t lanes[hn::MaxLanes(di)];
        HWY_ALIGN double out[hn::MaxLanes(dd)];
        for (; k + N <= end; k += N) {
            hn::Vec<decltype(di)> i;
            if (rows) {
                for (std::size_t l = 0; l < N; ++l) lanes[l] = std::int32_t(rows[k + l]);
                i = hn::Load(di, lanes);
            } else {
                i = hn::Iota(di, std::int32_t(k));
            }
            const auto i3 = hn::Mul(i, three);
            const auto vn = norm(dd, v, i3), an = norm(dd, a, i3);
            // dt = min(dt, q) as std::min(dt, q): q where q < dt (a NaN q keeps dt).
            auto dt = cap;
            const auto qv = hn::Div(lambda_vh, vn);
            dt = hn::IfThenElse(hn::And(hn::Gt(vn, zero), hn::Lt(qv, dt)), qv, dt);
            const auto qa = hn::Mul(lambda_f, hn::Sqrt(hn::Div(h, an)));
            dt = hn::IfThenElse(hn::And(hn::Gt(an, zero), hn::Lt(qa, dt)), qa, dt);
            if (b.acoustic) {
                const auto qc = hn::Div(lambda_ch, hn::Add(c_s, vn));
                dt = hn::IfThenElse(hn::Lt(qc, dt), qc, dt);
            }
            if (rows) {
                hn::Store(dt, dd, out);
                for (std::size_t l = 0; l < N; ++l) dt_raw[rows[k + l]] = out[l];
            } else {
                hn::StoreU(dt, dd, dt_raw + k);
            }
        }
    }
    for (; k < end; ++k) {  // the tail: StepBound itself
        const std::size_t i = rows ? rows[k] : k;
        dt_raw[i] = b.of(Vec3(v[3 * i], v[3 * i + 1], v[3 * i + 2]), Vec3(a[3 * i], a[3 * i + 1], a[3 * i + 2]));
    }
}
#else
void StepBounds(const StepBound&, const Real*, const Real*, std::size_t, const Index*, std::size_t, std::size_t,
                double*) {}
#endif

}  // namespace HWY_NAMESPACE
}  // namespace sph
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace sph {
HWY_EXPORT(StepBounds);
void step_bounds_simd(const StepBound& bound, const Real* v, const Real* a, std::size_t n, const Index* rows,
                      std::size_t begin, std::size_t end, double* dt_raw) {
    HWY_DYNAMIC_DISPATCH(StepBounds)(bound, v, a, n, rows, begin, end, dt_raw);
}
}  // namespace sph
#endif
