#pragma once
/// @file world.hpp
/// @brief All simulation data: the fluid and boundary particle sets (component stores), their
/// grids and neighbour lists, the derived physical constants and the current step's scalars.
/// Systems receive it as an argument; there are no globals.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "engine/component_store.hpp"
#include "engine/grid.hpp"
#include "engine/kernel.hpp"
#include "engine/scene.hpp"

namespace sph {

/// @brief Resource names used in system access declarations.
namespace res {
inline std::string fluid(std::string_view component) { return "fluid." + std::string(component); }
inline std::string boundary(std::string_view component) { return "boundary." + std::string(component); }
inline const std::string fluid_grid = "fluid.grid";
inline const std::string fluid_neighbours = "fluid.neighbours";
inline const std::string boundary_neighbours = "fluid.boundary_neighbours";
inline const std::string boundary_grid = "boundary.grid";
inline const std::string dt = "step.dt";
inline const std::string stats = "step.stats";
inline const std::string collisions = "step.collisions";
inline const std::string active_set = "fluid.active_set";
inline const std::string halo_set = "fluid.halo_set";
inline const std::string moving_bodies = "boundary.moving_bodies";
// PCISPH (Ihmsen et al. 2010 Alg. 2).
inline const std::string boundary_active = "boundary.active_set";          ///< + boundary->fluid lists
inline const std::string pcisph_delta = "pcisph.delta";                    ///< delta of eq. 4-5
inline const std::string pcisph_errors = "pcisph.errors";                  ///< predicted rho_err of the last pass
inline const std::string pcisph_controller = "pcisph.controller";          ///< next dt, shock request
inline const std::string fluid_count = "fluid.count";                      ///< the number of fluid particles (emitters)
}  // namespace res

/// @brief Constants derived from the scene once (SI units).
struct Physics {
    Real particle_radius = 0;
    Real spacing = 0;         ///< 2 r: lattice spacing of fluid and boundary sampling
    Real h = 0;               ///< support radius, fluid.support * 2 r (4 r by default)
    Real rest_density = 1000;
    Real mass = 0;            ///< m = rho0 / sum_j W_ij over a filled lattice (see README)
    Real speed_of_sound = 0;  ///< c_s
    Real tait_b = 0;          ///< B = rho0 c_s^2 / gamma, gamma = 7 (He eq. 2)
    Real viscosity = 0;       ///< Monaghan alpha
    Real boundary_viscosity = 0;  ///< Monaghan alpha against boundary particles (0: free-slip walls)
    Vec3 gravity = Vec3::Zero();
    double fluid_height = 0;  ///< m, used for the default c_s
};

/// @brief Simulated time is kept in integer ticks of 1 ps, so sums of steps and the activity
/// test of individual stepping (t_last + dt_i <= t) are exact; 2^63 ticks = 106 days.
using Tick = std::int64_t;
inline constexpr double kSecondsPerTick = 1e-12;
/// @brief Seconds to ticks, rounded down (a step never grows by quantisation).
inline Tick to_ticks(double seconds) { return static_cast<Tick>(std::floor(seconds / kSecondsPerTick)); }
inline double to_seconds(Tick t) { return double(t) * kSecondsPerTick; }

/// @brief Per-step scalars, written by the step's systems.
struct StepState {
    Tick t_ticks = 0;           ///< simulated time at the start of the step
    Tick dt_ticks = 0;          ///< the step being taken
    double t = 0;               ///< = to_seconds(t_ticks)
    double dt = 0;              ///< = to_seconds(dt_ticks)
    double dt_stable = 0;       ///< the step the stability conditions allow (before clipping)
    /// No step may end past this time (the run's end): the dt system clips the last step.
    double t_stop = std::numeric_limits<double>::infinity();
    std::int64_t step = 0;      ///< index of the step being taken
    std::uint64_t updated = 0;  ///< fluid particles whose forces were evaluated
    std::uint64_t neighbour_pairs = 0;  ///< fluid-fluid list entries of updated particles
    double rho_err_avg = 0, rho_err_max = 0;  ///< max(rho/rho0 - 1, 0), fluid average and max
    double v_max = 0, a_max = 0;
    Index a_max_particle = 0;
    std::uint64_t collisions = 0;  ///< particles put back on a boundary surface this step
    // Work counters (individual stepping; every fluid particle otherwise).
    std::uint64_t active = 0;                  ///< fluid particles active this step
    std::uint64_t neighbour_searches = 0;      ///< fluid particles whose lists were rebuilt
    std::uint64_t force_evaluations = 0;       ///< fluid particles whose forces were evaluated
    std::uint64_t boundary_contributions = 0;  ///< boundary list entries of those particles
    std::uint64_t propagation_updates = 0;     ///< particles whose Delta t_i was recomputed
    // PCISPH.
    int iterations = 0;                ///< prediction-correction passes
    std::uint64_t boundary_active = 0; ///< active boundary particles
    bool rolled_back = false;          ///< this step was discarded by a shock rollback
    std::uint64_t shocks = 0;          ///< rollbacks so far (kept through rollbacks)
    // The step just taken, as the recorder reports it (set by Simulation::step, also when the
    // step is rolled back and t and step no longer describe it).
    std::int64_t last_step = 0;
    double last_t = 0, last_dt = 0;

    /// @brief Sets the step (quantised down to whole ticks, at least one tick).
    void set_dt(double seconds) {
        dt_ticks = std::max<Tick>(1, to_ticks(seconds));
        dt = to_seconds(dt_ticks);
    }
    /// @brief Sets the step to at most `seconds` and never past t_stop (the run's end).
    void set_dt_clipped(double seconds) {
        set_dt(seconds);
        clip_to_stop();
    }
    /// @brief As set_dt_clipped, also at most `cap` ticks (exact: no round trip through seconds).
    void set_dt_clipped(double seconds, Tick cap) {
        set_dt(seconds);
        if (cap >= 1 && cap < dt_ticks) {
            dt_ticks = cap;
            dt = to_seconds(dt_ticks);
        }
        clip_to_stop();
    }

private:
    void clip_to_stop() {
        if (std::isfinite(t_stop)) {
            const Tick left = to_ticks(t_stop + 0.5 * kSecondsPerTick) - t_ticks;
            if (left > 0 && left < dt_ticks) {
                dt_ticks = left;
                dt = to_seconds(dt_ticks);
            }
        }
    }
};

/// @brief PCISPH state carried between steps (Ihmsen et al. 2010 Alg. 2 and sec. 3.3). Saved
/// and restored with the particle columns by a rollback.
struct PcisphState {
    double delta = 0;        ///< eq. 4-5 for delta_dt
    double delta_dt = 0;     ///< the step delta was computed for (recomputed when dt changes)
    int iterations = 0;      ///< prediction-correction passes this step
    double pred_err_max = 0, pred_err_avg = 0;  ///< last pass: max and mean of max(rho*/rho0 - 1, 0)
    double pending_dt = 0;   ///< adaptive: the step the next step takes (0: the initial rule)
    double rollback_dt = 0;  ///< > 0: a shock was detected; roll back and resume with this step (eq. 24)
    double prev_err_max = -1;  ///< rho_err^max(t - dt) for eq. 25 (< 0: none yet)
    double v_max_tracked = 0, a_max_tracked = 0;  ///< over all kept steps: v^max, F^max of eq. 14-15
    double rho_err_avg_max = 0;  ///< max over kept steps of rho_err^avg
    int reason = 0;          ///< adaptive controller's last decision (see AdaptiveDecision)
};

/// @brief Emitters' progress (one entry per scene emitter); saved and restored with the state.
struct EmitterState {
    std::vector<double> budget;          ///< particles owed (rate x elapsed time - emitted)
    std::vector<std::uint64_t> emitted;  ///< particles inserted so far
    std::uint32_t next_id = 0;           ///< id of the next inserted particle
};

/// @brief Boundary particles with at least one fluid neighbour (Ihmsen 2010 sec. 3.4: only
/// those are active) and their fluid neighbours, as compressed rows over the active set.
struct BoundaryActive {
    std::vector<Index> set;     ///< ascending boundary indices
    std::vector<Index> start;   ///< set.size() + 1 offsets into `fluid`
    std::vector<Index> fluid;   ///< fluid neighbours (r < h) of each active boundary particle
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

struct World {
    Scene scene;
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
    /// Boundaries with a motion (empty when every boundary is static), in scene order.
    std::vector<MovingBody> moving_bodies;
    /// Boundary particles [0, static_boundary_end) never move (z-ordered once).
    std::size_t static_boundary_end = 0;
    StepState step;
    PcisphState pcisph;
    BoundaryActive boundary_active;
    EmitterState emitters;
};

}  // namespace sph
