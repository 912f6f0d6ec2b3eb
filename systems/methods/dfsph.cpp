// Bender & Koschier 2017 Alg. 1 as a recipe (see systems/dfsph/dfsph_systems.hpp for the order
// and why the divergence solve opens a step). Boundaries: Akinci et al. 2012 particles, which
// enter the density, the factor and both solvers (the boundary's pressure mirrors the fluid
// particle's, eq. 13 with k_b = k_i). That pressure only acts on compressed particles, so drops
// and thin sheets would run into the walls (`glass` without it: 51,310 net catches in 1 s and an
// exploding pour); dfsph_wall_contact removes the velocity into the wall of particles touching
// it before the density solve (Ihmsen et al. 2010 eq. 9-12 at the velocity level), and the
// collision net catches the rest (docs/results/dfsph.md).
#include "systems/methods/dfsph.hpp"

#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"
#include "engine/graph/repeat_system.hpp"
#include "systems/boundary/boundary_collision_system.hpp"
#include "systems/boundary/boundary_motion_system.hpp"
#include "systems/boundary/boundary_volume_system.hpp"
#include "systems/dfsph/dfsph_systems.hpp"
#include "systems/emit/emitter_system.hpp"
#include "systems/forces/nonpressure_forces_system.hpp"
#include "systems/metrics/step_stats_system.hpp"
#include "systems/neighbours/boundary_neighbours_system.hpp"
#include "systems/neighbours/fluid_grid_system.hpp"
#include "systems/neighbours/fluid_neighbours_system.hpp"
#include "systems/timestep/constant_dt_system.hpp"

namespace sph {

namespace {

/// The solver's loop: a pressure pass then a source pass, while the error exceeds eta or fewer
/// than `min` passes ran, at most `max`.
std::unique_ptr<System> solver_loop(DfsphSolver solver, bool boundary, bool moving, double eta, int min, int max,
                                    double relaxation, Counter counter) {
    std::vector<std::unique_ptr<System>> body;
    body.push_back(std::make_unique<DfsphPressureSystem>(solver, boundary));
    body.push_back(std::make_unique<DfsphSourceSystem>(solver, boundary, moving, relaxation));
    const bool density = solver == DfsphSolver::Density;
    auto more = [=](const Context& ctx, int k) {
        const DfsphErrors& e = ctx.read(res::dfsph_errors);
        return k < min || (k < max && (density ? e.density_error : e.divergence_error) > eta);
    };
    auto done = [=](Context& ctx, int k) {
        DfsphErrors& e = ctx.write(res::dfsph_errors);
        (density ? e.density_iterations : e.divergence_iterations) = k;
        ctx.write(counter) = std::uint64_t(k);
    };
    return std::make_unique<RepeatSystem>(density ? "dfsph_density" : "dfsph_divergence", std::move(body), more, done,
                                          Access().write(res::dfsph_errors, counter));
}

}  // namespace

Recipe make_dfsph_recipe(const Scene& scene) {
    const bool boundary = !scene.boundaries.empty();
    const bool moving = has_moving_boundaries(scene);
    const bool adaptive = scene.simulation.stepping.mode == SteppingMode::Adaptive;
    const bool viscous = artificial_viscosity(scene) > 0 || (boundary && boundary_artificial_viscosity(scene) > 0);
    const bool nonpressure = viscous || scene.fluid.surface_tension > 0;
    const DfsphParams& p = scene.dfsph;

    Recipe r;
    if (boundary) r.setup.push_back(std::make_unique<BoundaryVolumeSystem>());
    if (moving) r.step.push_back(std::make_unique<BoundaryMotionSystem>(scene.boundaries));
    if (!adaptive) r.step.push_back(std::make_unique<ConstantDtSystem>(scene.simulation.stepping.dt));
    r.step.push_back(std::make_unique<DfsphStepSizeSystem>(adaptive, p.cfl, scene.simulation.stepping.dt_max, p.eta,
                                                           p.eta_divergence));
    if (!scene.emitters.empty())
        r.step.push_back(std::make_unique<EmitterSystem>(scene.emitters, scene.simulation.scale));
    r.step.push_back(std::make_unique<FluidGridSystem>());
    r.step.push_back(std::make_unique<FluidNeighbourSystem>());
    if (boundary) r.step.push_back(std::make_unique<BoundaryNeighbourSystem>());
    // Viscosity alone rides on the factor pass (dfsph_systems.hpp); surface tension takes the
    // separate non-pressure system, viscosity included.
    const bool fused_viscosity = viscous && scene.fluid.surface_tension == 0;
    r.step.push_back(std::make_unique<DfsphFactorSystem>(boundary, moving, fused_viscosity));
    if (p.divergence) {
        r.step.push_back(std::make_unique<DfsphWarmStartSystem>(DfsphSolver::Divergence, p.warm_start));
        r.step.push_back(solver_loop(DfsphSolver::Divergence, boundary, moving, p.eta_divergence,
                                     // not over-relaxed: 1.5 raised peer_dam_break's error from 0.06 to 0.15 %
                                     p.min_divergence_iterations, p.max_divergence_iterations, 1.0,
                                     counter::divergence_iterations));
    }
    if (nonpressure && !fused_viscosity)
        r.step.push_back(std::make_unique<NonpressureForcesSystem>(boundary, moving, scene.fluid.surface_tension));
    r.step.push_back(std::make_unique<DfsphPredictSystem>(nonpressure));
    // Wall contact on v*, before the density solve (not after it: measured on hydrostatic_tank,
    // after it the wall layer is compressed, 0.57 % average density error against 0.06 %).
    if (boundary) r.step.push_back(std::make_unique<DfsphWallContactSystem>(moving));
    r.step.push_back(std::make_unique<DfsphWarmStartSystem>(DfsphSolver::Density, p.warm_start));
    r.step.push_back(solver_loop(DfsphSolver::Density, boundary, moving, p.eta, p.min_iterations, p.max_iterations,
                                 p.relaxation, counter::iterations));
    r.step.push_back(std::make_unique<DfsphIntegrateSystem>());
    if (boundary) {
        r.step.push_back(std::make_unique<BoundaryCollisionSystem>(scene.boundaries, moving));
    }
    r.step.push_back(std::make_unique<StepStatsSystem>(false));
    return r;
}

}  // namespace sph
