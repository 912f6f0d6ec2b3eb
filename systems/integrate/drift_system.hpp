#pragma once
/// @file drift_system.hpp
/// @brief Binned stepping's lazy drift (He et al. Alg. 2 lines 19-21 and 9, evaluated when a
/// row is read instead of for every row every step).
///
/// A sleeping row's state at any time t is a function of its base state (x, v, rho at t_last
/// and a, drho/dt evaluated then; systems/integrate/drift.hpp), so it need not be written
/// every step. A step reads the positions of every row (the grid) and the velocity, density
/// and pressure of the active rows and their neighbours only:
/// * DriftSystem (first in the step) writes every row's position at the step's time: the one
///   streaming pass over all rows, reading 40 bytes a row and writing 12.
/// * DriftRowsSystem (after the neighbour search) writes velocity, density and pressure of the
///   active rows and of their fluid neighbours, and lists them in res::drifted (the rows the
///   pair systems read).
/// * AsyncIntegrationSystem(active_only) advances the active rows to the step's end.
/// Everything else stays behind until World::synchronise (drift_fluid below), which
/// Simulation calls before any whole-fluid read. A row whose t_last is the current time is
/// already current (evaluated or put back by the collision net then) and is left as it is.
#include "engine/graph/system.hpp"

namespace sph {

/// @brief Brings every fluid row to the clock's time (velocity, position, density, pressure):
/// the World::synchronise hook of a lazy recipe.
void drift_fluid(World& w);

class DriftSystem final : public System {
public:
    std::string name() const override { return "drift"; }
    Access access() const override;
    /// Registers the base-state columns and installs drift_fluid as World::synchronise.
    void register_components(World& w) override;
    void run(Context& ctx) override;
};

class DriftRowsSystem final : public System {
public:
    /// @param all drift every row's velocity, density and pressure (with the walls'
    /// extrapolated pressure, Adami et al. 2012, which reads the fluid around each wall
    /// particle near an active row: up to 2h from it, beyond the active rows' lists).
    /// @param summed the density system sums rho (and p) of every active row: when every row is
    /// active, only the velocity is drifted.
    explicit DriftRowsSystem(bool all = false, bool summed = false) : m_all(all), m_summed(summed) {}
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
