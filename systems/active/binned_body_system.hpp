#pragma once
/// @file binned_body_system.hpp
/// @brief Binned stepping with moving bodies, after BinnedSelectSystem: on a step at a due time,
/// every sleeping row within reach of a moving body joins the active set (SelectActiveSystem's
/// rule, near_moving_body: within h + the body's speed x the row's step of its bounding box),
/// due now on the largest bin `now` allows; its entry at its old end goes stale (DueBuckets).
///
/// Only candidates are tested: the rows that were within R + m of a body's box when the list
/// was made (R = h + speed x dt_max bounds every row's reach, as dt_max bounds every step; m the
/// margin, kMargin h). A row within R of the box now was within R + m of it then while the box
/// has moved by d_b and the rows by at most d_f since, with d_b + d_f <= m: d_b from the boxes
/// themselves, d_f summed step by step from DriftBound's speed bound (the speed of every row
/// since the last step that evaluated all of them, binned_state.hpp) and the collision net's
/// jumps (DriftBound::net_shift_static: a row a moving body netted crossed into its box, so it
/// was a candidate already, whatever speed the hit gave it). Otherwise (or when rows were reordered, added or restored) the list is made anew from
/// every row. A candidate's position at the step's time comes from its base state (drift.hpp,
/// the bits DriftSystem writes): it reads no position, so it waits for neither the drift nor the
/// fluid grid. The set equals a scan of every row with current positions.
/// Cost: O(candidates) per due step; O(N) when the list is made anew.
#include <cstdint>
#include <limits>
#include <vector>

#include "engine/core/types.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/system.hpp"

namespace sph {

namespace counter {
inline constexpr Counter body_candidates{"body_candidates"};  ///< rows tested against the moving bodies' reach
}  // namespace counter

class BinnedBodySystem final : public System {
public:
    /// @param stepping the scene's dt_max (bounds every row's step) and lambda_v, lambda_f (the
    /// drift bound's speed, He eq. 6-7).
    explicit BinnedBodySystem(const SteppingParams& stepping)
        : m_dt_max(stepping.dt_max), m_lambda_v(stepping.lambda_v), m_lambda_f(stepping.lambda_f) {}
    /// The margin m of the candidate list, in h: a wider list is made less often (every m / (body
    /// speed + the rows' speed bound) seconds) and tested longer at each due step.
    static constexpr double kMargin = 1.0;
    std::string name() const override { return "binned_body"; }
    Access access() const override;
    void register_components(World& w) override;
    void run(Context& ctx) override;
    /// How many times the candidate list was made (from every row), for the tests.
    std::size_t lists_made() const { return m_lists_made; }

private:
    /// Makes the candidate list from every row's position at `now`.
    void make_list(Context& ctx, const std::vector<MovingBody>& bodies, double reach);

    double m_dt_max, m_lambda_v, m_lambda_f;
    std::vector<Index> m_list;             ///< the candidates, ascending
    std::vector<Aabb> m_boxes;             ///< each body's box when the list was made
    std::uint64_t m_layout = std::numeric_limits<std::uint64_t>::max();      ///< the fluid's layout then
    double m_moved = std::numeric_limits<double>::infinity();  ///< d_f: how far any row can have moved since
    Tick m_last = 0;                       ///< the tick of the last step seen (d_f is summed from there)
    std::vector<Index> m_added;            ///< the rows this step adds
    std::size_t m_lists_made = 0;
};

}  // namespace sph
