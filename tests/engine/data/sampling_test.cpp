// Boundary sampling of the shapes PCISPH scenes use (Ihmsen et al. 2010 sec. 3.2: spacing
// r0 = h/2, normals towards the fluid), and the OBJ reader. Expected values are geometric:
// distances to the declared surface, coverage of the surface, normal directions.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <filesystem>
#include <fstream>
#include <random>

#include "engine/core/errors.hpp"
#include "engine/data/sampling.hpp"

using namespace sph;

namespace {
std::filesystem::path write_temp(const std::string& name, const std::string& text) {
    const auto p = std::filesystem::temp_directory_path() / name;
    std::ofstream(p) << text;
    return p;
}
}  // namespace

TEST(ObjReader, FansPolygonsAndResolvesNegativeIndices) {
    const auto p = write_temp("sph_quad.obj", "# quad\nv 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nvn 0 1 0\nf 1/1/1 4 3 2\nf -4 -3 -2\n");
    std::vector<Vec3d> v;
    std::vector<std::array<int, 3>> t;
    read_obj(p, v, t);
    ASSERT_EQ(v.size(), 4u);
    ASSERT_EQ(t.size(), 3u);  // the quad fans into 2 triangles, plus one triangle by negative indices
    EXPECT_EQ(t[0], (std::array<int, 3>{0, 3, 2}));
    EXPECT_EQ(t[1], (std::array<int, 3>{0, 2, 1}));
    EXPECT_EQ(t[2], (std::array<int, 3>{0, 1, 2}));
}

TEST(ObjReader, MalformedLinesNameFileAndLine) {
    std::vector<Vec3d> v;
    std::vector<std::array<int, 3>> t;
    const auto p = write_temp("sph_bad.obj", "v 0 0 0\nv 1 0 x\n");
    try {
        read_obj(p, v, t);
        FAIL() << "no error";
    } catch (const InputError& e) {
        EXPECT_EQ(std::string(e.what()), p.string() + ":2: invalid number \"x\" in \"v 1 0 x\"");
    }
    const auto q = write_temp("sph_bad2.obj", "v 0 0 0\nv 1 0 0\nf 1 2 3\n");
    try {
        read_obj(q, v, t);
        FAIL() << "no error";
    } catch (const InputError& e) {
        EXPECT_EQ(std::string(e.what()), q.string() + ":3: vertex 3 is not defined before this face (2 so far) in \"f 1 2 3\"");
    }
}

// A 1 x 1 m square of two triangles facing up, sampled at s = 0.1 with offset 0.05: every
// sample 0.05 below the plane with normal +y; every point of the square within s / sqrt(2)
// (half a lattice diagonal) of a sample; no two samples closer than s / 4 (shared edge merged).
TEST(BoundarySampling, TrianglesAreSampledEvenlyBehindTheirFront) {
    BoundaryDesc b;
    b.shape = BoundaryShape::Mesh;
    b.vertices = {Vec3d(0, 0, 0), Vec3d(1, 0, 0), Vec3d(1, 0, 1), Vec3d(0, 0, 1)};
    b.triangles = {{0, 3, 2}, {0, 2, 1}};  // counter-clockwise seen from +y
    const double s = 0.1;
    const SurfaceSamples ss = sample_boundary(b, s, 0.05);
    EXPECT_EQ(ss.positions.size(), 121u);  // the 11 x 11 lattice, diagonal samples merged
    for (std::size_t i = 0; i < ss.positions.size(); ++i) {
        EXPECT_NEAR(ss.positions[i].y(), -0.05, 1e-12);
        EXPECT_NEAR((ss.normals[i] - Vec3d::UnitY()).norm(), 0.0, 1e-12);
        for (std::size_t j = 0; j < i; ++j) EXPECT_GE((ss.positions[i] - ss.positions[j]).norm(), s / 4);
    }
    std::mt19937 rng(1);
    std::uniform_real_distribution<double> u(0, 1);
    for (int k = 0; k < 500; ++k) {
        const Vec3d p(u(rng), -0.05, u(rng));
        double best = 1e9;
        for (const auto& q : ss.positions) best = std::min(best, (p - q).norm());
        EXPECT_LE(best, s / std::sqrt(2.0) + 1e-9);
    }
}

// A height field sloping 1:3 along x: samples sit `offset` below the surface along its normal,
// which points up the slope's face: n = (-1, 3, 0) / sqrt(10).
TEST(BoundarySampling, HeightFieldNormalsAndOffset) {
    const std::string text = R"({"name": "t", "simulation": {"method": "pcisph"},
        "fluid_blocks": [{"min": [0, 0.5, 0], "max": [0.2, 0.7, 0.2]}],
        "boundaries": [{"type": "heightfield", "min": [0, 0, 0], "max": [3, 1, 1], "heights": [[0, 1], [0, 1]]}]})";
    const Scene sc = parse_scene(text, "hf.json");
    const SurfaceSamples ss = sample_boundary(sc.boundaries[0], 0.1, 0.02);
    const Vec3d n = Vec3d(-1, 3, 0).normalized();
    ASSERT_GT(ss.positions.size(), 300u);
    for (std::size_t i = 0; i < ss.positions.size(); ++i) {
        EXPECT_NEAR((ss.normals[i] - n).norm(), 0.0, 1e-9);
        const Vec3d on_surface = ss.positions[i] + 0.02 * n;
        EXPECT_NEAR(on_surface.y(), on_surface.x() / 3.0, 1e-9);
    }
}

// A solid cylinder of radius 0.2 and height 0.5 along y, offset 0.01: side samples at radius
// 0.19 with radial normals, cap samples at y = 0.01 and 0.49 with normals -y / +y, all inside.
TEST(BoundarySampling, CylinderSidesAndCaps) {
    BoundaryDesc b;
    b.shape = BoundaryShape::Cylinder;
    b.center = Vec3d(1, 0, 1);
    b.axis = Vec3d::UnitY();
    b.radius = 0.2;
    b.height = 0.5;
    const SurfaceSamples ss = sample_boundary(b, 0.04, 0.01);
    int side = 0, caps = 0;
    for (std::size_t i = 0; i < ss.positions.size(); ++i) {
        const Vec3d d = ss.positions[i] - b.center;
        const Vec3d radial(d.x(), 0, d.z());
        EXPECT_NEAR(ss.normals[i].norm(), 1.0, 1e-12);
        if (std::abs(ss.normals[i].y()) > 0.5) {
            ++caps;
            EXPECT_NEAR(d.y(), ss.normals[i].y() > 0 ? 0.49 : 0.01, 1e-12);
            EXPECT_LT(radial.norm(), 0.19);
        } else {
            ++side;
            EXPECT_NEAR(radial.norm(), 0.19, 1e-12);
            EXPECT_NEAR((ss.normals[i] - radial.normalized()).norm(), 0.0, 1e-9);
        }
    }
    // Side: round(2 pi 0.19 / 0.04) = 30 per ring, 13 rings. Caps: one sample per s^2 of the
    // disc inside the rim ring (radius R - s/2), within 10 % (rings of round(2 pi rho / s)).
    EXPECT_EQ(side, 30 * 13);
    EXPECT_NEAR(caps, 2 * 3.14159 * 0.17 * 0.17 / (0.04 * 0.04), 0.1 * 2 * 3.14159 * 0.17 * 0.17 / (0.04 * 0.04));
}

// A fluid block fills whole spacings (issue 16's measurement: the 1.228 x 0.55 x 1.0 m block at
// r = 15 mm got 23,760 particles instead of 25,015, 5 % less water): block_fill reports it, the
// count is sample_block's, and a block whose sides are multiples of the spacing loses nothing.
TEST(Sampling, BlockFillReportsTheShortfallOfWholeSpacings) {
    const Aabb box{Vec3d(0.0, 0.0, 0.0), Vec3d(1.228, 0.55, 1.0)};
    const BlockFill f = block_fill(box, 0.03);
    EXPECT_EQ(f.particles, Eigen::Vector3i(40, 18, 33));
    EXPECT_EQ(sample_block(box, 0.03).size(), 23760u);
    EXPECT_NEAR(f.particle_volume, 23760 * 0.03 * 0.03 * 0.03, 1e-12);
    EXPECT_NEAR(f.shortfall(), 1.0 - 0.64152 / 0.6754, 1e-9);  // 5.02 %
    const BlockFill whole = block_fill(Aabb{Vec3d(0.1, 0.0, 0.0), Vec3d(0.7, 0.3, 0.9)}, 0.03);
    EXPECT_EQ(whole.particles, Eigen::Vector3i(20, 10, 30));
    EXPECT_NEAR(whole.shortfall(), 0.0, 1e-9);
}
