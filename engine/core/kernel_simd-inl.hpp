// The cubic spline of kernel.hpp (Monaghan 1992, support h) on Highway vectors: the same
// formulas in the same order, a whole vector of pairs at a time. Included inside the
// HWY_NAMESPACE of a Highway translation unit (once per compiled target), hence the toggle
// guard instead of #pragma once.
#if defined(SPH_KERNEL_SIMD_INL_HPP_) == defined(HWY_TARGET_TOGGLE)
#ifdef SPH_KERNEL_SIMD_INL_HPP_
#undef SPH_KERNEL_SIMD_INL_HPP_
#else
#define SPH_KERNEL_SIMD_INL_HPP_
#endif

#include <hwy/highway.h>

#include "engine/core/kernel.hpp"

HWY_BEFORE_NAMESPACE();
namespace sph {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

/// @brief The kernel's constants broadcast to vectors.
template <class D>
struct KernelV {
    using V = hn::Vec<D>;
    V inv_h, sigma, grad_sigma, r_min, half, one, two, three, six;
    KernelV(D d, const CubicSpline& k)
        : inv_h(hn::Set(d, k.inv_support())), sigma(hn::Set(d, k.sigma())), grad_sigma(hn::Set(d, k.grad_sigma())),
          r_min(hn::Set(d, Real(1e-9) * k.support())), half(hn::Set(d, Real(0.5))), one(hn::Set(d, Real(1))),
          two(hn::Set(d, Real(2))), three(hn::Set(d, Real(3))), six(hn::Set(d, Real(6))) {}

    /// W(r) (CubicSpline::w), zero for r >= h.
    V w(D d, V r) const {
        const V q = hn::Mul(r, inv_h);
        const V q2 = hn::Mul(q, q);
        const V inner = hn::Mul(sigma, hn::Add(hn::Mul(six, hn::Sub(hn::Mul(q2, q), q2)), one));
        const V f = hn::Sub(one, q);
        const V outer = hn::Mul(hn::Mul(hn::Mul(hn::Mul(sigma, two), f), f), f);
        const V w = hn::IfThenElse(hn::Le(q, half), inner, outer);
        return hn::IfThenElseZero(hn::Lt(q, one), w);
    }

    /// The factor s with grad W = x_ij s (CubicSpline::grad); zero for r >= h and r ~ 0.
    V grad_factor(D d, V r) const {
        const V q = hn::Mul(r, inv_h);
        const V f = hn::Sub(one, q);
        const V dwdq = hn::IfThenElse(hn::Le(q, half), hn::Mul(q, hn::Sub(hn::Mul(three, q), two)),
                                      hn::Neg(hn::Mul(f, f)));
        const auto valid = hn::And(hn::Lt(q, one), hn::Gt(r, r_min));
        // r is replaced by 1 where invalid, so no lane divides by zero.
        const V safe_r = hn::IfThenElse(valid, r, one);
        return hn::IfThenElseZero(valid, hn::Div(hn::Mul(hn::Mul(grad_sigma, dwdq), inv_h), safe_r));
    }
};

/// @brief |d|^2 summed as Eigen's squaredNorm does, ((x^2 + y^2) + z^2).
template <class V>
HWY_INLINE V norm2(V dx, V dy, V dz) {
    return hn::Add(hn::Add(hn::Mul(dx, dx), hn::Mul(dy, dy)), hn::Mul(dz, dz));
}

/// @brief a . b summed in the same order, ((ax bx + ay by) + az bz).
template <class V>
HWY_INLINE V dot3(V ax, V ay, V az, V bx, V by, V bz) {
    return hn::Add(hn::Add(hn::Mul(ax, bx), hn::Mul(ay, by)), hn::Mul(az, bz));
}

/// @brief Loads the neighbour indices [k, k + lanes) of a list of `count` entries, lanes at
/// or past `count` set to 0 (a valid row whose contribution the caller masks off).
/// @warning The list must be readable up to k + lanes (NeighbourLists' capacity is a
/// multiple of 16).
template <class DI>
HWY_INLINE hn::Vec<DI> load_neighbours(DI di, const Index* list, std::size_t k, std::size_t count, hn::Mask<DI>& in) {
    in = hn::FirstN(di, count - k);
    return hn::IfThenElseZero(in, hn::LoadU(di, reinterpret_cast<const std::int32_t*>(list) + k));
}

/// @brief A particle's position (or velocity) broadcast to every lane.
template <class D>
struct Broadcast3 {
    hn::Vec<D> x, y, z;
};
template <class D>
HWY_INLINE Broadcast3<D> broadcast3(D d, const Real* xyz) {
    return {hn::Set(d, xyz[0]), hn::Set(d, xyz[1]), hn::Set(d, xyz[2])};
}

/// @brief The xyz rows `base + 3 j` of a column of Vec3 (`j3` = 3 j; every j a row of the
/// column), one gather per component; on AVX2 (8 floats), eight 16-byte loads and a transpose
/// instead, the same values: Zen 3 runs three 8-lane gathers at half that speed
/// (docs/results/benchmarks.md, "AVX2 rows without gathers").
template <class D, class VI>
HWY_INLINE Broadcast3<D> gather3(D d, const Real* base, VI j3) {
#if HWY_TARGET == HWY_AVX2 && !defined(SPH_DOUBLE)
    if constexpr (sizeof(hn::Vec<D>) == 32 && sizeof(hn::TFromD<D>) == 4) {
        // Lane l loads the four floats that end at row j_l's z, base[3 j_l - 1, 3 j_l + 2]: inside
        // the column for j_l > 0, and read from a copy of row 0 behind a pad for j_l = 0 (also
        // every masked-off lane). A 4 x 4 transpose in each 128-bit half then gives x, y and z.
        alignas(32) std::int32_t at[8];
        hn::Store(j3, hn::RebindToSigned<D>(), at);
        const float row0[4] = {0.0f, base[0], base[1], base[2]};
        const auto row = [&](int l) { return _mm_loadu_ps(at[l] ? base + at[l] - 1 : row0); };
        const auto pair = [&](int l) { return _mm256_insertf128_ps(_mm256_castps128_ps256(row(l)), row(l + 4), 1); };
        const __m256 r0 = pair(0), r1 = pair(1), r2 = pair(2), r3 = pair(3);
        const __m256 t0 = _mm256_unpacklo_ps(r0, r1), t1 = _mm256_unpackhi_ps(r0, r1);  // (-, -, x0, x1), (y0, y1, z0, z1)
        const __m256 t2 = _mm256_unpacklo_ps(r2, r3), t3 = _mm256_unpackhi_ps(r2, r3);
        return {hn::Vec<D>{_mm256_shuffle_ps(t0, t2, _MM_SHUFFLE(3, 2, 3, 2))},
                hn::Vec<D>{_mm256_shuffle_ps(t1, t3, _MM_SHUFFLE(1, 0, 1, 0))},
                hn::Vec<D>{_mm256_shuffle_ps(t1, t3, _MM_SHUFFLE(3, 2, 3, 2))}};
    }
#endif
    return {hn::GatherIndex(d, base, j3), hn::GatherIndex(d, base + 1, j3), hn::GatherIndex(d, base + 2, j3)};
}

/// @brief One vector of a particle's neighbour list [k0, k0 + lanes): the neighbours j (lanes at
/// or past `count` masked off by `in` and reading row 0), 3 j for the xyz gathers, and
/// x_i - x_j with its squared length.
template <class D>
struct PairChunk {
    hn::Vec<hn::RebindToSigned<D>> j, j3;
    hn::Mask<D> in;
    hn::Vec<D> dx, dy, dz, r2;
};
template <class D>
HWY_INLINE PairChunk<D> pair_chunk(D d, const Real* xs, const Broadcast3<D>& xi, const Index* list, std::size_t k0,
                                   std::size_t count) {
    const hn::RebindToSigned<D> di;
    hn::Mask<decltype(di)> in;
    const auto j = load_neighbours(di, list, k0, count, in);
    const auto j3 = hn::Add(hn::ShiftLeft<1>(j), j);
    const Broadcast3<D> xj = gather3(d, xs, j3);
    const auto dx = hn::Sub(xi.x, xj.x), dy = hn::Sub(xi.y, xj.y), dz = hn::Sub(xi.z, xj.z);
    return {j, j3, hn::RebindMask(d, in), dx, dy, dz, norm2(dx, dy, dz)};
}

/// Software prefetch ahead of a pair loop over a subset of rows, at row q of [.., end): the list
/// of the row kListAhead rows on, and the positions named by the list of the row kPairsAhead
/// rows on (fetched two rows earlier). The gathers wait on memory, not arithmetic, and the rows
/// of a subset (binned and individual stepping) are too scattered for the hardware prefetcher.
/// Over all rows (rows == nullptr) or a dense run of them the hardware prefetcher does better
/// and nothing is issued: `sparse` says whether the caller's rows are scattered (see
/// rows_are_sparse). docs/results/benchmarks.md has the measurements.
template <class Lists>
HWY_INLINE void prefetch_ahead(const Lists& lists, const Real* x, const Index* rows, bool sparse, std::size_t q,
                               std::size_t end) {
    constexpr std::size_t kListAhead = 4, kPairsAhead = 2;
    if (!sparse) return;
    if (q + kListAhead < end) __builtin_prefetch(lists.of(rows[q + kListAhead]).data());
    if (q + kPairsAhead < end)
        for (const Index j : lists.of(rows[q + kPairsAhead])) __builtin_prefetch(x + 3 * std::size_t(j));
}

/// Whether rows[begin, end) (ascending) are scattered: they span more than twice their count.
HWY_INLINE bool rows_are_sparse(const Index* rows, std::size_t begin, std::size_t end) {
    return rows && end > begin && std::size_t(rows[end - 1] - rows[begin]) > 2 * (end - begin);
}

}  // namespace HWY_NAMESPACE
}  // namespace sph
HWY_AFTER_NAMESPACE();

#endif  // SPH_KERNEL_SIMD_INL_HPP_
