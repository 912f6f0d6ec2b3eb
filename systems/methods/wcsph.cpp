#include "systems/methods/wcsph.hpp"

#include "systems/active/binned_body_system.hpp"
#include "systems/active/binned_select_system.hpp"
#include "systems/active/select_active_system.hpp"
#include "systems/boundary/boundary_collision_system.hpp"
#include "systems/boundary/boundary_motion_system.hpp"
#include "systems/boundary/boundary_volume_system.hpp"
#include "systems/boundary/wall_pressure_system.hpp"
#include "systems/density/density_system.hpp"
#include "systems/forces/forces_system.hpp"
#include "systems/forces/gradient_correction_system.hpp"
#include "systems/integrate/async_integration_system.hpp"
#include "systems/integrate/drift_system.hpp"
#include "systems/integrate/symplectic_euler_system.hpp"
#include "systems/metrics/step_stats_system.hpp"
#include "systems/neighbours/boundary_neighbours_system.hpp"
#include "systems/neighbours/fluid_grid_system.hpp"
#include "systems/neighbours/fluid_neighbours_system.hpp"
#include "systems/timestep/dt_propagation_system.hpp"
#include "systems/timestep/individual_dt_system.hpp"
#include "systems/timestep/binned_step_system.hpp"
#include "systems/timestep/binned_wake_system.hpp"
#include "systems/timestep/constant_dt_system.hpp"
#include "systems/timestep/global_dt_system.hpp"

namespace sph {

Recipe make_wcsph_recipe(const Scene& scene) {
    Recipe r;
    const bool boundary = !scene.boundaries.empty();
    const SteppingMode mode = scene.simulation.stepping.mode;
    const bool binned = mode == SteppingMode::Binned;
    // Both per-particle modes evaluate only their active set (the `individual` flag of the
    // neighbour, density and force systems); they differ in selection, step rule and stats.
    const bool individual = mode == SteppingMode::Individual || binned;
    const bool moving = has_moving_boundaries(scene);
    if (boundary) r.setup.push_back(std::make_unique<BoundaryVolumeSystem>());
    // Kinematic boundaries are placed at the step's time before anything reads them.
    if (moving) r.step.push_back(std::make_unique<BoundaryMotionSystem>(scene.boundaries));
    // He et al. Alg. 2 (individual) or Alg. 1 with eq. 6-8 (global) / a fixed step (constant);
    // binned: power-of-two bins with a neighbour limiter (systems/timestep/binned_step_system.hpp).
    const SteppingParams& stepping = scene.simulation.stepping;
    if (mode == SteppingMode::Constant) r.step.push_back(std::make_unique<ConstantDtSystem>(stepping.dt));
    if (mode == SteppingMode::Individual)
        r.step.push_back(std::make_unique<SelectActiveSystem>(stepping.activation));
    // The walls' pressure from the fluid around them (Adami et al. 2012), once the fluid's is known.
    const bool extrapolated = boundary && wall_pressure(scene) == WallPressure::Extrapolated;
    // binned: the lazy drift (systems/integrate/drift_system.hpp). Positions are placed lazily
    // (the grid's build places every row, a kept grid's step the rows around the due ones)
    // unless something reads positions beyond the due rows' reach (the extrapolated walls'
    // gather), the grid is built every step, or a body moves (measured: docs/results/benchmarks.md,
    // "A moving body's wake-up"). Then every row's position at the step's time, before anything
    // reads one.
    const bool lazy_positions = binned && stepping.keep_grid && !moving && !extrapolated;
    if (binned && !lazy_positions) r.step.push_back(std::make_unique<DriftSystem>());
    if (binned) r.step.push_back(std::make_unique<BinnedSelectSystem>(stepping.dt_min, stepping.dt_max));
    // binned: the rows within a moving body's reach made due, from a list of candidates.
    if (binned && moving) r.step.push_back(std::make_unique<BinnedBodySystem>(stepping));
    // binned: the grid kept while the due rows are few and no row can have moved far.
    r.step.push_back(binned && stepping.keep_grid ? std::make_unique<FluidGridSystem>(stepping, lazy_positions)
                                                  : std::make_unique<FluidGridSystem>());
    if (lazy_positions) r.step.push_back(std::make_unique<DriftSystem>(DriftSystem::Rows::AroundDue));
    // binned reads only the active particles' lists: compact, the others emptied.
    r.step.push_back(std::make_unique<FluidNeighbourSystem>(individual, !binned));
    if (boundary) r.step.push_back(std::make_unique<BoundaryNeighbourSystem>(individual, !binned, lazy_positions));
    // binned: velocity, density and pressure of the rows the pair systems read (every row when
    // the extrapolated walls read the fluid beyond the active rows' lists).
    const bool continuity = density_form(scene) == DensityForm::Continuity;
    if (binned) r.step.push_back(std::make_unique<DriftRowsSystem>(extrapolated, !continuity));
    r.step.push_back(std::make_unique<DensitySystem>(boundary, individual, continuity, moving));
    if (extrapolated) r.step.push_back(std::make_unique<WallPressureSystem>(individual));
    const bool corrected = scene.fluid.pressure_gradient == PressureGradient::Corrected;
    if (corrected) r.step.push_back(std::make_unique<GradientCorrectionSystem>(boundary, individual));
    r.step.push_back(
        std::make_unique<ForcesSystem>(boundary, individual, moving, corrected, stepping, continuity, extrapolated));
    r.step.push_back(std::make_unique<StepStatsSystem>(
        individual, binned ? StepStatsSystem::Rows::Active : StepStatsSystem::Rows::All));
    if (binned) {
        // Limiter, wake-up and the next due time, then He Alg. 2 lines 18-21 for the active rows
        // (the others are drifted when read).
        r.step.push_back(std::make_unique<BinnedStepSystem>(stepping.dt_min, stepping.dt_max));
        r.step.push_back(std::make_unique<AsyncIntegrationSystem>(true));
    } else if (individual) {
        r.step.push_back(std::make_unique<DtPropagationSystem>());
        r.step.push_back(std::make_unique<IndividualGlobalDtSystem>(stepping.activation, stepping.dt_max));
        r.step.push_back(std::make_unique<AsyncIntegrationSystem>());
    } else {
        if (mode == SteppingMode::Global) r.step.push_back(std::make_unique<GlobalDtSystem>(stepping));
        r.step.push_back(std::make_unique<SymplecticEulerSystem>());
    }
    // Droplet contacts counted apart (the net is their contact by design, DensitySystem).
    if (boundary)
        r.step.push_back(std::make_unique<BoundaryCollisionSystem>(scene.boundaries, moving, binned, true));
    if (boundary && binned) r.step.push_back(std::make_unique<BinnedWakeSystem>());
    return r;
}

}  // namespace sph
