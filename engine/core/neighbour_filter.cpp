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

#include "engine/core/grid.hpp"
#include "engine/core/neighbour_filter.hpp"

HWY_BEFORE_NAMESPACE();
namespace sph {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

#ifndef SPH_DOUBLE
Index FilterCandidates(const CandidateCache& cache, const Vec3& xi, Index self, float r2, Index* dst) {
    const hn::ScalableTag<float> d;
    const hn::RebindToUnsigned<decltype(d)> du;
    const std::size_t lanes = hn::Lanes(d);
    const auto vx = hn::Set(d, xi.x()), vy = hn::Set(d, xi.y()), vz = hn::Set(d, xi.z());
    const auto vr2 = hn::Set(d, r2);
    const auto vself = hn::Set(du, self);
    Index c = 0;
    // The padding past cache.count holds far points, which fail the distance test.
    for (std::size_t k = 0; k < cache.count; k += lanes) {
        const auto dx = hn::Sub(vx, hn::LoadU(d, cache.x.data() + k));
        const auto dy = hn::Sub(vy, hn::LoadU(d, cache.y.data() + k));
        const auto dz = hn::Sub(vz, hn::LoadU(d, cache.z.data() + k));
        const auto dist2 = hn::MulAdd(dz, dz, hn::MulAdd(dy, dy, hn::Mul(dx, dx)));
        const auto j = hn::LoadU(du, cache.index.data() + k);
        const auto in = hn::And(hn::RebindMask(du, hn::Lt(dist2, vr2)), hn::Ne(j, vself));
        // Compress into a register and store the whole vector (the caller's buffer has a
        // vector of slack): on Zen 4 the memory form of vpcompressd is microcoded.
        hn::StoreU(hn::Compress(j, in), du, dst + c);
        c += Index(hn::CountTrue(du, in));
    }
    return c;
}
Index FilterRanges(const UniformGrid& grid, const CandidateRanges& ranges, const Vec3& xi, Index self, float r2,
                   Index* dst) {
    const hn::ScalableTag<float> d;
    const hn::RebindToUnsigned<decltype(d)> du;
    const std::size_t lanes = hn::Lanes(d);
    const auto vx = hn::Set(d, xi.x()), vy = hn::Set(d, xi.y()), vz = hn::Set(d, xi.z());
    const auto vr2 = hn::Set(d, r2);
    const auto vself = hn::Set(du, self);
    const float *sx = grid.sorted_x(), *sy = grid.sorted_y(), *sz = grid.sorted_z();
    const Index* sj = grid.sorted_index().data();
    Index c = 0;
    for (int r = 0; r < ranges.count; ++r) {
        const std::size_t e = ranges.end[r];
        // A load past a range's end reads the next range's slots or the grid's padding
        // (UniformGrid::kPadding readable slots after the last): masked off.
        for (std::size_t k = ranges.begin[r]; k < e; k += lanes) {
            const auto dx = hn::Sub(vx, hn::LoadU(d, sx + k));
            const auto dy = hn::Sub(vy, hn::LoadU(d, sy + k));
            const auto dz = hn::Sub(vz, hn::LoadU(d, sz + k));
            const auto dist2 = hn::MulAdd(dz, dz, hn::MulAdd(dy, dy, hn::Mul(dx, dx)));
            const auto j = hn::LoadU(du, sj + k);
            const auto in = hn::And(hn::And(hn::RebindMask(du, hn::Lt(dist2, vr2)), hn::Ne(j, vself)),
                                    hn::FirstN(du, e - k));
            hn::StoreU(hn::Compress(j, in), du, dst + c);
            c += Index(hn::CountTrue(du, in));
        }
    }
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
