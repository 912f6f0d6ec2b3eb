#pragma once
/// @file wcsph.hpp
/// @brief WCSPH as recipes of flow-graph systems: He et al. Alg. 1 with `constant` or `global`
/// (eq. 6-8) stepping, and Alg. 2 (`individual`).
#include "engine/run/simulation.hpp"

namespace sph {

Recipe make_wcsph_recipe(const Scene& scene);

}  // namespace sph
