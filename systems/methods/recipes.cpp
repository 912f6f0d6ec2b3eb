#include "systems/methods/recipes.hpp"

#include "systems/methods/dfsph.hpp"
#include "systems/methods/pcisph.hpp"
#include "systems/methods/wcsph.hpp"

namespace sph {

Recipe make_recipe(const Scene& scene) {
    // A scene built or changed in code meets the loader's rules as a scene file does.
    validate_scene(scene);
    switch (scene.simulation.method) {
        case Method::Wcsph:
            return make_wcsph_recipe(scene);
        case Method::Pcisph:
            return make_pcisph_recipe(scene);
        case Method::Dfsph:
            return make_dfsph_recipe(scene);
    }
    return make_wcsph_recipe(scene);
}

std::unique_ptr<Simulation> make_simulation(const Scene& scene) {
    return std::make_unique<Simulation>(scene, make_recipe(scene));
}

}  // namespace sph
