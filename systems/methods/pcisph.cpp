// Ihmsen et al. 2010 Alg. 2 as a recipe. Why the loop is a sub-graph run k times and not a
// cycle in the outer graph: the outer graph is a DAG derived from declared accesses and built
// once; a cycle would need a conditional (multifunction) node and edges that bypass the
// derivation. A RepeatSystem keeps both graphs acyclic and derived, its body's phases still
// run as separate, timed nodes (fluid and boundary density concurrently), and the number of
// passes is decided from data after each pass (until_converged) at no extra cost.
#include "systems/methods/pcisph.hpp"

#include "engine/graph/repeat_system.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"
#include "systems/pcisph/pcisph_state.hpp"
#include "systems/timestep/constant_dt_system.hpp"
#include "systems/timestep/global_dt_system.hpp"
#include "systems/boundary/boundary_collision_system.hpp"
#include "systems/boundary/boundary_motion_system.hpp"
#include "systems/boundary/boundary_volume_system.hpp"
#include "systems/pcisph/boundary_active_system.hpp"
#include "systems/pcisph/boundary_mass_system.hpp"
#include "systems/pcisph/predict_collision_system.hpp"
#include "systems/pcisph/world_collision_system.hpp"
#include "systems/emit/emitter_system.hpp"
#include "systems/forces/nonpressure_forces_system.hpp"
#include "systems/metrics/step_stats_system.hpp"
#include "systems/neighbours/boundary_neighbours_system.hpp"
#include "systems/neighbours/fluid_grid_system.hpp"
#include "systems/neighbours/fluid_neighbours_system.hpp"
#include "systems/pcisph/pcisph_boundary_density_system.hpp"
#include "systems/pcisph/pcisph_config.hpp"
#include "systems/pcisph/pcisph_density_system.hpp"
#include "systems/pcisph/pcisph_integrate_system.hpp"
#include "systems/pcisph/pcisph_predict_system.hpp"
#include "systems/pcisph/pcisph_pressure_force_system.hpp"
#include "systems/pcisph/pcisph_reset_system.hpp"
#include "systems/pcisph/pcisph_step_size_system.hpp"
#include "systems/timestep/adaptive_dt_system.hpp"

namespace sph {

Recipe make_pcisph_recipe(const Scene& scene) {
    PcisphConfig c;
    c.boundary = !scene.boundaries.empty();
    c.ihmsen = c.boundary && scene.boundary.handling == BoundaryHandling::Ihmsen;
    c.moving = has_moving_boundaries(scene);
    c.adaptive = scene.simulation.stepping.mode == SteppingMode::Adaptive;
    c.nonpressure = artificial_viscosity(scene) > 0 || (c.boundary && boundary_artificial_viscosity(scene) > 0) ||
                    scene.fluid.surface_tension > 0;

    Recipe r;
    if (c.boundary) r.setup.push_back(std::make_unique<BoundaryVolumeSystem>());
    if (c.ihmsen) r.setup.push_back(std::make_unique<BoundaryMassSystem>());

    if (c.moving) r.step.push_back(std::make_unique<BoundaryMotionSystem>(scene.boundaries));
    const AdaptiveParams adaptive = adaptive_params(scene);
    if (!c.adaptive) r.step.push_back(std::make_unique<ConstantDtSystem>(scene.simulation.stepping.dt));
    r.step.push_back(std::make_unique<PcisphStepSizeSystem>(
        c.adaptive, adaptive, scene.simulation.gravity.norm(),
        PcisphStepSizeSystem::SummaryInfo{to_string(scene.boundary.handling), scene.pcisph.eta}));
    if (!scene.emitters.empty())
        r.step.push_back(std::make_unique<EmitterSystem>(scene.emitters, scene.simulation.scale));
    r.step.push_back(std::make_unique<FluidGridSystem>());
    r.step.push_back(std::make_unique<FluidNeighbourSystem>());
    if (c.boundary) r.step.push_back(std::make_unique<BoundaryNeighbourSystem>());
    if (c.ihmsen) r.step.push_back(std::make_unique<BoundaryActiveSystem>());
    if (c.nonpressure)
        r.step.push_back(std::make_unique<NonpressureForcesSystem>(c.boundary, c.moving, scene.fluid.surface_tension));
    r.step.push_back(std::make_unique<PcisphResetSystem>(c.ihmsen));

    std::vector<std::unique_ptr<System>> body;
    body.push_back(std::make_unique<PcisphPredictSystem>(c.nonpressure));
    const double friction = scene.boundary.friction;
    if (c.boundary) body.push_back(std::make_unique<PredictCollisionSystem>(c.moving, friction));
    body.push_back(std::make_unique<PcisphDensitySystem>(c.ihmsen));
    if (c.ihmsen) body.push_back(std::make_unique<PcisphBoundaryDensitySystem>());
    body.push_back(std::make_unique<PcisphPressureForceSystem>(c.ihmsen));
    const PcisphParams p = scene.pcisph;
    auto more = [p](const Context& ctx, int k) {
        if (p.loop == PcisphLoop::Fixed) return k < p.iterations;
        // Solenthaler & Pajarola 2009: while max rho_err* > eta or k < 3 (here `iterations`).
        return k < p.max_iterations && (ctx.read(res::pcisph_errors).pred_err_max > p.eta || k < p.iterations);
    };
    auto done = [](Context& ctx, int k) {
        ctx.write(res::pcisph_errors).iterations = k;
        ctx.write(counter::iterations) = std::uint64_t(k);
    };
    r.step.push_back(std::make_unique<RepeatSystem>("pcisph_iterations", std::move(body), more, done,
                                                    Access().write(res::pcisph_errors, counter::iterations)));

    r.step.push_back(std::make_unique<PcisphIntegrateSystem>(c.nonpressure));
    if (c.boundary) {
        r.step.push_back(std::make_unique<WorldCollisionSystem>(c.moving, friction));  // eq. 11-12
        r.step.push_back(std::make_unique<BoundaryCollisionSystem>(scene.boundaries, c.moving));  // safety net
    }
    r.step.push_back(std::make_unique<StepStatsSystem>(false));
    if (c.adaptive) {
        r.step.push_back(std::make_unique<AdaptiveDtSystem>(adaptive));
        r.rollback_steps = 2;  // sec. 3.3: "we go two simulation steps backwards"
    }
    return r;
}

}  // namespace sph
