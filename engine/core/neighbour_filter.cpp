// The vectorised candidate filter of the neighbour search (build_neighbour_lists): for one
// query point, the candidates of the 27 surrounding cells (9 contiguous ranges of sorted
// slots) are tested a whole vector at a time, |x_i - x_j|^2 < r^2, and the indices in range
// are compressed into the output (AVX-512 vpcompressd; a table lookup on AVX2), so the loop
// has no data-dependent branch. Same lists, in the same order, as the scalar filter.
#include "engine/core/simd_targets.hpp"

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "engine/core/neighbour_filter.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

#include <vector>

#include "engine/core/grid.hpp"
#include "engine/core/neighbour_filter.hpp"

HWY_BEFORE_NAMESPACE();
namespace sph {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

#ifndef SPH_DOUBLE
Index FilterCandidates(const UniformGrid& grid, const CandidateRanges& ranges, const Vec3& xi, Index self, float r2,
                       Index* dst) {
    const hn::ScalableTag<float> d;
    const hn::RebindToUnsigned<decltype(d)> du;
    const std::size_t lanes = hn::Lanes(d);
    const float* sx = grid.sorted_x();
    const float* sy = grid.sorted_y();
    const float* sz = grid.sorted_z();
    const Index* sidx = grid.sorted_index().data();
    const auto vx = hn::Set(d, xi.x()), vy = hn::Set(d, xi.y()), vz = hn::Set(d, xi.z());
    const auto vr2 = hn::Set(d, r2);
    const auto vself = hn::Set(du, self);
    Index c = 0;
    for (int r = 0; r < ranges.count; ++r) {
        const Index b = ranges.begin[r], e = ranges.end[r];
        for (Index k = b; k < e; k += Index(lanes)) {
            // Slots past e are in range of the arrays (kPadding) and masked off by FirstN.
            const auto dx = hn::Sub(vx, hn::LoadU(d, sx + k));
            const auto dy = hn::Sub(vy, hn::LoadU(d, sy + k));
            const auto dz = hn::Sub(vz, hn::LoadU(d, sz + k));
            const auto dist2 = hn::MulAdd(dz, dz, hn::MulAdd(dy, dy, hn::Mul(dx, dx)));
            const auto j = hn::LoadU(du, sidx + k);
            const auto in = hn::And(hn::RebindMask(du, hn::Lt(dist2, vr2)),
                                    hn::And(hn::FirstN(du, e - k), hn::Ne(j, vself)));
            // Compress into a register and store the whole vector (the caller's buffer has
            // a vector of slack): on Zen 4 the memory form of vpcompressd is microcoded.
            hn::StoreU(hn::Compress(j, in), du, dst + c);
            c += Index(hn::CountTrue(du, in));
        }
    }
    return c;
}
#else
Index FilterCandidates(const UniformGrid&, const CandidateRanges&, const Vec3&, Index, Real, Index*) { return 0; }
#endif

}  // namespace HWY_NAMESPACE
}  // namespace sph
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace sph {
HWY_EXPORT(FilterCandidates);

Index filter_candidates_simd(const UniformGrid& grid, const CandidateRanges& ranges, const Vec3& xi, Index self, Real r2,
                             Index* dst) {
    return HWY_DYNAMIC_DISPATCH(FilterCandidates)(grid, ranges, xi, self, r2, dst);
}

std::string simd_target() {
#ifdef SPH_DOUBLE
    return "scalar";
#else
    // The target HWY_DYNAMIC_DISPATCH picks: the best of those compiled that the CPU supports.
    const std::vector<std::int64_t> targets = hwy::SupportedAndGeneratedTargets();
    return targets.empty() ? "none" : hwy::TargetName(targets.front());
#endif
}
}  // namespace sph
#endif
