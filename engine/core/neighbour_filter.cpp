// The vectorised candidate filter of the neighbour search (build_neighbour_lists): for one
// query point, the candidates of the 27 surrounding cells (copied contiguously per cell, see
// CandidateCache) are tested a whole vector at a time, |x_i - x_j|^2 < r^2, and the indices in
// range are compressed into the output (AVX-512 vpcompressd; a table lookup on AVX2), so the
// loop has no data-dependent branch. Same lists, in the same order, as the scalar filter.
#include "engine/core/simd_targets.hpp"

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "engine/core/neighbour_filter.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

#include <array>
#include <bit>
#include <cstdint>

#include "engine/core/grid.hpp"
#include "engine/core/neighbour_filter.hpp"

HWY_BEFORE_NAMESPACE();
namespace sph {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

#ifndef SPH_DOUBLE
#if HWY_TARGET == HWY_AVX2
/// The 8-lane compress of AVX2 by a permutation table: entry m holds, in 4-bit fields, the lanes
/// whose bit is set in m in ascending order, then the others. Highway 1.0.3 (Debian 12) builds
/// the same table as a non-static constexpr array inside Compress, which GCC copies to the stack
/// (1 KiB) on every call (google/highway#1139): that made the AVX2 filter slower than the scalar
/// one (docs/results/benchmarks.md, "The AVX2 compress"). Static here, so it is read in place.
constexpr std::array<std::uint32_t, 256> compress_nibbles() {
    std::array<std::uint32_t, 256> table{};
    for (std::uint32_t m = 0; m < 256; ++m) {
        std::uint32_t packed = 0, field = 0;
        for (int selected = 1; selected >= 0; --selected)
            for (std::uint32_t lane = 0; lane < 8; ++lane)
                if (((m >> lane) & 1u) == std::uint32_t(selected)) packed |= lane << (4 * field++);
        table[m] = packed;
    }
    return table;
}
alignas(64) static constexpr std::array<std::uint32_t, 256> kCompressNibbles = compress_nibbles();

template <class DU>
HWY_INLINE hn::Vec<DU> CompressIndices(DU du, hn::Vec<DU> v, hn::Mask<DU> in, std::size_t& count) {
    std::uint8_t bits = 0;
    hn::StoreMaskBits(du, in, &bits);
    count = std::size_t(std::popcount(bits));
    alignas(32) static constexpr std::uint32_t kShifts[8] = {0, 4, 8, 12, 16, 20, 24, 28};
    const auto lanes = hn::And(hn::Shr(hn::Set(du, kCompressNibbles[bits]), hn::Load(du, kShifts)), hn::Set(du, 7u));
    return hn::TableLookupLanes(v, hn::IndicesFromVec(du, lanes));
}
#else
template <class DU>
HWY_INLINE hn::Vec<DU> CompressIndices(DU du, hn::Vec<DU> v, hn::Mask<DU> in, std::size_t& count) {
    count = hn::CountTrue(du, in);
    return hn::Compress(v, in);
}
#endif

/// Filters slots [begin, end) of slot-ordered arrays x, y, z, j against xi, appending the indices
/// in range to dst + c; returns the new count. Masked: the last vector's lanes past `end` are
/// masked off (they may hold real candidates); otherwise they must hold far points.
template <bool Masked>
Index FilterRun(const float* x, const float* y, const float* z, const Index* jx, std::size_t begin, std::size_t end,
                const Vec3& xi, Index self, float r2, Index* dst, Index c) {
    const hn::ScalableTag<float> d;
    const hn::RebindToUnsigned<decltype(d)> du;
    const std::size_t lanes = hn::Lanes(d);
    const auto vx = hn::Set(d, xi.x()), vy = hn::Set(d, xi.y()), vz = hn::Set(d, xi.z());
    const auto vr2 = hn::Set(d, r2);
    const auto vself = hn::Set(du, self);
    for (std::size_t k = begin; k < end; k += lanes) {
        const auto dx = hn::Sub(vx, hn::LoadU(d, x + k));
        const auto dy = hn::Sub(vy, hn::LoadU(d, y + k));
        const auto dz = hn::Sub(vz, hn::LoadU(d, z + k));
        const auto dist2 = hn::MulAdd(dz, dz, hn::MulAdd(dy, dy, hn::Mul(dx, dx)));
        const auto j = hn::LoadU(du, jx + k);
        auto in = hn::And(hn::RebindMask(du, hn::Lt(dist2, vr2)), hn::Ne(j, vself));
        if constexpr (Masked) in = hn::And(in, hn::FirstN(du, end - k));
        // Compress into a register and store the whole vector (the caller's buffer has a
        // vector of slack): on Zen 4 the memory form of vpcompressd is microcoded.
        std::size_t in_range = 0;
        hn::StoreU(CompressIndices(du, j, in, in_range), du, dst + c);
        c += Index(in_range);
    }
    return c;
}

Index FilterCandidates(const CandidateCache& cache, const Vec3& xi, Index self, float r2, Index* dst) {
    // The padding past cache.count holds far points, which fail the distance test.
    return FilterRun<false>(cache.x.data(), cache.y.data(), cache.z.data(), cache.index.data(), 0, cache.count, xi,
                            self, r2, dst, 0);
}

Index FilterRanges(const UniformGrid& grid, const CandidateRanges& ranges, const Vec3& xi, Index self, float r2,
                   Index* dst) {
    // A load past a range's end reads the next range's slots or the grid's padding
    // (UniformGrid::kPadding readable slots after the last): masked off.
    Index c = 0;
    for (int r = 0; r < ranges.count; ++r)
        c = FilterRun<true>(grid.sorted_x(), grid.sorted_y(), grid.sorted_z(), grid.sorted_index().data(),
                            ranges.begin[r], ranges.end[r], xi, self, r2, dst, c);
    return c;
}
#else
Index FilterCandidates(const CandidateCache&, const Vec3&, Index, Real, Index*) { return 0; }
Index FilterRanges(const UniformGrid&, const CandidateRanges&, const Vec3&, Index, Real, Index*) { return 0; }
#endif

}  // namespace HWY_NAMESPACE
}  // namespace sph
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace sph {
HWY_EXPORT(FilterCandidates);

Index filter_candidates_simd(const CandidateCache& cache, const Vec3& xi, Index self, Real r2, Index* dst) {
    return HWY_DYNAMIC_DISPATCH(FilterCandidates)(cache, xi, self, r2, dst);
}
HWY_EXPORT(FilterRanges);
Index filter_ranges_simd(const UniformGrid& grid, const CandidateRanges& ranges, const Vec3& xi, Index self, Real r2,
                         Index* dst) {
    return HWY_DYNAMIC_DISPATCH(FilterRanges)(grid, ranges, xi, self, r2, dst);
}

}  // namespace sph
#endif
