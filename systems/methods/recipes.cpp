#include "systems/methods/recipes.hpp"

#include <string>

#include "engine/core/errors.hpp"
#include "systems/methods/dfsph.hpp"
#include "systems/methods/pcisph.hpp"
#include "systems/methods/wcsph.hpp"

namespace sph {

Recipe make_recipe(const Scene& scene) {
    // A scene built in code does not pass the loader's checks; this one guards a recipe that would
    // blow up (docs/methods.md, "Known limitations"), as the loader does for a scene file.
    if (!method_takes_support(scene.simulation.method, scene.fluid.support))
        throw InputError("fluid.support = " + std::to_string(scene.fluid.support) + ": methods \"pcisph\" and "
                         "\"dfsph\" run with the kernel support of 2 particle spacings only");
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
