#pragma once
/// @file recipes.hpp
/// @brief A method is a recipe of systems chosen from the scene: no boundary systems without
/// boundaries, no boundary_motion without a moving boundary, one step-size system per mode.
/// This dispatcher picks the method's recipe (wcsph.hpp, pcisph.hpp).
#include <memory>

#include "engine/run/simulation.hpp"

namespace sph {

/// @brief The recipe the scene's method and stepping mode ask for.
Recipe make_recipe(const Scene& scene);

/// @brief Convenience: a ready Simulation for a scene.
std::unique_ptr<Simulation> make_simulation(const Scene& scene);

}  // namespace sph
