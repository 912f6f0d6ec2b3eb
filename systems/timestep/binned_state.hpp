#pragma once
/// @file binned_state.hpp
/// @brief The state binned stepping keeps beside its particle columns (comp::bin, comp::ti_end):
/// the run's integer timeline (a Kept resource: checkpointed, so a resumed run continues on the
/// same quanta) and the due-time buckets the active set is taken from (Scratch: rebuilt from
/// the ti_end column whenever the fluid rows are reordered, added or restored).
#include <cstdint>
#include <limits>
#include <map>
#include <vector>

#include "engine/core/resources.hpp"
#include "engine/core/timeline.hpp"
#include "engine/core/types.hpp"
#include "engine/data/world.hpp"

namespace sph {

/// @brief Particles by the time their step ends, in quanta. Entries go stale when a particle's
/// end moves earlier (a wake-up); a particle is due at key k only while ti_end == k, so stale
/// entries are skipped when their bucket is taken. Every live particle has an entry at its end.
struct DueBuckets {
    std::map<std::uint64_t, std::vector<Index>> due;
    /// The fluid store's layout the indices refer to (ComponentStore::layout).
    std::uint64_t layout = std::numeric_limits<std::uint64_t>::max();
    /// Bounds on every particle's bin, lo <= bin <= hi: exact when the buckets are rebuilt, then
    /// kept by each system that sets a bin (lowered to the smallest it sets, raised to the
    /// largest). The limiter skips rows that cannot violate them (BinnedStepSystem).
    int bin_lo = 0, bin_hi = 0;
};

namespace res {
inline constexpr Resource<BinTimeline> bin_timeline{"binned.timeline"};
inline constexpr Resource<DueBuckets> due_buckets{"binned.due"};
}  // namespace res

/// @brief The engine tick (1 ps) of a time on the timeline, rounded to the nearest.
inline Tick ticks_of(const BinTimeline& t, std::uint64_t quanta) {
    return t.origin + Tick(std::llround(t.seconds(quanta) / kSecondsPerTick));
}

}  // namespace sph
