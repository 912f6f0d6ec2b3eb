#pragma once
/// @file world_init.hpp
/// @brief Samples a scene into a World.
#include "engine/data/scene.hpp"
#include "engine/data/world.hpp"

namespace sph {

/// @brief Samples the scene into a World: fluid lattice, boundary surfaces, the derived
/// constants (mass, c_s, B), the domain and the grids. Registers position, velocity and id.
void initialise_world(World& world, const Scene& scene);

/// @brief The outward normals of boundary rows [begin, end), sampled from the scene again in
/// the store's row order (the boundary is static or translated, so a row's normal never
/// changes). For outputs of methods that keep no `normal` column.
std::vector<Vec3> sampled_boundary_normals(const World& world, std::size_t begin, std::size_t end);

/// @brief Registers the boundary's `normal` column, filled, unless it is there: called by the
/// systems that read normals (PCISPH's collision handling, DFSPH's wall contact), so the
/// other methods do not allocate it.
void ensure_boundary_normals(World& world);

}  // namespace sph
