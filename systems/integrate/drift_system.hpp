#pragma once
/// @file drift_system.hpp
/// @brief Binned stepping's lazy drift (He et al. Alg. 2 lines 19-21 and 9, evaluated when a
/// row is read instead of for every row every step).
///
/// A sleeping row's state at any time t is a function of its base state (x, v, rho at t_last
/// and a, drho/dt evaluated then; systems/integrate/drift.hpp), so it need not be written
/// every step. A step reads the positions of every row (the grid) and the velocity, density
/// and pressure of the active rows and their neighbours only:
/// * Positions, in one of two ways (DriftSystem::Rows):
///   - Every: DriftSystem, first in the step, writes every row's position at the step's time
///     (one streaming pass, reading 44 bytes a row and writing 12). Used when something reads
///     positions beyond the due rows' reach: the extrapolated walls' gather (2h around the due
///     rows), a grid built every step, or a moving body (measured: at 1.17 M particles in
///     `stirring_pool` the lazy placement cost more on the steps that build the grid than it
///     saved on the others; BinnedBodySystem itself reads no position).
///   - AroundDue (lazy positions): FluidGridSystem places every row when it builds the grid (it
///     reads them all anyway), and DriftSystem, after it and binned_select, places on a step
///     that keeps the grid only the rows that step reads: the due rows, and the rows of the
///     kept grid's cells within h + drift of each (what the searches read,
///     UniformGrid::ranges_within; the pair systems read a subset). res::placed lists them.
/// * DriftRowsSystem (after the neighbour search) writes velocity, density and pressure of the
///   active rows and of their fluid neighbours, and lists them in res::drifted (the rows the
///   pair systems read).
/// * AsyncIntegrationSystem(active_only) advances the active rows to the step's end.
/// Everything else stays behind until World::synchronise (drift_fluid below), which
/// Simulation calls before any whole-fluid read. A row whose t_last is the current time is
/// already current (evaluated or put back by the collision net then) and is left as it is.
#include <cstdint>
#include <span>
#include <vector>

#include "engine/data/world.hpp"
#include "engine/graph/system.hpp"

namespace sph {

/// @brief Brings every fluid row to the clock's time (velocity, position, density, pressure):
/// the World::synchronise hook of a lazy recipe.
void drift_fluid(World& w);

/// @brief Every row's position at `now` from its base state (He Alg. 2 lines 20-21; a row whose
/// t_last is now is left as it is), in one parallel streaming pass.
void place_every_row(std::span<Vec3> x, std::span<const Vec3> x0, std::span<const Vec3> v0, std::span<const Vec3> a,
                     std::span<const std::int64_t> t_last, Tick now);

class DriftSystem final : public System {
public:
    /// Which positions it writes (drift_system.hpp's contract).
    enum class Rows { Every, AroundDue };
    explicit DriftSystem(Rows rows = Rows::Every) : m_rows(rows) {}
    /// A placement around the due rows that would reach this share of the rows or more places
    /// every row instead, in the streaming pass: a row placed cell by cell costs up to ~18 times
    /// one streamed (BM_Binned_drift_around_due against BM_Binned_drift, scattered due rows).
    static constexpr double kStreamShare = 1.0 / 16;
    /// A placement by cells of this many rows or more runs in parallel over the cells.
    static constexpr std::size_t kParallelRows = 4096;
    std::string name() const override { return "drift"; }
    Access access() const override;
    /// Registers the base-state columns and installs drift_fluid as World::synchronise.
    void register_components(World& w) override;
    void run(Context& ctx) override;

private:
    Rows m_rows;
    std::vector<std::uint8_t> m_cell_mark;  ///< a cell claimed this step (cleared after use)
    std::vector<std::int64_t> m_cells;      ///< the cells claimed this step
    std::vector<Index> m_offset;            ///< each claimed cell's first entry in res::placed
};

class DriftRowsSystem final : public System {
public:
    /// @param all drift every row's velocity, density and pressure (with the walls'
    /// extrapolated pressure, Adami et al. 2012, which reads the fluid around each wall
    /// particle near an active row: up to 2h from it, beyond the active rows' lists).
    /// @param summed the density system sums rho (and p) of every active row: when every row is
    /// active, only the velocity is drifted.
    explicit DriftRowsSystem(bool all = false, bool summed = false) : m_all(all), m_summed(summed) {}
    /// From n / kStreamRows active rows on, every row is streamed without marking.
    static constexpr std::size_t kStreamRows = 16;
    /// Below that, the rows read are marked and counted; when they are this share of the rows
    /// or more, every row is streamed (at 1 % of 10^6 rows due, scattered, the scan already
    /// costs what the stream costs: BM_Binned_drift_rows, docs/results/he_table1.md).
    static constexpr double kStreamMarked = 0.5;
    std::string name() const override { return "drift_rows"; }
    Access access() const override;
    void register_components(World& w) override;
    void run(Context& ctx) override;

private:
    bool m_all;
    bool m_summed;
    std::vector<std::uint8_t> m_mark;  ///< a row claimed this step (cleared after use)
};

}  // namespace sph
