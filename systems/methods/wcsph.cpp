#include "systems/methods/wcsph.hpp"

#include "systems/boundary/boundary_collision_system.hpp"
#include "systems/boundary/boundary_volume_system.hpp"
#include "systems/density/density_system.hpp"
#include "systems/forces/forces_system.hpp"
#include "systems/integrate/symplectic_euler_system.hpp"
#include "systems/metrics/step_stats_system.hpp"
#include "systems/neighbours/neighbour_search_system.hpp"
#include "systems/timestep/global_dt_system.hpp"

namespace sph {

Recipe make_wcsph_recipe(const Scene& scene) {
    Recipe r;
    const bool boundary = !scene.boundaries.empty();
    if (boundary) r.setup.push_back(std::make_unique<BoundaryVolumeSystem>());
    r.step.push_back(std::make_unique<FluidGridSystem>());
    r.step.push_back(std::make_unique<FluidNeighbourSystem>());
    if (boundary) r.step.push_back(std::make_unique<BoundaryNeighbourSystem>());
    r.step.push_back(std::make_unique<DensitySystem>(boundary));
    r.step.push_back(std::make_unique<ForcesSystem>(boundary));
    r.step.push_back(std::make_unique<StepStatsSystem>());
    if (scene.simulation.stepping.mode == SteppingMode::Global) r.step.push_back(std::make_unique<GlobalDtSystem>());
    r.step.push_back(std::make_unique<SymplecticEulerSystem>());
    if (boundary) r.step.push_back(std::make_unique<BoundaryCollisionSystem>());
    return r;
}

Recipe make_recipe(const Scene& scene) {
    switch (scene.simulation.method) {
        case Method::Wcsph:
            return make_wcsph_recipe(scene);
    }
    return make_wcsph_recipe(scene);
}

std::unique_ptr<Simulation> make_simulation(const Scene& scene) {
    return std::make_unique<Simulation>(scene, make_recipe(scene));
}

}  // namespace sph
