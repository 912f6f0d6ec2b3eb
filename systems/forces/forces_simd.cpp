// He et al. eq. 4, a_i = -sum_j m_j (p_i/rho_i^2 + p_j/rho_j^2 + Pi_ij) grad W_ij + g, with
// Monaghan 1992's Pi_ij (forces_kernels.hpp), Akinci et al. 2012's boundary volumes in the pair with
// the wall's pressure mirroring the fluid's (twice Akinci eq. 10's single term), -sum_b psi_b (2 p_i/rho_i^2 + Pi_ib) grad W_ib (psi_b = rho0 V_b; with
// extrapolated walls p_i/rho_i^2 + p_b/rho_b^2, Adami et al. 2012 eq. 27,
// Pi_ib with rho_b = rho0 and v_ib = v_i - v_b), and He eq. 5's drho_i/dt =
// sum_j m_j v_ij . grad W_ij + sum_b psi_b v_ib . grad W_ib: the formulas of forces_system.cpp,
// vectorised across each particle's neighbour list (positions, velocities, densities and
// pressures gathered). p_i / rho_i^2 is hoisted out of the pair loop. With the corrected
// gradient (Bonet & Lok 1999), -m_j P_ij (L_i + L_j)/2 grad W_ij splits into an L_j half per
// pair (L_j gathered) and an L_i half applied once per row to the summed P_ij grad W_ij; against
// the boundary, psi_b P_ib L_i grad W_ib joins that sum (P: the pressure coefficient).
#include "engine/core/simd_targets.hpp"

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "systems/forces/forces_simd.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

#include "engine/core/kernel_simd-inl.hpp"
#include "systems/forces/viscosity_simd-inl.hpp"
#include "systems/forces/forces_simd.hpp"

HWY_BEFORE_NAMESPACE();
namespace sph {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

#ifndef SPH_DOUBLE
/// a -= coef (x_ij s) per component; returns x_ij s (grad W_ij). Masked lanes must carry a zero
/// coefficient *and* a zero s: they read row 0, whose values may be anything (a zero gradient
/// alone would give 0 * inf = NaN; an inactive PCISPH boundary particle has p/rho^2 = NaN).
template <class D>
HWY_INLINE Broadcast3<D> subtract_along_gradient(const PairChunk<D>& c, hn::Vec<D> s, hn::Vec<D> coef,
                                                 Broadcast3<D>& a) {
    const Broadcast3<D> g{hn::Mul(c.dx, s), hn::Mul(c.dy, s), hn::Mul(c.dz, s)};
    a.x = hn::NegMulAdd(coef, g.x, a.x);
    a.y = hn::NegMulAdd(coef, g.y, a.y);
    a.z = hn::NegMulAdd(coef, g.z, a.z);
    return g;
}

/// Writes the lane sums of a (plus g) to the xyz row `out`.
template <class D>
HWY_INLINE void store_sum3(D d, const Broadcast3<D>& a, const Real* g, Real* out) {
    out[0] = hn::GetLane(hn::SumOfLanes(d, a.x)) + (g ? g[0] : Real(0));
    out[1] = hn::GetLane(hn::SumOfLanes(d, a.y)) + (g ? g[1] : Real(0));
    out[2] = hn::GetLane(hn::SumOfLanes(d, a.z)) + (g ? g[2] : Real(0));
}

/// sum += w g per component.
template <class D>
HWY_INLINE void add_times(hn::Vec<D> w, const Broadcast3<D>& g, Broadcast3<D>& sum) {
    sum.x = hn::MulAdd(w, g.x, sum.x);
    sum.y = hn::MulAdd(w, g.y, sum.y);
    sum.z = hn::MulAdd(w, g.z, sum.z);
}

/// L_j g of the chunk's neighbours, L_j gathered from 9 Reals per particle (column-major:
/// (L g)_r = sum_c L[3 c + r] g_c).
template <class D>
HWY_INLINE Broadcast3<D> gathered_times(D d, const Real* L, const PairChunk<D>& c, const Broadcast3<D>& g) {
    const auto j9 = hn::Add(hn::ShiftLeft<1>(c.j3), c.j3);
    const auto l = [&](int k) { return hn::GatherIndex(d, L + k, j9); };
    return {hn::MulAdd(l(0), g.x, hn::MulAdd(l(3), g.y, hn::Mul(l(6), g.z))),
            hn::MulAdd(l(1), g.x, hn::MulAdd(l(4), g.y, hn::Mul(l(7), g.z))),
            hn::MulAdd(l(2), g.x, hn::MulAdd(l(5), g.y, hn::Mul(l(8), g.z)))};
}

/// v_i - v_j of the chunk's neighbours (velocities gathered from the xyz rows at `v`; none: v_i).
template <class D>
HWY_INLINE Broadcast3<D> relative_velocity(D d, const Broadcast3<D>& vi, const Real* v, const PairChunk<D>& c) {
    if (!v) return vi;
    const Broadcast3<D> vj = gather3(d, v, c.j3);
    return {hn::Sub(vi.x, vj.x), hn::Sub(vi.y, vj.y), hn::Sub(vi.z, vj.z)};
}

void ForceRows(const ForcePairArgs& a, const Index* rows, std::size_t begin, std::size_t end) {
    hn::ScalableTag<Real> d;
    using D = decltype(d);
    const KernelV<D> k(d, *a.kernel);
    const auto m = hn::Set(d, a.mass);
    const auto rho0 = hn::Set(d, a.rest_density);
    const auto eps_h2 = hn::Set(d, Real(0.01) * a.h * a.h);
    // 2 alpha h c_s of monaghan_pi's nu = 2 alpha h c_s / (rho_i + rho_j), as it multiplies.
    const auto alpha_2hc = hn::Set(d, Real(2) * a.alpha * a.h * a.speed_of_sound);
    const auto alpha_b_2hc = hn::Set(d, Real(2) * a.alpha_b * a.h * a.speed_of_sound);
    const bool viscous = a.alpha > 0, viscous_b = a.alpha_b > 0;
    const bool laminar = a.nu4 > 0, laminar_b = laminar && a.alpha_b_laminar;
    const auto nu4 = hn::Set(d, a.nu4);
    const bool corrected = a.L != nullptr;
    const auto half_m = hn::Set(d, Real(0.5) * a.mass);
    const bool sparse = rows_are_sparse(rows, begin, end);
    for (std::size_t q = begin; q < end; ++q) {
        const Index i = rows ? rows[q] : Index(q);
        prefetch_ahead(*a.fluid, a.x, rows, sparse, q, end);
        const Broadcast3<D> xi = broadcast3(d, a.x + 3 * std::size_t(i));
        const Broadcast3<D> vi = broadcast3(d, a.v + 3 * std::size_t(i));
        const Real rhoi = a.rho[i];
        const Real pi_s = a.p[i] / (rhoi * rhoi);  // hoisted: p_i / rho_i^2
        const auto pi = hn::Set(d, pi_s);
        const auto vrhoi = hn::Set(d, rhoi);
        Broadcast3<D> acc{hn::Zero(d), hn::Zero(d), hn::Zero(d)};
        Broadcast3<D> li_sum{hn::Zero(d), hn::Zero(d), hn::Zero(d)};  // corrected: what L_i multiplies
        auto div = hn::Zero(d);
        const Index* list = a.fluid->of(i).data();
        const std::size_t count = a.fluid->size_of(Index(i));
        for (std::size_t k0 = 0; k0 < count; k0 += hn::Lanes(d)) {
            const PairChunk<D> c = pair_chunk(d, a.x, xi, list, k0, count);
            const auto s = hn::IfThenElseZero(c.in, k.grad_factor(d, hn::Sqrt(c.r2)));
            const Broadcast3<D> vij = relative_velocity(d, vi, a.v, c);
            const auto rhoj = hn::GatherIndex(d, a.rho, c.j);
            const auto pcoef = hn::Add(pi, hn::Div(hn::GatherIndex(d, a.p, c.j), hn::Mul(rhoj, rhoj)));
            const auto visc = viscous ? monaghan(dot3(vij.x, vij.y, vij.z, c.dx, c.dy, c.dz), c.r2, alpha_2hc,
                                                 hn::Add(vrhoi, rhoj), eps_h2)
                                      : hn::Zero(d);
            Broadcast3<D> g;
            if (!corrected) {
                g = subtract_along_gradient(c, s, hn::IfThenElseZero(c.in, hn::Mul(m, hn::Add(pcoef, visc))), acc);
            } else {
                // the viscosity along grad W_ij; m P_ij / 2 times L_j grad W_ij here, times L_i later
                g = subtract_along_gradient(c, s, hn::IfThenElseZero(c.in, hn::Mul(m, visc)), acc);
                const auto w = hn::IfThenElseZero(c.in, hn::Mul(half_m, pcoef));
                const Broadcast3<D> lg = gathered_times(d, a.L, c, g);
                acc.x = hn::NegMulAdd(w, lg.x, acc.x);
                acc.y = hn::NegMulAdd(w, lg.y, acc.y);
                acc.z = hn::NegMulAdd(w, lg.z, acc.z);
                add_times(w, g, li_sum);
            }
            if (a.drho) div = hn::MulAdd(m, dot3(vij.x, vij.y, vij.z, g.x, g.y, g.z), div);
            if (laminar) {  // a += m 4 nu (x_ij . grad W_ij) / ((rho_i + rho_j)(r^2 + eps)) v_ij
                const auto lam = hn::Div(hn::Mul(m, hn::Mul(nu4, hn::Mul(s, c.r2))),
                                         hn::Mul(hn::Add(vrhoi, rhoj), hn::Add(c.r2, eps_h2)));
                add_times(lam, vij, acc);
            }
        }
        if (a.xb) {
            const Index* blist = a.boundary->of(i).data();
            const std::size_t bcount = a.boundary->size_of(Index(i));
            const auto two_pi = hn::Set(d, Real(2) * pi_s);
            for (std::size_t k0 = 0; k0 < bcount; k0 += hn::Lanes(d)) {
                const PairChunk<D> c = pair_chunk(d, a.xb, xi, blist, k0, bcount);
                const auto s = hn::IfThenElseZero(c.in, k.grad_factor(d, hn::Sqrt(c.r2)));
                const Broadcast3<D> vib = relative_velocity(d, vi, a.vel_b, c);  // v_i - v_b
                auto coef = two_pi;
                if (a.p_b) {  // p_i / rho_i^2 + p_b / rho_b^2 (extrapolated walls)
                    const auto rb = hn::GatherIndex(d, a.rho_b, c.j);
                    coef = hn::Add(hn::Set(d, pi_s), hn::Div(hn::GatherIndex(d, a.p_b, c.j), hn::Mul(rb, rb)));
                }
                const auto visc = viscous_b ? monaghan(dot3(vib.x, vib.y, vib.z, c.dx, c.dy, c.dz), c.r2,
                                                       alpha_b_2hc, hn::Add(vrhoi, rho0), eps_h2)
                                            : hn::Zero(d);
                const auto psi = hn::Mul(rho0, hn::GatherIndex(d, a.volume_b, c.j));
                Broadcast3<D> g;
                if (!corrected) {
                    g = subtract_along_gradient(c, s, hn::IfThenElseZero(c.in, hn::Mul(psi, hn::Add(coef, visc))), acc);
                } else {  // psi P_ib L_i grad W_ib: into the sum L_i multiplies
                    g = subtract_along_gradient(c, s, hn::IfThenElseZero(c.in, hn::Mul(psi, visc)), acc);
                    const auto w = hn::IfThenElseZero(c.in, hn::Mul(psi, coef));
                    add_times(w, g, li_sum);
                }
                if (a.drho) div = hn::MulAdd(psi, dot3(vib.x, vib.y, vib.z, g.x, g.y, g.z), div);
                if (laminar_b) {  // no-slip walls: psi 4 nu xgrad / ((rho_i + rho0)(r^2 + eps)) v_ib
                    const auto lam = hn::Div(hn::Mul(psi, hn::Mul(nu4, hn::Mul(s, c.r2))),
                                             hn::Mul(hn::Add(vrhoi, rho0), hn::Add(c.r2, eps_h2)));
                    add_times(lam, vib, acc);
                }
            }
        }
        store_sum3(d, acc, a.gravity, a.acc + 3 * std::size_t(i));
        if (corrected) {  // a_i -= L_i (sum of the pressure terms' P grad W)
            Real sum[3];
            store_sum3(d, li_sum, nullptr, sum);
            const Real* Li = a.L + 9 * std::size_t(i);
            Real* out = a.acc + 3 * std::size_t(i);
            for (int r = 0; r < 3; ++r) out[r] -= Li[r] * sum[0] + Li[3 + r] * sum[1] + Li[6 + r] * sum[2];
        }
        if (a.drho) a.drho[i] = hn::GetLane(hn::SumOfLanes(d, div));
    }
}

// Bonet & Lok 1999: M_i = -sum_j V_j s_ij x_ij x_ij^T (grad W_ij = s_ij x_ij), V_j = m / rho_j
// for fluid neighbours and V_b for boundary ones; six lane sums, mirrored into the Mat3.
void MomentRows(const MomentPairArgs& a, const Index* rows, std::size_t begin, std::size_t end) {
    hn::ScalableTag<Real> d;
    using D = decltype(d);
    using V = hn::Vec<D>;
    const KernelV<D> k(d, *a.kernel);
    const auto m = hn::Set(d, a.mass);
    const bool sparse = rows_are_sparse(rows, begin, end);
    for (std::size_t q = begin; q < end; ++q) {
        const Index i = rows ? rows[q] : Index(q);
        prefetch_ahead(*a.fluid, a.x, rows, sparse, q, end);
        const Broadcast3<D> xi = broadcast3(d, a.x + 3 * std::size_t(i));
        V xx = hn::Zero(d), xy = xx, xz = xx, yy = xx, yz = xx, zz = xx;
        // M -= w x_ij x_ij^T for one chunk, w = V_j s_ij (zero on masked lanes).
        const auto subtract = [&](const PairChunk<D>& c, V w) {
            const V wx = hn::Mul(w, c.dx), wy = hn::Mul(w, c.dy), wz = hn::Mul(w, c.dz);
            xx = hn::NegMulAdd(wx, c.dx, xx);
            xy = hn::NegMulAdd(wx, c.dy, xy);
            xz = hn::NegMulAdd(wx, c.dz, xz);
            yy = hn::NegMulAdd(wy, c.dy, yy);
            yz = hn::NegMulAdd(wy, c.dz, yz);
            zz = hn::NegMulAdd(wz, c.dz, zz);
        };
        const Index* list = a.fluid->of(i).data();
        const std::size_t count = a.fluid->size_of(i);
        for (std::size_t k0 = 0; k0 < count; k0 += hn::Lanes(d)) {
            const PairChunk<D> c = pair_chunk(d, a.x, xi, list, k0, count);
            const V s = k.grad_factor(d, hn::Sqrt(c.r2));
            subtract(c, hn::IfThenElseZero(c.in, hn::Mul(hn::Div(m, hn::GatherIndex(d, a.rho, c.j)), s)));
        }
        if (a.xb) {
            const Index* blist = a.boundary->of(i).data();
            const std::size_t bcount = a.boundary->size_of(i);
            for (std::size_t k0 = 0; k0 < bcount; k0 += hn::Lanes(d)) {
                const PairChunk<D> c = pair_chunk(d, a.xb, xi, blist, k0, bcount);
                const V s = k.grad_factor(d, hn::Sqrt(c.r2));
                subtract(c, hn::IfThenElseZero(c.in, hn::Mul(hn::GatherIndex(d, a.volume_b, c.j), s)));
            }
        }
        const auto sum = [&](V v) { return hn::GetLane(hn::SumOfLanes(d, v)); };
        Mat3& M = a.moment[i];
        M(0, 0) = sum(xx);
        M(1, 1) = sum(yy);
        M(2, 2) = sum(zz);
        M(0, 1) = M(1, 0) = sum(xy);
        M(0, 2) = M(2, 0) = sum(xz);
        M(1, 2) = M(2, 1) = sum(yz);
    }
}

// Ihmsen et al. 2010 eq. 6: a_i = -sum_j m (p_i/rho_i^2 + p_j/rho_j^2) grad W_ij
//                                 -sum_b m_b (p_i/rho_i^2 + p_b/rho_b^2) grad W_ib.
void PressureForceRows(const PressurePairArgs& a, std::size_t begin, std::size_t end) {
    hn::ScalableTag<Real> d;
    using D = decltype(d);
    const KernelV<D> k(d, *a.kernel);
    const auto m = hn::Set(d, a.mass);
    for (std::size_t i = begin; i < end; ++i) {
        const Broadcast3<D> xi = broadcast3(d, a.x + 3 * i);
        const auto pi = hn::Set(d, a.p_term[i]);
        Broadcast3<D> acc{hn::Zero(d), hn::Zero(d), hn::Zero(d)};
        // term(j): p_j / rho_j^2 of the chunk's neighbours; weight(j): m_j.
        auto pairs = [&](const Real* xs, const NeighbourLists& lists, auto&& term, auto&& weight) {
            const Index* list = lists.of(Index(i)).data();
            const std::size_t count = lists.size_of(Index(i));
            for (std::size_t k0 = 0; k0 < count; k0 += hn::Lanes(d)) {
                const PairChunk<D> c = pair_chunk(d, xs, xi, list, k0, count);
                const auto s = hn::IfThenElseZero(c.in, k.grad_factor(d, hn::Sqrt(c.r2)));
                subtract_along_gradient(c, s, hn::IfThenElseZero(c.in, hn::Mul(weight(c.j), hn::Add(pi, term(c.j)))), acc);
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
        store_sum3(d, acc, nullptr, a.acc + 3 * i);
    }
}

// Becker & Teschner 2007 eq. 10-11 (nu = 2 alpha h c_s / (2 rho0)) and eq. 13:
// a_i = -sum_j m Pi_ij grad W_ij - kappa sum_j W_ij x_ij - sum_b rho0 V_b Pi_ib grad W_ib, the
// last with the boundary's alpha_b (fluid.boundary_viscosity; 0: free-slip walls).
void NonpressureRows(const NonpressurePairArgs& a, std::size_t begin, std::size_t end) {
    hn::ScalableTag<Real> d;
    using D = decltype(d);
    const KernelV<D> k(d, *a.kernel);
    const auto m = hn::Set(d, a.mass);
    const auto rho0 = hn::Set(d, a.rest_density);
    const auto rho_sum = hn::Set(d, a.rest_density + a.rest_density);
    const auto eps_h2 = hn::Set(d, Real(0.01) * a.h * a.h);
    const auto alpha_2hc = hn::Set(d, Real(2) * a.alpha * a.h * a.speed_of_sound);
    const auto alpha_b_2hc = hn::Set(d, Real(2) * a.alpha_b * a.h * a.speed_of_sound);
    const auto kappa = hn::Set(d, a.kappa);
    const bool viscous = a.alpha > 0, viscous_b = a.alpha_b > 0, cohesive = a.kappa > 0;
    for (std::size_t i = begin; i < end; ++i) {
        const Broadcast3<D> xi = broadcast3(d, a.x + 3 * i);
        const Broadcast3<D> vi = broadcast3(d, a.v + 3 * i);
        Broadcast3<D> acc{hn::Zero(d), hn::Zero(d), hn::Zero(d)};
        const Index* list = a.fluid->of(Index(i)).data();
        const std::size_t count = a.fluid->size_of(Index(i));
        for (std::size_t k0 = 0; k0 < count; k0 += hn::Lanes(d)) {
            const PairChunk<D> c = pair_chunk(d, a.x, xi, list, k0, count);
            const auto r = hn::Sqrt(c.r2);
            if (viscous) {
                const Broadcast3<D> vij = relative_velocity(d, vi, a.v, c);
                const auto vx = dot3(vij.x, vij.y, vij.z, c.dx, c.dy, c.dz);
                const auto coef = hn::IfThenElseZero(c.in, hn::Mul(m, monaghan(vx, c.r2, alpha_2hc, rho_sum, eps_h2)));
                subtract_along_gradient(c, hn::IfThenElseZero(c.in, k.grad_factor(d, r)), coef, acc);
            }
            if (cohesive)  // a -= kappa W_ij x_ij: the "gradient" factor is 1
                subtract_along_gradient(c, hn::Set(d, Real(1)), hn::IfThenElseZero(c.in, hn::Mul(kappa, k.w(d, r))), acc);
        }
        if (a.xb && viscous_b) {
            const Index* blist = a.boundary->of(Index(i)).data();
            const std::size_t bcount = a.boundary->size_of(Index(i));
            for (std::size_t k0 = 0; k0 < bcount; k0 += hn::Lanes(d)) {
                const PairChunk<D> c = pair_chunk(d, a.xb, xi, blist, k0, bcount);
                const Broadcast3<D> vib = relative_velocity(d, vi, a.vel_b, c);  // v_i - v_b
                const auto psi = hn::Mul(rho0, hn::GatherIndex(d, a.volume_b, c.j));
                const auto coef = hn::IfThenElseZero(
                    c.in, hn::Mul(psi, monaghan(dot3(vib.x, vib.y, vib.z, c.dx, c.dy, c.dz), c.r2, alpha_b_2hc, rho_sum,
                                                eps_h2)));
                subtract_along_gradient(c, hn::IfThenElseZero(c.in, k.grad_factor(d, hn::Sqrt(c.r2))), coef, acc);
            }
        }
        store_sum3(d, acc, nullptr, a.acc + 3 * i);
    }
}
#else
void ForceRows(const ForcePairArgs&, const Index*, std::size_t, std::size_t) {}
void MomentRows(const MomentPairArgs&, const Index*, std::size_t, std::size_t) {}
void PressureForceRows(const PressurePairArgs&, std::size_t, std::size_t) {}
void NonpressureRows(const NonpressurePairArgs&, std::size_t, std::size_t) {}
#endif

}  // namespace HWY_NAMESPACE
}  // namespace sph
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace sph {
HWY_EXPORT(ForceRows);
HWY_EXPORT(MomentRows);
HWY_EXPORT(PressureForceRows);
HWY_EXPORT(NonpressureRows);
void nonpressure_rows_simd(const NonpressurePairArgs& a, std::size_t begin, std::size_t end) {
    HWY_DYNAMIC_DISPATCH(NonpressureRows)(a, begin, end);
}
void force_rows_simd(const ForcePairArgs& a, const Index* rows, std::size_t begin, std::size_t end) {
    HWY_DYNAMIC_DISPATCH(ForceRows)(a, rows, begin, end);
}
void moment_rows_simd(const MomentPairArgs& a, const Index* rows, std::size_t begin, std::size_t end) {
    HWY_DYNAMIC_DISPATCH(MomentRows)(a, rows, begin, end);
}
void pressure_force_rows_simd(const PressurePairArgs& a, std::size_t begin, std::size_t end) {
    HWY_DYNAMIC_DISPATCH(PressureForceRows)(a, begin, end);
}
}  // namespace sph
#endif
