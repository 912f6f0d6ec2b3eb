#pragma once
/// @file fluid_grid_system.hpp
/// @brief He et al. Alg. 1 line 3 / Alg. 2 line 4, first half: the fluid grid, rebuilt every
/// step, or (binned stepping) kept while no row can have moved far since its build.
#include <cstdint>
#include <limits>

#include "engine/data/scene.hpp"
#include "engine/graph/system.hpp"

namespace sph {

/// @brief Sorts the fluid particles into the uniform grid (cell size h).
///
/// With `keep` (binned stepping) a step whose due rows are few keeps the last grid instead,
/// declaring how far any row may have moved since it was built (UniformGrid::set_drift): the
/// speed bound of res::drift_bound (binned_state.hpp) times the time since the build, plus the
/// rounding of a float position for each step since. A bound reset after the build (a step that
/// evaluated every row while the grid was kept) does not cover the time before it: built afresh.
/// A row the collision net moved off its drift (DriftBound::net_shift: a jump to a static
/// surface, the speed not raised) adds its jump to the drift. The searches then return what a
/// fresh grid returns, so a run is bit for bit the same either way. The grid is built afresh
/// when the rows were reordered, added or restored, when the net may have sped a row up (a
/// moving boundary), when the bound is void, when the drift would reach kMaxDrift h, or when at least a kBuildShare
/// of the rows is due (where a fresh build and the 27-cell search cost less than the drifted
/// search's wider reach: docs/results/benchmarks.md). The share is the one the last step
/// planned (DriftBound::next_due), not this step's selection, so that the grid runs beside
/// binned_select rather than after it (measured: waiting for it cost 3-4 % on every step).
class FluidGridSystem final : public System {
public:
    FluidGridSystem() = default;
    /// @param stepping the scene's lambda_v and lambda_f (He eq. 6-7), which the drift bound needs
    /// @param place lazy positions (drift_system.hpp): a build first brings every row's position
    /// to the step's time and lists every row in res::placed; a kept grid places none.
    explicit FluidGridSystem(const SteppingParams& stepping, bool place = false)
        : m_keep(true), m_place(place), m_lambda_v(stepping.lambda_v), m_lambda_f(stepping.lambda_f) {}
    static constexpr double kMaxDrift = 0.25;    ///< of h
    static constexpr double kBuildShare = 1.0 / 64; ///< of the rows due
    std::string name() const override { return "fluid_grid"; }
    Access access() const override;
    void register_components(World& w) override;
    void run(Context& ctx) override;

private:
    /// Whether the grid may be kept this step; if so it is given its drift.
    bool kept(Context& ctx);

    bool m_keep = false;
    bool m_place = false;
    double m_lambda_v = 0, m_lambda_f = 0;
    std::int64_t m_built_at = 0;  ///< the clock (engine ticks) at the last build
    std::uint64_t m_layout = std::numeric_limits<std::uint64_t>::max();  ///< the fluid rows' layout then
    int m_steps_kept = 0;  ///< steps that kept it since
    double m_net_shift = 0;  ///< the collision net's jumps since the build, summed (m)
};

}  // namespace sph
