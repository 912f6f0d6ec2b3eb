#pragma once
/// @file surface.hpp
/// @brief The fluid's surface, built per frame from the particles with OpenVDB: a narrow-band
/// level set (written as .vdb, which Houdini, Blender and ParaView read) and a closed triangle
/// mesh extracted from it (written as binary .ply).
///
/// The level set is what Houdini's "VDB from Particles" builds: the union of spheres of radius
/// R = `sphere_radius` around the particle centres (OpenVDB's ParticlesToLevelSet), smoothed by
/// a Gaussian of `smoothing` width, then eroded by R - r (r the particle radius) so that the
/// surface lies r beyond the outermost centres: where the faces of a fluid block lie, since a
/// block's lattice puts its outer centres r inside them. Spheres larger than the spacing 2 r
/// overlap, so the dimples between neighbouring spheres are shallow (depth R - sqrt(R² - 2 r²)
/// over a square lattice: 0.35 r for the default R = 3 r) and the filter levels the rest.
/// Smoothing and the rounding of a block's edges still take volume away (9 % of a 15 x 10 x 10
/// block at R = 3 r), so by default (`keep_volume`) the surface is then offset once, uniformly, until it
/// encloses the particles' own volume N (2 r)³, the volume the fluid holds.
#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <vector>

#include "engine/core/types.hpp"
#include "engine/data/scene.hpp"

namespace sph {

/// @brief False when the engine was built without OpenVDB (SPH_WITH_OPENVDB=OFF): the "vdb"
/// and "mesh" formats are then refused before a run starts.
bool surface_available();

/// @brief A triangle mesh: vertices in metres, triangles counter-clockwise seen from outside
/// (outward normals), every edge shared by exactly two triangles when the surface is closed.
struct SurfaceMesh {
    std::vector<std::array<float, 3>> vertices;
    std::vector<std::array<std::uint32_t, 3>> triangles;
    /// @brief The volume enclosed (divergence theorem, sum of signed tetrahedra), m³.
    double enclosed_volume() const;
    /// @brief True when every directed edge appears once and its reverse once: closed, with
    /// consistent orientation (no holes, no flipped triangle, no edge shared by 3 or more).
    bool watertight() const;
};

/// @brief A narrow-band signed-distance level set of the fluid (negative inside), in metres.
class FluidSurface {
public:
    /// @brief Builds it from the particle centres `x` of radius `particle_radius`.
    FluidSurface(std::span<const Vec3> x, double particle_radius, const SurfaceParams::Resolved& params);
    ~FluidSurface();
    FluidSurface(FluidSurface&&) noexcept;
    FluidSurface& operator=(FluidSurface&&) noexcept;

    /// @brief The signed distance at a point (trilinear), clamped to ± the band's half width
    /// (3 voxels) away from the surface.
    double value(const Vec3d& p) const;
    /// @brief Voxels in the narrow band.
    std::uint64_t active_voxels() const;
    /// @brief The zero level set as triangles (OpenVDB's volumeToMesh, no adaptivity; each quad
    /// split into two triangles).
    SurfaceMesh mesh() const;
    /// @brief Writes the level set as one grid named "surface" (class level set, Blosc
    /// compressed) with the simulated time as file metadata "time"; atomic like every output.
    void write_vdb(const std::filesystem::path& file, double t) const;

private:
    struct Impl;
    std::unique_ptr<Impl> m;
};

/// @brief Writes a mesh as binary little-endian PLY (float x y z; uchar-counted int faces), the
/// simulated time in a comment ("t = ...", as the particle frames); atomic like every output.
void write_mesh_ply(const std::filesystem::path& file, const SurfaceMesh& mesh, double t);

}  // namespace sph
