#pragma once
/// @file wcsph.hpp
/// @brief Methods are recipes of systems chosen from the scene: no boundary systems without
/// boundaries, no boundary_motion system without a moving boundary, no dt system for
/// `constant` stepping.
#include <memory>

#include "engine/simulation.hpp"

namespace sph {

/// @brief WCSPH (He et al. Alg. 1) with `constant` or `global` (He eq. 6-8) stepping.
Recipe make_wcsph_recipe(const Scene& scene);

/// @brief The recipe the scene's method and stepping mode ask for.
Recipe make_recipe(const Scene& scene);

/// @brief Convenience: a ready Simulation for a scene.
std::unique_ptr<Simulation> make_simulation(const Scene& scene);

}  // namespace sph
