// He et al. eq. 4, a_i = -sum_j m_j (p_i/rho_i^2 + p_j/rho_j^2 + Pi_ij) grad W_ij + g, with
// Monaghan 1992's Pi_ij (forces_kernels.hpp), the Akinci et al. 2012 eq. 10 boundary term with
// pressure mirroring, -sum_b psi_b (2 p_i/rho_i^2 + Pi_ib) grad W_ib (psi_b = rho0 V_b,
// Pi_ib with rho_b = rho0 and v_ib = v_i - v_b), and He eq. 5's drho_i/dt =
// sum_j m_j v_ij . grad W_ij + sum_b psi_b v_ib . grad W_ib: the formulas of forces_system.cpp,
// vectorised across each particle's neighbour list (positions, velocities, densities and
// pressures gathered). p_i / rho_i^2 is hoisted out of the pair loop.
#include "engine/core/simd_targets.hpp"

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "systems/forces/forces_simd.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

#include "engine/core/kernel_simd-inl.hpp"
#include "systems/forces/forces_simd.hpp"

HWY_BEFORE_NAMESPACE();
namespace sph {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

#ifndef SPH_DOUBLE
template <class D>
struct Gathered3 {
    hn::Vec<D> x, y, z;
};
template <class D, class VI>
HWY_INLINE Gathered3<D> gather3(D d, const Real* base, VI j3) {
    return {hn::GatherIndex(d, base, j3), hn::GatherIndex(d, base + 1, j3), hn::GatherIndex(d, base + 2, j3)};
}

/// Monaghan's Pi for approaching pairs (v.x < 0), zero otherwise (monaghan_pi).
template <class V>
HWY_INLINE V monaghan(V vx, V r2, V alpha_2hc, V rho_sum, V eps_h2) {
    const V nu = hn::Div(alpha_2hc, rho_sum);
    const V pi = hn::Div(hn::Neg(hn::Mul(nu, vx)), hn::Add(r2, eps_h2));
    return hn::IfThenElseZero(hn::Lt(vx, hn::Zero(hn::DFromV<V>())), pi);
}

void ForceRows(const ForcePairArgs& a, const Index* rows, std::size_t begin, std::size_t end) {
    hn::ScalableTag<Real> d;
    hn::RebindToSigned<decltype(d)> di;
    const KernelV<decltype(d)> k(d, *a.kernel);
    const auto m = hn::Set(d, a.mass);
    const auto rho0 = hn::Set(d, a.rest_density);
    const auto eps_h2 = hn::Set(d, Real(0.01) * a.h * a.h);
    // 2 alpha h c_s of monaghan_pi's nu = 2 alpha h c_s / (rho_i + rho_j), as it multiplies.
    const auto alpha_2hc = hn::Set(d, Real(2) * a.alpha * a.h * a.speed_of_sound);
    const auto alpha_b_2hc = hn::Set(d, Real(2) * a.alpha_b * a.h * a.speed_of_sound);
    const bool viscous = a.alpha > 0, viscous_b = a.alpha_b > 0;
    for (std::size_t q = begin; q < end; ++q) {
        const Index i = rows ? rows[q] : Index(q);
        const Real* xi = a.x + 3 * std::size_t(i);
        const Real* vi = a.v + 3 * std::size_t(i);
        const Real rhoi = a.rho[i];
        const Real pi_s = a.p[i] / (rhoi * rhoi);
        const auto pi = hn::Set(d, pi_s);
        const auto vrhoi = hn::Set(d, rhoi);
        const auto xix = hn::Set(d, xi[0]), xiy = hn::Set(d, xi[1]), xiz = hn::Set(d, xi[2]);
        const auto vix = hn::Set(d, vi[0]), viy = hn::Set(d, vi[1]), viz = hn::Set(d, vi[2]);
        auto ax = hn::Zero(d), ay = hn::Zero(d), az = hn::Zero(d), div = hn::Zero(d);
        const Index* list = a.fluid->of(i).data();
        const std::size_t count = a.fluid->count[i];
        for (std::size_t k0 = 0; k0 < count; k0 += hn::Lanes(d)) {
            hn::Mask<decltype(di)> in_i;
            const auto j = load_neighbours(di, list, k0, count, in_i);
            const auto in = hn::RebindMask(d, in_i);
            const auto j3 = hn::Add(hn::ShiftLeft<1>(j), j);
            const auto xj = gather3(d, a.x, j3);
            const auto dx = hn::Sub(xix, xj.x), dy = hn::Sub(xiy, xj.y), dz = hn::Sub(xiz, xj.z);
            const auto r2 = norm2(dx, dy, dz);
            // Masked lanes get a zero gradient, so they add nothing below.
            const auto s = hn::IfThenElseZero(in, k.grad_factor(d, hn::Sqrt(r2)));
            const auto gx = hn::Mul(dx, s), gy = hn::Mul(dy, s), gz = hn::Mul(dz, s);
            const auto vj = gather3(d, a.v, j3);
            const auto vx = hn::Sub(vix, vj.x), vy = hn::Sub(viy, vj.y), vz = hn::Sub(viz, vj.z);
            const auto rhoj = hn::GatherIndex(d, a.rho, j);
            const auto pj = hn::GatherIndex(d, a.p, j);
            auto coef = hn::Add(pi, hn::Div(pj, hn::Mul(rhoj, rhoj)));
            if (viscous)
                coef = hn::Add(coef, monaghan(dot3(vx, vy, vz, dx, dy, dz), r2, alpha_2hc, hn::Add(vrhoi, rhoj), eps_h2));
            // Masked lanes read row 0, whose values may be anything: their coefficient is zeroed
            // (a zero gradient alone would give 0 * inf = NaN).
            coef = hn::IfThenElseZero(in, hn::Mul(m, coef));
            ax = hn::NegMulAdd(coef, gx, ax);
            ay = hn::NegMulAdd(coef, gy, ay);
            az = hn::NegMulAdd(coef, gz, az);
            if (a.drho) div = hn::MulAdd(m, dot3(vx, vy, vz, gx, gy, gz), div);  // gx.. are 0 in masked lanes
        }
        if (a.xb) {
            const Index* blist = a.boundary->of(i).data();
            const std::size_t bcount = a.boundary->count[i];
            const auto two_pi = hn::Set(d, Real(2) * pi_s);
            for (std::size_t k0 = 0; k0 < bcount; k0 += hn::Lanes(d)) {
                hn::Mask<decltype(di)> in_i;
                const auto b = load_neighbours(di, blist, k0, bcount, in_i);
                const auto in = hn::RebindMask(d, in_i);
                const auto b3 = hn::Add(hn::ShiftLeft<1>(b), b);
                const auto xb = gather3(d, a.xb, b3);
                const auto dx = hn::Sub(xix, xb.x), dy = hn::Sub(xiy, xb.y), dz = hn::Sub(xiz, xb.z);
                const auto r2 = norm2(dx, dy, dz);
                const auto s = hn::IfThenElseZero(in, k.grad_factor(d, hn::Sqrt(r2)));
                const auto gx = hn::Mul(dx, s), gy = hn::Mul(dy, s), gz = hn::Mul(dz, s);
                auto vx = vix, vy = viy, vz = viz;  // relative velocity v_i - v_b
                if (a.vel_b) {
                    const auto vb = gather3(d, a.vel_b, b3);
                    vx = hn::Sub(vix, vb.x);
                    vy = hn::Sub(viy, vb.y);
                    vz = hn::Sub(viz, vb.z);
                }
                auto coef = two_pi;
                if (viscous_b)
                    coef = hn::Add(coef, monaghan(dot3(vx, vy, vz, dx, dy, dz), r2, alpha_b_2hc, hn::Add(vrhoi, rho0), eps_h2));
                const auto psi = hn::Mul(rho0, hn::GatherIndex(d, a.volume_b, b));
                coef = hn::IfThenElseZero(in, hn::Mul(psi, coef));
                ax = hn::NegMulAdd(coef, gx, ax);
                ay = hn::NegMulAdd(coef, gy, ay);
                az = hn::NegMulAdd(coef, gz, az);
                if (a.drho) div = hn::MulAdd(psi, dot3(vx, vy, vz, gx, gy, gz), div);
            }
        }
        Real* acc = a.acc + 3 * std::size_t(i);
        acc[0] = hn::GetLane(hn::SumOfLanes(d, ax)) + a.gravity[0];
        acc[1] = hn::GetLane(hn::SumOfLanes(d, ay)) + a.gravity[1];
        acc[2] = hn::GetLane(hn::SumOfLanes(d, az)) + a.gravity[2];
        if (a.drho) a.drho[i] = hn::GetLane(hn::SumOfLanes(d, div));
    }
}

// Ihmsen et al. 2010 eq. 6: a_i = -sum_j m (p_i/rho_i^2 + p_j/rho_j^2) grad W_ij
//                                 -sum_b m_b (p_i/rho_i^2 + p_b/rho_b^2) grad W_ib.
void PressureForceRows(const PressurePairArgs& a, std::size_t begin, std::size_t end) {
    hn::ScalableTag<Real> d;
    hn::RebindToSigned<decltype(d)> di;
    const KernelV<decltype(d)> k(d, *a.kernel);
    const auto m = hn::Set(d, a.mass);
    for (std::size_t i = begin; i < end; ++i) {
        const Real* xi = a.x + 3 * i;
        const auto pi = hn::Set(d, a.p_term[i]);
        const auto xix = hn::Set(d, xi[0]), xiy = hn::Set(d, xi[1]), xiz = hn::Set(d, xi[2]);
        auto ax = hn::Zero(d), ay = hn::Zero(d), az = hn::Zero(d);
        // term(j): p_j / rho_j^2 of neighbour lanes j; weight(j): m_j.
        auto pairs = [&](const Real* xs, const NeighbourLists& lists, auto&& term, auto&& weight) {
            const Index* list = lists.of(Index(i)).data();
            const std::size_t count = lists.count[i];
            for (std::size_t k0 = 0; k0 < count; k0 += hn::Lanes(d)) {
                hn::Mask<decltype(di)> in_i;
                const auto j = load_neighbours(di, list, k0, count, in_i);
                const auto in = hn::RebindMask(d, in_i);
                const auto j3 = hn::Add(hn::ShiftLeft<1>(j), j);
                const auto xj = gather3(d, xs, j3);
                const auto dx = hn::Sub(xix, xj.x), dy = hn::Sub(xiy, xj.y), dz = hn::Sub(xiz, xj.z);
                const auto s = hn::IfThenElseZero(in, k.grad_factor(d, hn::Sqrt(norm2(dx, dy, dz))));
                // Masked lanes read row 0 (a boundary particle out of the active set has rho = 0,
                // so p/rho^2 is NaN there): their coefficient is zeroed, not only their gradient.
                const auto coef = hn::IfThenElseZero(in, hn::Mul(weight(j), hn::Add(pi, term(j))));
                ax = hn::NegMulAdd(coef, hn::Mul(dx, s), ax);
                ay = hn::NegMulAdd(coef, hn::Mul(dy, s), ay);
                az = hn::NegMulAdd(coef, hn::Mul(dz, s), az);
            }
        };
        pairs(a.x, *a.fluid, [&](auto j) { return hn::GatherIndex(d, a.p_term, j); }, [&](auto) { return m; });
        if (a.xb)
            pairs(
                a.xb, *a.boundary,
                [&](auto j) {
                    const auto rho = hn::GatherIndex(d, a.rho_b, j);
                    return hn::Div(hn::GatherIndex(d, a.p_b, j), hn::Mul(rho, rho));
                },
                [&](auto j) { return hn::GatherIndex(d, a.mass_b, j); });
        Real* acc = a.acc + 3 * i;
        acc[0] = hn::GetLane(hn::SumOfLanes(d, ax));
        acc[1] = hn::GetLane(hn::SumOfLanes(d, ay));
        acc[2] = hn::GetLane(hn::SumOfLanes(d, az));
    }
}

// Becker & Teschner 2007 eq. 10-11 (nu = 2 alpha h c_s / (2 rho0)) and eq. 13:
// a_i = -sum_j m Pi_ij grad W_ij - kappa sum_j W_ij x_ij - sum_b rho0 V_b Pi_ib grad W_ib.
void NonpressureRows(const NonpressurePairArgs& a, std::size_t begin, std::size_t end) {
    hn::ScalableTag<Real> d;
    hn::RebindToSigned<decltype(d)> di;
    const KernelV<decltype(d)> k(d, *a.kernel);
    const auto m = hn::Set(d, a.mass);
    const auto rho0 = hn::Set(d, a.rest_density);
    const auto rho_sum = hn::Set(d, a.rest_density + a.rest_density);
    const auto eps_h2 = hn::Set(d, Real(0.01) * a.h * a.h);
    const auto alpha_2hc = hn::Set(d, Real(2) * a.alpha * a.h * a.speed_of_sound);
    const auto kappa = hn::Set(d, a.kappa);
    const bool viscous = a.alpha > 0, cohesive = a.kappa > 0;
    for (std::size_t i = begin; i < end; ++i) {
        const Real* xi = a.x + 3 * i;
        const Real* vi = a.v + 3 * i;
        const auto xix = hn::Set(d, xi[0]), xiy = hn::Set(d, xi[1]), xiz = hn::Set(d, xi[2]);
        const auto vix = hn::Set(d, vi[0]), viy = hn::Set(d, vi[1]), viz = hn::Set(d, vi[2]);
        auto ax = hn::Zero(d), ay = hn::Zero(d), az = hn::Zero(d);
        const Index* list = a.fluid->of(Index(i)).data();
        const std::size_t count = a.fluid->count[i];
        for (std::size_t k0 = 0; k0 < count; k0 += hn::Lanes(d)) {
            hn::Mask<decltype(di)> in_i;
            const auto j = load_neighbours(di, list, k0, count, in_i);
            const auto in = hn::RebindMask(d, in_i);
            const auto j3 = hn::Add(hn::ShiftLeft<1>(j), j);
            const auto xj = gather3(d, a.x, j3);
            const auto dx = hn::Sub(xix, xj.x), dy = hn::Sub(xiy, xj.y), dz = hn::Sub(xiz, xj.z);
            const auto r2 = norm2(dx, dy, dz);
            const auto r = hn::Sqrt(r2);
            if (viscous) {
                const auto vj = gather3(d, a.v, j3);
                const auto vx = dot3(hn::Sub(vix, vj.x), hn::Sub(viy, vj.y), hn::Sub(viz, vj.z), dx, dy, dz);
                const auto coef = hn::IfThenElseZero(in, hn::Mul(m, monaghan(vx, r2, alpha_2hc, rho_sum, eps_h2)));
                const auto s = hn::IfThenElseZero(in, k.grad_factor(d, r));
                ax = hn::NegMulAdd(coef, hn::Mul(dx, s), ax);
                ay = hn::NegMulAdd(coef, hn::Mul(dy, s), ay);
                az = hn::NegMulAdd(coef, hn::Mul(dz, s), az);
            }
            if (cohesive) {
                const auto cw = hn::IfThenElseZero(in, hn::Mul(kappa, k.w(d, r)));
                ax = hn::NegMulAdd(cw, dx, ax);
                ay = hn::NegMulAdd(cw, dy, ay);
                az = hn::NegMulAdd(cw, dz, az);
            }
        }
        if (a.xb && viscous) {
            const Index* blist = a.boundary->of(Index(i)).data();
            const std::size_t bcount = a.boundary->count[i];
            for (std::size_t k0 = 0; k0 < bcount; k0 += hn::Lanes(d)) {
                hn::Mask<decltype(di)> in_i;
                const auto b = load_neighbours(di, blist, k0, bcount, in_i);
                const auto in = hn::RebindMask(d, in_i);
                const auto b3 = hn::Add(hn::ShiftLeft<1>(b), b);
                const auto xb = gather3(d, a.xb, b3);
                const auto dx = hn::Sub(xix, xb.x), dy = hn::Sub(xiy, xb.y), dz = hn::Sub(xiz, xb.z);
                const auto r2 = norm2(dx, dy, dz);
                auto vx = vix, vy = viy, vz = viz;  // relative velocity v_i - v_b
                if (a.vel_b) {
                    const auto vb = gather3(d, a.vel_b, b3);
                    vx = hn::Sub(vix, vb.x);
                    vy = hn::Sub(viy, vb.y);
                    vz = hn::Sub(viz, vb.z);
                }
                const auto psi = hn::Mul(rho0, hn::GatherIndex(d, a.volume_b, b));
                const auto coef = hn::IfThenElseZero(
                    in, hn::Mul(psi, monaghan(dot3(vx, vy, vz, dx, dy, dz), r2, alpha_2hc, rho_sum, eps_h2)));
                const auto s = hn::IfThenElseZero(in, k.grad_factor(d, hn::Sqrt(r2)));
                ax = hn::NegMulAdd(coef, hn::Mul(dx, s), ax);
                ay = hn::NegMulAdd(coef, hn::Mul(dy, s), ay);
                az = hn::NegMulAdd(coef, hn::Mul(dz, s), az);
            }
        }
        Real* acc = a.acc + 3 * i;
        acc[0] = hn::GetLane(hn::SumOfLanes(d, ax));
        acc[1] = hn::GetLane(hn::SumOfLanes(d, ay));
        acc[2] = hn::GetLane(hn::SumOfLanes(d, az));
    }
}
#else
void ForceRows(const ForcePairArgs&, const Index*, std::size_t, std::size_t) {}
void PressureForceRows(const PressurePairArgs&, std::size_t, std::size_t) {}
void NonpressureRows(const NonpressurePairArgs&, std::size_t, std::size_t) {}
#endif

}  // namespace HWY_NAMESPACE
}  // namespace sph
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace sph {
HWY_EXPORT(ForceRows);
HWY_EXPORT(PressureForceRows);
HWY_EXPORT(NonpressureRows);
void nonpressure_rows_simd(const NonpressurePairArgs& a, std::size_t begin, std::size_t end) {
    HWY_DYNAMIC_DISPATCH(NonpressureRows)(a, begin, end);
}
void force_rows_simd(const ForcePairArgs& a, const Index* rows, std::size_t begin, std::size_t end) {
    HWY_DYNAMIC_DISPATCH(ForceRows)(a, rows, begin, end);
}
void pressure_force_rows_simd(const PressurePairArgs& a, std::size_t begin, std::size_t end) {
    HWY_DYNAMIC_DISPATCH(PressureForceRows)(a, begin, end);
}
}  // namespace sph
#endif
