#pragma once
/// @file sampling.hpp
/// @brief Particle sampling of fluid blocks (cubic lattice) and boundary surfaces.
#include <vector>

#include "engine/data/scene.hpp"

namespace sph {

struct SurfaceSamples {
    std::vector<Vec3d> positions;
    std::vector<Vec3d> normals;  ///< unit, pointing into the fluid side
};

/// @brief Lattice of spacing s filling `box`: min + s/2 + k s (see lattice_dims).
std::vector<Vec3d> sample_block(const Aabb& box, double spacing);

/// @brief How much of a block's declared volume its lattice holds: the lattice fills whole
/// spacings per axis (lattice_dims), each particle carrying spacing³ of fluid, so a side that
/// is not a multiple of the spacing loses up to one spacing (1.228 x 0.55 x 1.0 m at a 3 cm
/// spacing: 40 x 18 x 33 = 23,760 particles, 0.6415 m³ of 0.6754, 5.0 % short).
struct BlockFill {
    Eigen::Vector3i particles;  ///< per axis
    double declared_volume;     ///< m³
    double particle_volume;     ///< N spacing³, m³
    /// (declared - held) / declared: 0 for sides that are whole multiples of the spacing.
    double shortfall() const { return declared_volume > 0 ? 1.0 - particle_volume / declared_volume : 0.0; }
};
BlockFill block_fill(const Aabb& box, double spacing);

/// @brief Boundary surface samples at a spacing as close to `spacing` as divides each edge
/// evenly (a container's walls, a box's faces) or a Fibonacci sphere of area / spacing^2 points.
/// The samples sit `offset` (one particle radius) behind the declared surface, on the solid
/// side: a boundary particle is a sphere of radius r touching the surface, so a fluid particle
/// resting on it is one spacing from the boundary layer, as in the fluid lattice. Sampling on
/// the surface itself puts the first fluid layer at half a spacing and over-counts its density.
SurfaceSamples sample_boundary(const BoundaryDesc& b, double spacing, double offset);

}  // namespace sph
