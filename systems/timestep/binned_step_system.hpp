#pragma once
/// @file binned_step_system.hpp
/// @brief Binned stepping, after the forces: each active particle's new bin, the neighbour
/// limiter and wake-up, and the step to the next due time.
///
/// 1. Raw bin: the largest bin whose step fits the particle's Delta t_i^raw (He eq. 6-8 per
///    particle, computed by the forces system). A step may shrink at any time; it may grow by
///    one bin, and only when `now` is a multiple of the larger step (SWIFT, timestep.h).
/// 2. Limiter (Saitoh & Makino 2009, SWIFT's time_bin_neighbour_max_delta_bin = 2) in place of
///    He et al. Alg. 2 line 16: bin_i <= bin_j + 2 for every j in i's fresh list, i.e. no step
///    more than 4x a neighbour's. Among the active particles this is a fixed point, reached by
///    repeated passes of bin_i = min(bin_i, min_j bin_j + 2) (bins only fall, so it is unique
///    whatever the order of updates: the result does not depend on the thread schedule).
/// 3. Wake-up: a sleeping neighbour j of an active i with bin_j > bin_i + 2 gets bin_i + 2 and
///    its step cut to end at the first multiple of that bin's step after now. Its state is
///    extrapolated from its last evaluation (He Alg. 2 lines 19-21), so the cut holds no
///    acceleration past the new end. A lowered sleeping bin may in turn bound an active one,
///    so steps 2-3 repeat until a wake-up pass changes nothing.
/// 4. Every active and woken particle is filed under its new end; the next step ends at the
///    earliest end with a live entry (stale entries of woken particles are dropped there),
///    clipped to the run's end and frame times by the engine.
/// Afterwards, for every active i and every j in i's list, |bin_i - bin_j| <= 2.
#include <vector>

#include "engine/core/timeline.hpp"
#include "engine/core/types.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/system.hpp"

namespace sph {

namespace counter {
inline constexpr Counter limiter_rows{"limiter_rows"};  ///< rows whose lists the limiter and the wake-up read
}  // namespace counter

class BinnedStepSystem final : public System {
public:
    /// @param dt_min, dt_max the scene's step range; @param headroom where rebasing puts the
    /// shortest bin, as a fraction of the shortest step, when the raw steps span more than one
    /// bin (0: never rebase; BinTimeline::rebased). When they all lie within a factor 2 of the
    /// shortest, every particle lands in the shortest bin and is due again at the next step,
    /// so the bin is put at the shortest step itself (headroom 1): such a run steps as
    /// `global` does. 0.8 against 0.7, 0.9 and 1.0: docs/results/he_table1.md, "The rebase's headroom".
    BinnedStepSystem(double dt_min, double dt_max, double headroom = kHeadroom)
        : m_dt_min(dt_min), m_dt_max(dt_max), m_headroom(headroom) {}
    static constexpr double kHeadroom = 0.8;
    /// The limiter's span in bins (rule 2): a step at most 2^kLimiterSpan times a neighbour's.
    /// 1 (at most 2x) measured no more accurate than 2 on the stirred pool at 1.17 M particles
    /// (docs/results/he_table1.md, "A tighter limiter").
    static constexpr int kLimiterSpan = 2;
    /// On a step whose grid was built from every row, with at most this many cells a row, the rows
    /// the limiter pulls at (every row due) are found by grid cell (binned_step_system.cpp) ...
    static constexpr double kCellsPerRow = 8;
    /// ... and the wake-up's rows, on a step with at least this share of the rows due.
    static constexpr double kWakeByCellsShare = 0.5;
    std::string name() const override { return "binned_step"; }
    Access access() const override;
    void register_components(World& w) override;
    void run(Context& ctx) override;

private:
    double m_dt_min, m_dt_max, m_headroom;
    std::vector<Index> m_counts;  ///< filing: rows per (chunk of the active set, new bin), then offsets
    std::vector<Index> m_limit, m_wake;           ///< active rows the limiter / wake-up must visit
    std::vector<Index> m_pull;                    ///< every row due: the rows the limiter pulls at
    /// Per grid cell: the smallest (limiter) or largest (wake-up) bin of the rows in its 27
    /// cells, and the scratch that computes it.
    std::vector<std::uint8_t> m_block, m_cell, m_block_tmp;
};

}  // namespace sph
