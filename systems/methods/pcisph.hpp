#pragma once
/// @file pcisph.hpp
/// @brief PCISPH with the boundary handling and adaptive time step of Ihmsen et al. 2010
/// (Alg. 2), as a recipe of flow-graph systems chosen from the scene.
#include "engine/run/simulation.hpp"

namespace sph {

/// @brief The prediction-correction loop is a sub-graph (RepeatSystem) run k times per step:
/// k = pcisph.iterations (`fixed`, default 3) or, for `until_converged`, while the largest
/// predicted density error exceeds eta or k < iterations, at most max_iterations.
/// `adaptive` stepping keeps a ring of two saved states for the shock rollback.
Recipe make_pcisph_recipe(const Scene& scene);

}  // namespace sph
