// The fluid surface (engine/run/surface.hpp) of a resting block of fluid, the lattice a scene's
// fluid block is filled with, against the block's own geometry: the mesh is closed and
// consistently oriented, encloses the block's volume, and the level set's zero crossing lies on
// the block's faces. Also the .ply the recorder writes, read back.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <random>

#include "engine/run/surface.hpp"

using namespace sph;

namespace {

constexpr double kR = 0.01;  // particle radius, m (spacing 2 cm)

/// A block's particle centres as a scene's fluid block places them (lattice_dims: the outer
/// centres r inside the faces), optionally jittered by up to `jitter` x r per axis.
std::vector<Vec3> block(const Aabb& box, double jitter = 0.0) {
    const Eigen::Vector3i n = lattice_dims(box, 2 * kR);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-jitter * kR, jitter * kR);
    std::vector<Vec3> x;
    for (int i = 0; i < n.x(); ++i)
        for (int j = 0; j < n.y(); ++j)
            for (int k = 0; k < n.z(); ++k) {
                const Vec3d p = box.min + Vec3d(kR, kR, kR) + 2 * kR * Vec3d(i, j, k);
                x.push_back((p + (jitter > 0 ? Vec3d(u(rng), u(rng), u(rng)) : Vec3d::Zero())).cast<Real>());
            }
    return x;
}

const Aabb kBox{Vec3d(0.1, 0.05, 0.1), Vec3d(0.4, 0.25, 0.3)};  // 0.3 x 0.2 x 0.2 m: 15 x 10 x 10 particles
const double kVolume = 0.3 * 0.2 * 0.2;

/// Largest |phi| at points of the block's faces one spacing in from their edges (the corners
/// and edges are rounded by r by construction, so they are left out).
double worst_face_distance(const FluidSurface& s, const Aabb& box) {
    double worst = 0;
    for (int axis = 0; axis < 3; ++axis)
        for (int side = 0; side < 2; ++side)
            for (int a = 0; a <= 4; ++a)
                for (int b = 0; b <= 4; ++b) {
                    Vec3d p;
                    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
                    p[axis] = side ? box.max[axis] : box.min[axis];
                    const double inset = 4 * kR;
                    p[u] = box.min[u] + inset + (box.max[u] - box.min[u] - 2 * inset) * a / 4.0;
                    p[v] = box.min[v] + inset + (box.max[v] - box.min[v] - 2 * inset) * b / 4.0;
                    worst = std::max(worst, std::abs(s.value(p)));
                }
    return worst;
}

}  // namespace

TEST(Surface, RestingBlockMeshIsClosedAndEnclosesTheBlock) {
    if (!surface_available()) GTEST_SKIP() << "built without OpenVDB";
    const auto x = block(kBox);
    ASSERT_EQ(x.size(), 1500u);
    const SurfaceParams defaults;
    const FluidSurface s(x, kR, defaults.resolve(kR));
    const SurfaceMesh m = s.mesh();
    ASSERT_GT(m.triangles.size(), 1000u);
    EXPECT_TRUE(m.watertight());
    // Volume: kept to the particles' N (2 r)^3 = the block's volume by one uniform offset after
    // smoothing; measured -0.03 % at the defaults (docs/results/surfaces.md; -9.3 % without that
    // offset). 1.5 % is a surface shifted by 0.06 r over the block's faces; without the volume
    // offset the test fails by 6x that margin.
    EXPECT_NEAR(m.enclosed_volume() / kVolume, 1.0, 0.015) << "enclosed " << m.enclosed_volume();
    // Every vertex within 0.5 r of the block's surface box (none floats off, none sinks).
    for (const auto& v : m.vertices)
        for (int a = 0; a < 3; ++a) {
            ASSERT_GE(v[std::size_t(a)], kBox.min[a] - 0.5 * kR);
            ASSERT_LE(v[std::size_t(a)], kBox.max[a] + 0.5 * kR);
        }
}

TEST(Surface, ZeroCrossingLiesOnTheBlockFaces) {
    if (!surface_available()) GTEST_SKIP() << "built without OpenVDB";
    const SurfaceParams defaults;
    const FluidSurface s(block(kBox), kR, defaults.resolve(kR));
    // Within a quarter of the particle radius (2.5 mm at r = 1 cm; the voxel is r): measured
    // 0.14 r at the defaults over 150 points of the six faces, on and between particle columns.
    EXPECT_LT(worst_face_distance(s, kBox), 0.25 * kR);
    // Inside is negative, outside positive: the centre is deep (clamped to the band), a point
    // 2 r outside a face is outside.
    EXPECT_LT(s.value(0.5 * (kBox.min + kBox.max)), 0.0);
    EXPECT_GT(s.value(Vec3d(kBox.max.x() + 2 * kR, 0.15, 0.2)), 0.0);
}

TEST(Surface, JitteredBlockStaysClosedAndKeepsItsVolume) {
    if (!surface_available()) GTEST_SKIP() << "built without OpenVDB";
    // A block after the start lattice has relaxed: every centre moved by up to 0.3 r per axis.
    // Measured -0.39 % at the defaults; 2 % as above, plus the jittered outer layer.
    const SurfaceParams defaults;
    const FluidSurface s(block(kBox, 0.3), kR, defaults.resolve(kR));
    const SurfaceMesh m = s.mesh();
    EXPECT_TRUE(m.watertight());
    EXPECT_NEAR(m.enclosed_volume() / kVolume, 1.0, 0.02);
}

TEST(Surface, PlyHoldsTheMesh) {
    if (!surface_available()) GTEST_SKIP() << "built without OpenVDB";
    const SurfaceParams defaults;
    const SurfaceMesh m = FluidSurface(block(kBox), kR, defaults.resolve(kR)).mesh();
    const auto file = std::filesystem::temp_directory_path() / "sph_surface_test.ply";
    write_mesh_ply(file, m, 0.25);
    std::ifstream in(file, std::ios::binary);
    const std::string all((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const std::size_t end = all.find("end_header\n") + 11;
    EXPECT_NE(all.find("element vertex " + std::to_string(m.vertices.size()) + "\n"), std::string::npos);
    EXPECT_NE(all.find("element face " + std::to_string(m.triangles.size()) + "\n"), std::string::npos);
    EXPECT_NE(all.find("comment sph surface, t = 0.25 s"), std::string::npos);
    ASSERT_EQ(all.size(), end + 12 * m.vertices.size() + 13 * m.triangles.size());
    // The last triangle, read back.
    const char* p = all.data() + all.size() - 13;
    EXPECT_EQ(p[0], 3);
    std::int32_t idx[3];
    std::memcpy(idx, p + 1, 12);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(std::uint32_t(idx[k]), m.triangles.back()[std::size_t(k)]);
    std::filesystem::remove(file);
}

TEST(Surface, MeshPropertiesCatchDefects) {
    // The checks themselves: a tetrahedron is closed with volume 1/6; without a face it is open;
    // with one face flipped it is not consistently oriented.
    SurfaceMesh t;
    t.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    t.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
    EXPECT_TRUE(t.watertight());
    EXPECT_NEAR(t.enclosed_volume(), 1.0 / 6.0, 1e-12);
    SurfaceMesh open = t;
    open.triangles.pop_back();
    EXPECT_FALSE(open.watertight());
    SurfaceMesh flipped = t;
    std::swap(flipped.triangles[3][1], flipped.triangles[3][2]);
    EXPECT_FALSE(flipped.watertight());
}

TEST(Surface, DISABLED_Sweep) {
    // Measurement aid (docs/results/surfaces.md): volume error, face distance and time per setting.
    for (double R : {2.0, 3.0, 4.0})
        for (double sm : {0.0, 1.0, 2.0})
            for (double vx : {0.5, 1.0}) {
                SurfaceParams p;
                p.sphere_radius = R * kR;
                p.smoothing = sm * kR;
                p.voxel_size = vx * kR;
                const auto t0 = std::chrono::steady_clock::now();
                const FluidSurface s(block(kBox, 0.3), kR, p.resolve(kR));
                const SurfaceMesh m = s.mesh();
                const double sec = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
                const FluidSurface s0(block(kBox), kR, p.resolve(kR));
                const SurfaceMesh m0 = s0.mesh();
                std::printf("R=%.0fr smooth=%.0fr voxel=%.1fr: lattice vol %+.2f%% face %.3f r watertight %d | jitter vol "
                            "%+.2f%% watertight %d | %.3f s\n",
                            R, sm, vx, 100 * (m0.enclosed_volume() / kVolume - 1), worst_face_distance(s0, kBox) / kR,
                            int(m0.watertight()), 100 * (m.enclosed_volume() / kVolume - 1), int(m.watertight()), sec);
            }
}

TEST(Surface, WithoutTheVolumeOffsetTheBlockShrinks) {
    if (!surface_available()) GTEST_SKIP() << "built without OpenVDB";
    // What keep_volume corrects: smoothing and the rounded edges take 9.3 % (measured) of this
    // block away. Asserted between 4 % and 12 %, so a change that made the offset unnecessary
    // (or the loss larger) is seen.
    SurfaceParams p;
    p.keep_volume = false;
    const double ratio = FluidSurface(block(kBox), kR, p.resolve(kR)).mesh().enclosed_volume() / kVolume;
    std::printf("enclosed without the volume offset: %.4f of the block\n", ratio);
    EXPECT_GT(ratio, 0.88);
    EXPECT_LT(ratio, 0.96);
}
