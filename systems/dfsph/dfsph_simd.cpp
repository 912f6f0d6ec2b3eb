// Bender & Koschier 2017 in volume form, vectorised across each particle's neighbour list: the
// factor's sums (eq. 11) with the Akinci et al. 2012 boundary terms, and the two pair sums of a
// solver pass, the velocity divergence (eq. 8/16) and the pressure acceleration (eq. 13/17),
// from the stored V grad W_ij. Compiled per target, chosen at run time (engine/core/simd.hpp).
#include "engine/core/simd_targets.hpp"

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "systems/dfsph/dfsph_simd.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

#include <cstring>
#include <type_traits>

#include "engine/core/kernel_simd-inl.hpp"
#include "systems/forces/viscosity_simd-inl.hpp"
#include "systems/dfsph/dfsph_simd.hpp"

HWY_BEFORE_NAMESPACE();
namespace sph {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

#ifndef SPH_DOUBLE
template <class D>
HWY_INLINE Real lane_sum(D d, hn::Vec<D> v) {
    return hn::GetLane(hn::SumOfLanes(d, v));
}

/// The stored gradients of row i: x, y, z components of its entries.
template <class R>
struct RowGradients {
    R *gx, *gy, *gz;
};
template <class G>
HWY_INLINE auto row_gradients(const NeighbourLists& lists, G& grads, std::size_t i) {
    const std::size_t b = i / NeighbourLists::kBlock, n = lists.blocks[b].size();
    auto* base = grads.blocks[b].data() + lists.begin_of(Index(i));
    return RowGradients<std::remove_reference_t<decltype(*base)>>{base, base + n, base + 2 * n};
}

/// Stores the first `valid` lanes of v at p (a row's last chunk must not write into the next
/// row, which another thread may be filling).
template <class D>
HWY_INLINE void store_lanes(D d, hn::Vec<D> v, std::size_t valid, Real* p) {
    if (valid >= hn::Lanes(d)) return hn::StoreU(v, d, p);
    HWY_ALIGN Real buf[hn::MaxLanes(d)];
    hn::Store(v, d, buf);
    std::memcpy(p, buf, valid * sizeof(Real));
}

void FactorSums(const DfsphPairArgs& a, std::size_t begin, std::size_t end, Real* w_sum, Real* wb_sum, Real* grad_sum,
                Real* grad_sq, Real* grad_b, Real* flux_b, PairGradients& grads) {
    hn::ScalableTag<Real> d;
    using D = decltype(d);
    const KernelV<D> k(d, *a.kernel);
    const auto vol = hn::Set(d, a.volume);
    const bool viscous = a.acc && (a.alpha > 0 || a.alpha_b > 0);
    const auto m = hn::Set(d, a.mass), rho0 = hn::Set(d, a.rest_density);
    const auto rho_sum = hn::Set(d, a.rest_density + a.rest_density);
    const auto eps_h2 = hn::Set(d, Real(0.01) * a.h * a.h);
    const auto alpha_2hc = hn::Set(d, Real(2) * a.alpha * a.h * a.speed_of_sound);
    const auto alpha_b_2hc = hn::Set(d, Real(2) * a.alpha_b * a.h * a.speed_of_sound);
    for (std::size_t i = begin; i < end; ++i) {
        const Broadcast3<D> xi = broadcast3(d, a.x + 3 * i);
        const Broadcast3<D> vi = viscous ? broadcast3(d, a.v + 3 * i) : Broadcast3<D>{};
        auto w = hn::Zero(d), wb = hn::Zero(d), sq = hn::Zero(d), fb = hn::Zero(d);
        Broadcast3<D> g{hn::Zero(d), hn::Zero(d), hn::Zero(d)}, gb{hn::Zero(d), hn::Zero(d), hn::Zero(d)};
        Broadcast3<D> visc{hn::Zero(d), hn::Zero(d), hn::Zero(d)};
        // a -= coef grad W with grad W = gf x (gf the masked gradient factor).
        auto viscous_pair = [&](const PairChunk<D>& c, hn::Vec<D> vx, hn::Vec<D> weight, hn::Vec<D> gf,
                                hn::Vec<D> a2hc) {
            const auto coef = hn::Mul(hn::Mul(weight, monaghan(vx, c.r2, a2hc, rho_sum, eps_h2)), gf);
            visc.x = hn::NegMulAdd(coef, c.dx, visc.x);
            visc.y = hn::NegMulAdd(coef, c.dy, visc.y);
            visc.z = hn::NegMulAdd(coef, c.dz, visc.z);
        };
        const Index* list = a.fluid->of(Index(i)).data();
        const std::size_t count = a.fluid->size_of(Index(i));
        const auto out = row_gradients(*a.fluid, grads, i);
        for (std::size_t k0 = 0; k0 < count; k0 += hn::Lanes(d)) {
            const PairChunk<D> c = pair_chunk(d, a.x, xi, list, k0, count);
            const auto r = hn::Sqrt(c.r2);
            w = hn::Add(w, hn::IfThenElseZero(c.in, k.w(d, r)));
            const auto gf = hn::IfThenElseZero(c.in, k.grad_factor(d, r));
            const auto s = hn::Mul(vol, gf);  // V grad W = s x_ij
            const auto gx = hn::Mul(s, c.dx), gy = hn::Mul(s, c.dy), gz = hn::Mul(s, c.dz);
            if (viscous) {
                const Broadcast3<D> vj = gather3(d, a.v, c.j3);
                viscous_pair(c, dot3(hn::Sub(vi.x, vj.x), hn::Sub(vi.y, vj.y), hn::Sub(vi.z, vj.z), c.dx, c.dy, c.dz), m,
                             gf, alpha_2hc);
            }
            g.x = hn::Add(g.x, gx);
            g.y = hn::Add(g.y, gy);
            g.z = hn::Add(g.z, gz);
            sq = hn::MulAdd(hn::Mul(s, s), c.r2, sq);
            store_lanes(d, gx, count - k0, out.gx + k0);
            store_lanes(d, gy, count - k0, out.gy + k0);
            store_lanes(d, gz, count - k0, out.gz + k0);
        }
        if (a.xb) {
            const Index* blist = a.boundary->of(Index(i)).data();
            const std::size_t bcount = a.boundary->size_of(Index(i));
            for (std::size_t k0 = 0; k0 < bcount; k0 += hn::Lanes(d)) {
                const PairChunk<D> c = pair_chunk(d, a.xb, xi, blist, k0, bcount);
                const auto r = hn::Sqrt(c.r2);
                const auto vb = hn::IfThenElseZero(c.in, hn::GatherIndex(d, a.volume_b, c.j));
                wb = hn::MulAdd(vb, hn::IfThenElseZero(c.in, k.w(d, r)), wb);
                const auto gf = hn::IfThenElseZero(c.in, k.grad_factor(d, r));
                const auto s = hn::Mul(vb, gf);
                const auto gx = hn::Mul(s, c.dx), gy = hn::Mul(s, c.dy), gz = hn::Mul(s, c.dz);
                gb.x = hn::Add(gb.x, gx);
                gb.y = hn::Add(gb.y, gy);
                gb.z = hn::Add(gb.z, gz);
                Broadcast3<D> vib = vi;  // v_i - v_b
                if (a.vel_b) {
                    const Broadcast3<D> vb3 = gather3(d, a.vel_b, c.j3);
                    fb = hn::Add(fb, dot3(vb3.x, vb3.y, vb3.z, gx, gy, gz));
                    vib = {hn::Sub(vi.x, vb3.x), hn::Sub(vi.y, vb3.y), hn::Sub(vi.z, vb3.z)};
                }
                if (viscous)
                    viscous_pair(c, dot3(vib.x, vib.y, vib.z, c.dx, c.dy, c.dz), hn::Mul(rho0, vb), gf, alpha_b_2hc);
            }
        }
        const std::size_t q = i - begin;
        w_sum[q] = lane_sum(d, w);
        wb_sum[q] = lane_sum(d, wb);
        grad_sum[3 * q] = lane_sum(d, g.x);
        grad_sum[3 * q + 1] = lane_sum(d, g.y);
        grad_sum[3 * q + 2] = lane_sum(d, g.z);
        grad_sq[q] = lane_sum(d, sq);
        grad_b[3 * q] = lane_sum(d, gb.x);
        grad_b[3 * q + 1] = lane_sum(d, gb.y);
        grad_b[3 * q + 2] = lane_sum(d, gb.z);
        flux_b[q] = lane_sum(d, fb);
        if (viscous) {
            a.acc[3 * i] = lane_sum(d, visc.x);
            a.acc[3 * i + 1] = lane_sum(d, visc.y);
            a.acc[3 * i + 2] = lane_sum(d, visc.z);
        }
    }
}

void Divergence(const DfsphPairArgs& a, std::size_t begin, std::size_t end, Real* div) {
    hn::ScalableTag<Real> d;
    using D = decltype(d);
    const hn::RebindToSigned<D> di;
    for (std::size_t i = begin; i < end; ++i) {
        const Broadcast3<D> vi = broadcast3(d, a.v + 3 * i);
        auto sum = hn::Zero(d);
        const Index* list = a.fluid->of(Index(i)).data();
        const std::size_t count = a.fluid->size_of(Index(i));
        const auto g = row_gradients(*a.fluid, *a.grads, i);
        for (std::size_t k0 = 0; k0 < count; k0 += hn::Lanes(d)) {
            hn::Mask<decltype(di)> in_i;
            const auto j = load_neighbours(di, list, k0, count, in_i);
            const auto in = hn::RebindMask(d, in_i);
            const Broadcast3<D> vj = gather3(d, a.v, hn::Add(hn::ShiftLeft<1>(j), j));
            const auto gx = hn::IfThenElseZero(in, hn::LoadU(d, g.gx + k0));
            const auto gy = hn::IfThenElseZero(in, hn::LoadU(d, g.gy + k0));
            const auto gz = hn::IfThenElseZero(in, hn::LoadU(d, g.gz + k0));
            sum = hn::Add(sum, dot3(hn::Sub(vi.x, vj.x), hn::Sub(vi.y, vj.y), hn::Sub(vi.z, vj.z), gx, gy, gz));
        }
        div[i - begin] = lane_sum(d, sum);
    }
}

void Pressure(const DfsphPairArgs& a, const Real* kappa, std::size_t begin, std::size_t end, Real* acc) {
    hn::ScalableTag<Real> d;
    using D = decltype(d);
    const hn::RebindToSigned<D> di;
    for (std::size_t i = begin; i < end; ++i) {
        const auto ki = hn::Set(d, kappa[i]);
        Broadcast3<D> f{hn::Zero(d), hn::Zero(d), hn::Zero(d)};
        const Index* list = a.fluid->of(Index(i)).data();
        const std::size_t count = a.fluid->size_of(Index(i));
        const auto g = row_gradients(*a.fluid, *a.grads, i);
        for (std::size_t k0 = 0; k0 < count; k0 += hn::Lanes(d)) {
            hn::Mask<decltype(di)> in_i;
            const auto j = load_neighbours(di, list, k0, count, in_i);
            const auto in = hn::RebindMask(d, in_i);
            const auto kij = hn::IfThenElseZero(in, hn::Add(ki, hn::GatherIndex(d, kappa, j)));
            f.x = hn::MulAdd(kij, hn::IfThenElseZero(in, hn::LoadU(d, g.gx + k0)), f.x);
            f.y = hn::MulAdd(kij, hn::IfThenElseZero(in, hn::LoadU(d, g.gy + k0)), f.y);
            f.z = hn::MulAdd(kij, hn::IfThenElseZero(in, hn::LoadU(d, g.gz + k0)), f.z);
        }
        const std::size_t q = i - begin;
        acc[3 * q] = lane_sum(d, f.x);
        acc[3 * q + 1] = lane_sum(d, f.y);
        acc[3 * q + 2] = lane_sum(d, f.z);
    }
}
#else
void FactorSums(const DfsphPairArgs&, std::size_t, std::size_t, Real*, Real*, Real*, Real*, Real*, Real*, PairGradients&) {}
void Divergence(const DfsphPairArgs&, std::size_t, std::size_t, Real*) {}
void Pressure(const DfsphPairArgs&, const Real*, std::size_t, std::size_t, Real*) {}
#endif

}  // namespace HWY_NAMESPACE
}  // namespace sph
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace sph {
HWY_EXPORT(FactorSums);
HWY_EXPORT(Divergence);
HWY_EXPORT(Pressure);

void PairGradients::shape_like(const NeighbourLists& lists) {
    blocks.resize(lists.blocks.size());
    for (std::size_t b = 0; b < lists.blocks.size(); ++b) {
        const std::size_t n = 3 * lists.blocks[b].size();
        // Grow by an eighth, not the vector's doubling: the lists' sizes drift by a few percent
        // from step to step, and a doubled block would hold 60 % more memory than it uses.
        if (n > blocks[b].capacity()) blocks[b].reserve(n + n / 8);
        blocks[b].resize(n);
    }
}

std::size_t PairGradients::bytes() const {
    std::size_t n = 0;
    for (const auto& b : blocks) n += b.capacity() * sizeof(Real);
    return n;
}

void dfsph_factor_sums_simd(const DfsphPairArgs& a, std::size_t begin, std::size_t end, Real* w_sum, Real* wb_sum,
                            Real* grad_sum, Real* grad_sq, Real* grad_b, Real* flux_b, PairGradients& grads) {
    HWY_DYNAMIC_DISPATCH(FactorSums)(a, begin, end, w_sum, wb_sum, grad_sum, grad_sq, grad_b, flux_b, grads);
}
void dfsph_divergence_simd(const DfsphPairArgs& a, std::size_t begin, std::size_t end, Real* div) {
    HWY_DYNAMIC_DISPATCH(Divergence)(a, begin, end, div);
}
void dfsph_pressure_simd(const DfsphPairArgs& a, const Real* kappa, std::size_t begin, std::size_t end, Real* acc) {
    HWY_DYNAMIC_DISPATCH(Pressure)(a, kappa, begin, end, acc);
}
}  // namespace sph
#endif
