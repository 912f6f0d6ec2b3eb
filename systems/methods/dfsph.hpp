#pragma once
/// @file dfsph.hpp
/// @brief Divergence-free SPH (Bender & Koschier 2015, 2017 Alg. 1) with Akinci et al. 2012
/// boundary particles, as a recipe of flow-graph systems chosen from the scene.
#include "engine/run/simulation.hpp"

namespace sph {

/// @brief Each solver is a sub-graph (RepeatSystem) of a pressure pass and a source pass, run
/// while its average error exceeds its eta or fewer than its minimum passes ran, at most its
/// maximum. `adaptive` stepping is the CFL step; `constant` the scene's dt.
Recipe make_dfsph_recipe(const Scene& scene);

}  // namespace sph
