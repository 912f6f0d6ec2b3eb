#pragma once
/// @file sampling.hpp
/// @brief Particle sampling of fluid blocks (cubic lattice) and boundary surfaces.
#include <vector>

#include "engine/scene.hpp"

namespace sph {

struct SurfaceSamples {
    std::vector<Vec3d> positions;
    std::vector<Vec3d> normals;  ///< unit, pointing into the fluid side
};

/// @brief Lattice of spacing s filling `box`: min + s/2 + k s (see lattice_dims).
std::vector<Vec3d> sample_block(const Aabb& box, double spacing);

/// @brief Boundary surface samples at a spacing as close to `spacing` as divides each edge
/// evenly (a container's walls, a box's faces) or a Fibonacci sphere of area / spacing^2 points.
SurfaceSamples sample_boundary(const BoundaryDesc& b, double spacing);

}  // namespace sph
