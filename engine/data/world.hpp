#pragma once
/// @file world.hpp
/// @brief All simulation data: the fluid and boundary particle sets (component stores), their
/// grids and neighbour lists, the derived physical constants, the clock, the step's scalars
/// and counters, and the resources systems own. There are no globals.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "engine/core/access.hpp"
#include "engine/core/component_store.hpp"
#include "engine/core/resources.hpp"
#include "engine/core/grid.hpp"
#include "engine/core/kernel.hpp"
#include "engine/data/scene.hpp"

namespace sph {

/// @brief Constants derived from the scene once (SI units).
struct Physics {
    Real particle_radius = 0;
    Real spacing = 0;         ///< 2 r: lattice spacing of fluid and boundary sampling
    Real h = 0;               ///< support radius, fluid.support * 2 r (4 r by default)
    Real rest_density = 1000;
    Real mass = 0;            ///< m = rho0 / sum_j W_ij over a filled lattice (docs/methods.md)
    Real speed_of_sound = 0;  ///< c_s
    Real tait_b = 0;          ///< B = rho0 c_s^2 / gamma, gamma = 7 (He eq. 2)
    Real viscosity = 0;       ///< Monaghan alpha
    Real boundary_viscosity = 0;  ///< Monaghan alpha against boundary particles (0: free-slip walls)
    /// WCSPH `fluid.density: continuity`: the density is integrated (He eq. 5 plus diffusion).
    bool continuity = false;
    Real density_diffusion = 0;     ///< delta-SPH delta (continuity only; 0: none)
    bool extrapolated_wall_pressure = false;  ///< WallPressure::Extrapolated (WCSPH)
    Real kinematic_viscosity = 0;   ///< nu of the laminar term (Morris et al. 1997), m^2/s
    Vec3 gravity = Vec3::Zero();
    double fluid_height = 0;  ///< m, used for the default c_s
    /// Pair loops take the vectorised path (simulation.simd; never with SPH_DOUBLE).
    bool simd = true;
};

/// @brief Simulated time is kept in integer ticks of 1 ps, so sums of steps and the activity
/// test of individual stepping (t_last + dt_i <= t) are exact; 2^63 ticks = 106 days.
using Tick = std::int64_t;
inline constexpr double kSecondsPerTick = 1e-12;
/// @brief Seconds to ticks, rounded down (a step never grows by quantisation).
inline Tick to_ticks(double seconds) { return static_cast<Tick>(std::floor(seconds / kSecondsPerTick)); }
inline double to_seconds(Tick t) { return double(t) * kSecondsPerTick; }

/// @brief Where the run is in time. Owned by the engine (Simulation advances it between steps);
/// constant while a step's graph runs, so every system may read it without declaring it.
struct Clock {
    Tick t_ticks = 0;           ///< simulated time at the start of the step
    double t = 0;               ///< = to_seconds(t_ticks)
    std::int64_t step = 0;      ///< index of the step being taken
    /// No step may end past this time (the run's end): the step-size system clips the last step.
    double t_stop = std::numeric_limits<double>::infinity();
    std::uint64_t rollbacks = 0;  ///< steps discarded by a rollback so far (kept through rollbacks)
    /// Fluid rows evaluated since the last spatial sort (binned and individual stepping sort by it:
    /// Simulation::sort_due).
    std::uint64_t rows_since_sort = 0;
};

/// @brief The step being taken (res::dt): written by the step-size system(s) of each recipe
/// (the last writer in recipe order owns it and is named when it collapses), read by the
/// integrators.
struct StepSize {
    Tick dt_ticks = 0;      ///< the step being taken
    double dt = 0;          ///< = to_seconds(dt_ticks)
    double dt_stable = 0;   ///< the step the stability conditions allow (before clipping)

    /// @brief Sets the step (quantised down to whole ticks, at least one tick).
    void set(double seconds) {
        dt_ticks = std::max<Tick>(1, to_ticks(seconds));
        dt = to_seconds(dt_ticks);
    }
    /// @brief Sets the step to at most `seconds` and never past clock.t_stop (the run's end).
    void set_clipped(double seconds, const Clock& clock) {
        set(seconds);
        clip_to_stop(clock);
    }
    /// @brief As set_clipped, also at most `cap` ticks (exact: no round trip through seconds).
    void set_clipped(double seconds, Tick cap, const Clock& clock) {
        set(seconds);
        if (cap >= 1 && cap < dt_ticks) {
            dt_ticks = cap;
            dt = to_seconds(dt_ticks);
        }
        clip_to_stop(clock);
    }

private:
    void clip_to_stop(const Clock& clock) {
        if (std::isfinite(clock.t_stop)) {
            const Tick left = to_ticks(clock.t_stop + 0.5 * kSecondsPerTick) - clock.t_ticks;
            if (left > 0 && left < dt_ticks) {
                dt_ticks = left;
                dt = to_seconds(dt_ticks);
            }
        }
    }
};

/// @brief Whole-fluid statistics of the step (res::stats), written by step_stats.
struct StepStats {
    double rho_err_avg = 0, rho_err_max = 0;  ///< max(rho/rho0 - 1, 0), fluid average and max
    double v_max = 0, a_max = 0;
    /// Mean |v_i| over the rows step_stats reduced (every row, or binned's active rows), m/s.
    /// A diagnostic (stats.csv's v_mean): no system reads it, and checkpoints do not hold it.
    double v_mean = 0;
    Index a_max_particle = 0;
    /// True when the figures above are over every fluid row (every mode but `binned`, and
    /// `binned`'s steps with every row due); false on `binned`'s steps that reduce over the due
    /// rows only, whose average is not the fluid's (stats.csv's `whole_fluid`; summary.json's
    /// max_avg_density_error is taken over the true steps).
    bool whole_fluid = true;
};

/// @brief A request to discard the last steps (res::rollback). A system that finds the step
/// unusable sets `request_dt` (> 0: the step to resume with); after the graph the engine
/// restores the state saved Recipe::rollback_steps steps back, clears the request and puts
/// the step into `resume_dt`, which the requesting method reads at the next step.
struct Rollback {
    double request_dt = 0;
    double resume_dt = 0;
    std::string requested_by;  ///< the system that asked (named in errors)
    std::string reason;        ///< what it found (named in errors)
};

/// @brief A boundary that moves with a kinematic motion: its boundary particles are the
/// contiguous range [begin, end) of the boundary store (after the static particles). Updated
/// every step by the boundary motion system; read by individual stepping to wake fluid
/// particles it comes near.
struct MovingBody {
    std::size_t begin = 0, end = 0;  ///< boundary particle range
    std::size_t boundary = 0;        ///< index of its description in scene.boundaries
    Aabb bounds;                     ///< current bounding box of its boundary particles, m
    /// Bound on the speed of its points from now on, m/s (speed_bound of its motion; a
    /// translation moves every point at the same speed).
    double speed = 0;
};

struct ParticleSet {
    ComponentStore store;
    std::size_t size() const { return store.size(); }
};

/// @brief Everything a run holds. Systems never get a World: they get a Context (context.hpp)
/// made from their declared Access, which hands out the parts below by typed handle (res::,
/// counter::, fluid(comp::...)). The constants (physics, kernel, domain, clock) are read-only
/// for systems. Movable, not copyable (a copy would duplicate the owned resources silently);
/// never moved once a graph's contexts refer to it.
struct World {
    World() = default;
    World(const World&) = delete;
    World& operator=(const World&) = delete;
    World(World&&) = default;
    World& operator=(World&&) = default;

    Scene scene;  ///< the scene as loaded (outputs and probes read it; systems get parameters)
    Physics physics;
    Aabb domain;
    CubicSpline kernel{1};
    ParticleSet fluid;
    ParticleSet boundary;
    UniformGrid fluid_grid;
    UniformGrid boundary_grid;
    NeighbourLists fluid_neighbours;     ///< fluid -> fluid (self excluded)
    NeighbourLists boundary_neighbours;  ///< fluid -> boundary
    /// Individual stepping: active particles (ascending), and the inactive neighbours of
    /// active particles (ascending), both rebuilt each step.
    std::vector<Index> active_set;
    std::vector<Index> halo_set;
    /// Binned stepping: the particles the collision net moved this step (ascending); their
    /// steps are cut to end at the next due time (BinnedWakeSystem).
    std::vector<Index> collided;
    /// Binned stepping: the rows whose velocity, density and pressure were brought to the
    /// step's time for the pair systems (the active rows and their fluid neighbours, ascending;
    /// DriftRowsSystem). The other sleeping rows are drifted lazily: see `synchronise`.
    std::vector<Index> drifted;
    /// Binned stepping with lazy positions: the rows whose position the system running brought
    /// to the step's time (FluidGridSystem: every row, in order, when it builds; DriftSystem:
    /// the rows a kept grid's searches around the due rows read). The others lag until read.
    std::vector<Index> placed;
    /// Binned stepping: the rows whose step BinnedStepSystem set this step (the active rows and
    /// the sleeping ones it woke, ascending), where it wrote their Delta t_i.
    std::vector<Index> stepped;
    /// Set by a recipe whose step leaves rows behind the clock (binned stepping's lazy drift):
    /// brings every fluid row to the clock's time. Simulation::synchronise calls it before
    /// anything reads the whole fluid (observers, the spatial sort, the end of a run).
    std::function<void(World&)> synchronise;
    /// Boundaries with a motion (empty when every boundary is static), in scene order.
    std::vector<MovingBody> moving_bodies;
    /// Boundary particles [0, static_boundary_end) never move (z-ordered once).
    std::size_t static_boundary_end = 0;
    Clock clock;
    StepSize step_size;
    StepStats stats;
    Rollback rollback;
    /// Per-step counters by name (counter::), each written by the system that declares it.
    std::map<std::string, std::uint64_t, std::less<>> counters;
    /// Resources owned by systems (a method's state), by name.
    ResourceStore resources;

    ComponentStore& store(SetId set) { return set == SetId::Fluid ? fluid.store : boundary.store; }
    const ComponentStore& store(SetId set) const { return set == SetId::Fluid ? fluid.store : boundary.store; }
    /// @brief A counter's value (0 when no system of the recipe declares it).
    std::uint64_t counter_value(std::string_view name) const {
        const auto it = counters.find(name);
        return it == counters.end() ? 0 : it->second;
    }
};

/// @brief The engine's resources, by typed handle.
namespace res {
inline constexpr Resource<UniformGrid> fluid_grid{"fluid.grid", &World::fluid_grid};
inline constexpr Resource<NeighbourLists> fluid_neighbours{"fluid.neighbours", &World::fluid_neighbours};
inline constexpr Resource<NeighbourLists> boundary_neighbours{"fluid.boundary_neighbours", &World::boundary_neighbours};
inline constexpr Resource<UniformGrid> boundary_grid{"boundary.grid", &World::boundary_grid};
inline constexpr Resource<StepSize> dt{"step.dt", &World::step_size};
inline constexpr Resource<StepStats> stats{"step.stats", &World::stats};
inline constexpr Resource<Rollback> rollback{"step.rollback", &World::rollback};
inline constexpr Resource<std::vector<Index>> active_set{"fluid.active_set", &World::active_set};
inline constexpr Resource<std::vector<Index>> halo_set{"fluid.halo_set", &World::halo_set};
inline constexpr Resource<std::vector<Index>> collided{"fluid.collided", &World::collided};
inline constexpr Resource<std::vector<Index>> drifted{"fluid.drifted", &World::drifted};
inline constexpr Resource<std::vector<Index>> placed{"fluid.placed", &World::placed};
inline constexpr Resource<std::vector<Index>> stepped{"fluid.stepped", &World::stepped};
inline constexpr Resource<std::vector<MovingBody>> moving_bodies{"boundary.moving_bodies", &World::moving_bodies};
}  // namespace res

/// @brief The counters of the standard stats.csv columns (a system may declare others).
namespace counter {
inline constexpr Counter updated{"updated"};                  ///< fluid particles whose forces were evaluated
inline constexpr Counter neighbour_pairs{"neighbour_pairs"};  ///< fluid-fluid list entries of those
inline constexpr Counter collisions{"collisions"};            ///< particles put back on a boundary surface
/// those of `collisions` that had no fluid neighbour: a lone droplet's contact with a wall
inline constexpr Counter droplet_contacts{"droplet_contacts"};
inline constexpr Counter active{"active"};                    ///< fluid particles active this step
inline constexpr Counter neighbour_searches{"neighbour_searches"};  ///< lists rebuilt
inline constexpr Counter force_evaluations{"force_evaluations"};    ///< forces evaluated
inline constexpr Counter boundary_contributions{"boundary_contributions"};  ///< boundary entries of those
inline constexpr Counter propagation_updates{"propagation_updates"};  ///< Delta t_i recomputed
inline constexpr Counter iterations{"iterations"};            ///< solver passes
inline constexpr Counter boundary_active{"boundary_active"};  ///< active boundary particles
inline constexpr Counter woken{"woken"};                      ///< sleeping particles whose step the limiter cut
inline constexpr Counter limiter_passes{"limiter_passes"};    ///< passes of the limiter to its fixed point
inline constexpr Counter grid_kept{"grid_kept"};              ///< 1 when the fluid grid was kept (drifted), 0 when built
}  // namespace counter

}  // namespace sph
