#pragma once
/// @file binned_state.hpp
/// @brief The state binned stepping keeps beside its particle columns (comp::bin, comp::ti_end):
/// the run's integer timeline (a Kept resource: checkpointed, so a resumed run continues on the
/// same quanta) and the due-time buckets the active set is taken from (Scratch: rebuilt from
/// the ti_end column whenever the fluid rows are reordered, added or restored).
#include <algorithm>
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

/// @brief What bounds every fluid row's speed along its drift since the last step that evaluated
/// every row, so that FluidGridSystem may keep its grid while no row can have moved far
/// (UniformGrid::set_drift). An evaluated row i has Delta t_i^raw <= lambda_v h / |v_i| and
/// <= lambda_f sqrt(h / |a_i|) (He et al. eq. 6-7, systems/timestep/global_dt_system.hpp), and a
/// step Delta t_i <= max(Delta t_i^raw, q) (its bin is at most the raw one; bin 0 is one quantum
/// q). Along its drift x0 + tau (v0 + tau a) (He Alg. 2 lines 20-21, tau <= Delta t_i) its speed
/// is at most |v0| + 2 Delta t_i |a| <= (lambda_v + 2 lambda_f^2 max(1, q / dt)) h / dt with dt
/// the shortest Delta t^raw evaluated since: BinnedStepSystem keeps dt and q, resetting them when
/// every row is evaluated. Woken rows keep their drift with a shorter step (within the bound).
struct DriftBound {
    double shortest_raw = std::numeric_limits<double>::infinity();
    double quantum = 0;  ///< the longest bin-0 step since the reset
    /// ComponentStore::membership at the reset; a restore or added rows void the bound until
    /// the next step that evaluates every row.
    std::uint64_t membership = std::numeric_limits<std::uint64_t>::max();
    /// The engine tick of the reset: the bound covers the drift since then only, so a grid
    /// built before it may not be kept on it.
    std::int64_t reset_at = 0;
    /// The entries filed under the next due time when the last step planned it: the rows the
    /// next step evaluates, give or take woken rows' stale entries and the rows a moving body
    /// adds. FluidGridSystem decides on it, so that it need not wait for that step's selection.
    std::size_t next_due = std::numeric_limits<std::size_t>::max();
    /// How far the collision net moved a row off its drift in the last step: the largest jump
    /// it applied (0: it moved none), or infinity when it may also have sped a row up (a hit on
    /// a moving boundary, whose velocity it adds). A static surface only removes the velocity
    /// into it, so a netted row keeps the speed bound above and, re-based where the net put it
    /// (BinnedWakeSystem), drifts on from there: a kept grid adds the jumps to its drift.
    double net_shift = 0;
    /// The largest jump among the rows the net moved without a moving body's hit. A row a moving
    /// body netted ends on its surface, within the body's reach, where BinnedBodySystem's
    /// candidates already include it, so the candidates need only this one.
    double net_shift_static = 0;
    /// The speed bound in m/s (infinity before the first reset).
    double speed(double lambda_v, double lambda_f, double h) const {
        if (!(shortest_raw > 0) || shortest_raw == std::numeric_limits<double>::infinity())
            return std::numeric_limits<double>::infinity();
        return (lambda_v + 2 * lambda_f * lambda_f * std::max(1.0, quantum / shortest_raw)) * h / shortest_raw;
    }
};

namespace res {
inline constexpr Resource<DriftBound> drift_bound{"binned.drift_bound"};
inline constexpr Resource<BinTimeline> bin_timeline{"binned.timeline"};
inline constexpr Resource<DueBuckets> due_buckets{"binned.due"};
}  // namespace res

/// @brief The engine tick (1 ps) of a time on the timeline, rounded to the nearest.
inline Tick ticks_of(const BinTimeline& t, std::uint64_t quanta) {
    return t.origin + Tick(std::llround(t.seconds(quanta) / kSecondsPerTick));
}

}  // namespace sph
