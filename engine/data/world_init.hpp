#pragma once
/// @file world_init.hpp
/// @brief Samples a scene into a World.
#include "engine/data/scene.hpp"
#include "engine/data/world.hpp"

namespace sph {

/// @brief Samples the scene into a World: fluid lattice, boundary surfaces, the derived
/// constants (mass, c_s, B), the domain and the grids. Registers position, velocity and id.
void initialise_world(World& world, const Scene& scene);

}  // namespace sph
