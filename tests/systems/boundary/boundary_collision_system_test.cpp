// BoundaryCollisionSystem (systems/boundary/boundary_collision_system.hpp), the safety net
// behind the particle boundary (cf. Ihmsen et al. 2010 eq. 9-12 with the analytic normal): a
// fluid particle whose centre ends a step beyond a declared surface is put back on it and loses
// the velocity component into the wall (an inelastic contact: the normal component is clamped,
// the tangential ones are kept); each such particle counts once in counter "collisions" and is
// marked in `wake` (individual stepping re-evaluates it); every other particle is left alone,
// bit for bit. Expected positions and velocities are worked out by hand per particle.
#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <vector>

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/data/world_init.hpp"
#include "engine/graph/system.hpp"
#include "systems/boundary/boundary_collision_system.hpp"
#include "systems/neighbours/fluid_grid_system.hpp"
#include "systems/neighbours/fluid_neighbours_system.hpp"
#include "test_scenes.hpp"

using namespace sph;

namespace {

bool same_bits(const Vec3& a, const Vec3& b) { return std::memcmp(a.data(), b.data(), sizeof(Vec3)) == 0; }

}  // namespace

// The 0.3 x 0.3 x 0.1 m container of a tank scene; 400 fluid particles inside it with random
// velocities, and five of them moved:
//   0: beyond the +x wall x = 0.3:  x = (0.31, 0.1, 0.05),   v = (2, -1, 0.5)
//      -> x = (0.3, 0.1, 0.05), v = (0, -1, 0.5)       (v_x into the wall removed)
//   1: below the floor y = 0:        x = (0.1, -0.005, 0.05), v = (0.3, -4, 0.2)
//      -> x = (0.1, 0, 0.05),  v = (0.3, 0, 0.2)
//   2: beyond the back wall z = 0 but already moving back in: x = (0.1, 0.1, -0.004), v = (0, 0, 1)
//      -> x = (0.1, 0.1, 0),   v = (0, 0, 1)            (nothing into the wall to remove)
//   3: beyond two walls at once (x = 0 and y = 0.3): x = (-0.01, 0.31, 0.05), v = (-1, 1, 0.25)
//      -> x = (0, 0.3, 0.05),  v = (0, 0, 0.25)
//   4: exactly on the wall x = 0.3, moving out: not beyond it, untouched and not counted
// collisions = 4 (particle 3 counts once).
TEST(BoundaryCollision, ContainerPutsEscapedParticlesBackOnTheWall) {
    World w;
    Scene s = test::tank_scene(Vec3d(0.16, 0.2, 0.1), Vec3d(0.3, 0.3, 0.1));
    initialise_world(w, s);
    w.fluid.store.add(comp::wake);
    auto x = w.fluid.store.get(comp::position);
    auto v = w.fluid.store.get(comp::velocity);
    const std::size_t n = x.size();
    ASSERT_EQ(n, 400u);
    std::mt19937 rng(2);
    std::uniform_real_distribution<Real> u(-1, 1);
    for (auto& vi : v) vi = Vec3(u(rng), u(rng), u(rng));
    x[0] = Vec3(0.31f, 0.1f, 0.05f), v[0] = Vec3(2, -1, 0.5f);
    x[1] = Vec3(0.1f, -0.005f, 0.05f), v[1] = Vec3(0.3f, -4, 0.2f);
    x[2] = Vec3(0.1f, 0.1f, -0.004f), v[2] = Vec3(0, 0, 1);
    x[3] = Vec3(-0.01f, 0.31f, 0.05f), v[3] = Vec3(-1, 1, 0.25f);
    x[4] = Vec3(Real(0.3), 0.1f, 0.05f), v[4] = Vec3(3, 0, 0);
    const std::vector<Vec3> x0(x.begin(), x.end()), v0(v.begin(), v.end());

    run_system(BoundaryCollisionSystem(s.boundaries), w);

    // The wall coordinate is the declared one rounded to Real once: exact comparisons.
    const Real wall = Real(0.3);
    EXPECT_EQ(x[0], Vec3(wall, 0.1f, 0.05f));
    EXPECT_EQ(v[0], Vec3(0, -1, 0.5f));
    EXPECT_EQ(x[1], Vec3(0.1f, 0, 0.05f));
    EXPECT_EQ(v[1], Vec3(0.3f, 0, 0.2f));
    EXPECT_EQ(x[2], Vec3(0.1f, 0.1f, 0));
    EXPECT_EQ(v[2], Vec3(0, 0, 1));
    EXPECT_EQ(x[3], Vec3(0, wall, 0.05f));
    EXPECT_EQ(v[3], Vec3(0, 0, 0.25f));
    EXPECT_TRUE(same_bits(x[4], x0[4]) && same_bits(v[4], v0[4]));
    EXPECT_EQ(w.counter_value("collisions"), 4u);
    const auto wake = w.fluid.store.get(comp::wake);
    for (std::size_t i = 0; i < n; ++i) {
        EXPECT_EQ(wake[i], i < 4 ? 1 : 0) << "particle " << i;
        if (i < 5) continue;
        // Inside (the lattice of the block, 1 cm from the walls at least): untouched, bit for bit.
        EXPECT_TRUE(same_bits(x[i], x0[i])) << "particle " << i;
        EXPECT_TRUE(same_bits(v[i], v0[i])) << "particle " << i;
    }
    // A second pass finds nothing: every particle is now on or inside the surface.
    run_system(BoundaryCollisionSystem(s.boundaries), w);
    EXPECT_EQ(w.counter_value("collisions"), 0u);
}

// Droplet contacts (`count_droplets`): of the particles the net corrects, those with no fluid
// particle within the support radius h (this step's lists, checked here against a brute-force
// distance test over every pair) count in `droplet_contacts` as well as in `collisions`. Block
// [0, 0.16] x [0, 0.2] x [0, 0.1], r = 0.01, h = 0.04 m (4 r); moved particles:
//   0: (0.31, 0.1, 0.05), beyond x = 0.3, 0.15 m from the block: a droplet;
//   1: (0.1, -0.005, 0.05), below the floor, under the block: has neighbours;
//   2: (0.29, 0.31, 0.05), beyond y = 0.3, with particle 3 at 0.01 m: not a droplet;
//   3: (0.29, 0.3, 0.05), on the wall: a neighbour of 2, not corrected;
//   4: (0.2, 0.1, 0.11), beyond z = 0.1; the nearest block particle, (0.15, 0.09, 0.09), is
//      sqrt(0.05^2 + 0.01^2 + 0.02^2) = 0.055 m away: a droplet;
//   5: (0.2, 0.31, 0.05), beyond y = 0.3, 0.09 m from particle 2 and 0.13 m from the block: a droplet.
// collisions = 5 (0, 1, 2, 4, 5), droplet_contacts = 3 (0, 4 and 5).
TEST(BoundaryCollision, CountsTheContactsOfParticlesWithoutFluidNeighboursApart) {
    World w;
    Scene s = test::tank_scene(Vec3d(0.16, 0.2, 0.1), Vec3d(0.3, 0.3, 0.1));
    initialise_world(w, s);
    auto x = w.fluid.store.get(comp::position);
    ASSERT_NEAR(double(w.physics.h), 0.04, 1e-7);
    x[0] = Vec3(0.31f, 0.1f, 0.05f);
    x[1] = Vec3(0.1f, -0.005f, 0.05f);
    x[2] = Vec3(0.29f, 0.31f, 0.05f);
    x[3] = Vec3(0.29f, 0.3f, 0.05f);
    x[4] = Vec3(0.2f, 0.1f, 0.11f);
    x[5] = Vec3(0.2f, 0.31f, 0.05f);
    const std::vector<Vec3> before(x.begin(), x.end());
    run_system(FluidGridSystem(), w);
    run_system(FluidNeighbourSystem(), w);
    run_system(BoundaryCollisionSystem(s.boundaries, false, false, true), w);
    // The oracle: every pair's distance at the positions the lists were built from.
    const Real h = w.physics.h;
    std::uint64_t hits = 0, droplets = 0;
    for (std::size_t i = 0; i < before.size(); ++i) {
        if (before[i] == x[i]) continue;  // not corrected
        ++hits;
        bool alone = true;
        for (std::size_t j = 0; j < before.size() && alone; ++j)
            alone = j == i || (before[i] - before[j]).norm() >= h;
        droplets += alone;
    }
    EXPECT_EQ(hits, 5u);
    EXPECT_EQ(droplets, 3u);
    EXPECT_EQ(w.counter_value("collisions"), hits);
    EXPECT_EQ(w.counter_value("droplet_contacts"), droplets);
    // Without the flag the counter is not declared: the net reads no lists.
    World w2;
    initialise_world(w2, s);
    run_system(BoundaryCollisionSystem(s.boundaries), w2);
    EXPECT_FALSE(w2.counters.count("droplet_contacts"));
}

// Without a wake column (global stepping registers none) the correction is the same.
TEST(BoundaryCollision, WorksWithoutWakeColumn) {
    World w;
    Scene s = test::tank_scene(Vec3d(0.04, 0.04, 0.04), Vec3d(0.3, 0.3, 0.1));
    initialise_world(w, s);
    ASSERT_FALSE(w.fluid.store.has(comp::wake.name));
    auto x = w.fluid.store.get(comp::position);
    auto v = w.fluid.store.get(comp::velocity);
    x[0] = Vec3(0.05f, 0.05f, 0.12f), v[0] = Vec3(0.5f, 0.5f, 1);  // beyond the front wall z = 0.1
    run_system(BoundaryCollisionSystem(s.boundaries), w);
    EXPECT_EQ(x[0], Vec3(0.05f, 0.05f, Real(0.1)));
    EXPECT_EQ(v[0], Vec3(0.5f, 0.5f, 0));
    EXPECT_EQ(w.counter_value("collisions"), 1u);
}

// Solid obstacles, worked out by hand (no particles needed: the system reads only the
// declared surfaces):
//   sphere centre (0.15, 0.15, 0.05), R = 0.05; particle at (0.18, 0.15, 0.05) (0.03 from the
//   centre), v = (-2, 1, 0): normal n = (1, 0, 0), x -> c + R n = (0.2, 0.15, 0.05), v_n = -2 < 0
//   removed: v -> (0, 1, 0);
//   box [0.1, 0.2] x [0, 0.05] x [0, 0.1]; particle at (0.12, 0.04, 0.05), v = (1, -3, 0.5):
//   nearest face y = 0.05 (0.01 away; x: 0.02, z: 0.05), x -> (0.12, 0.05, 0.05), v_y < 0
//   removed: v -> (1, 0, 0.5);
//   a particle outside both, at (0.3, 0.3, 0.3), untouched.
// Tolerance on the sphere position 1e-7 m: c + R n is a float sum (0.15f + 0.05f, one rounding).
TEST(BoundaryCollision, SphereAndBoxObstacles) {
    BoundaryDesc sphere;
    sphere.shape = BoundaryShape::Sphere;
    sphere.center = Vec3d(0.15, 0.15, 0.05);
    sphere.radius = 0.05;
    BoundaryDesc box;
    box.shape = BoundaryShape::Box;
    box.box = Aabb{Vec3d(0.1, 0, 0), Vec3d(0.2, 0.05, 0.1)};
    World w;
    w.fluid.store.add(comp::position);
    w.fluid.store.add(comp::velocity);
    w.fluid.store.resize(3);
    auto x = w.fluid.store.get(comp::position);
    auto v = w.fluid.store.get(comp::velocity);
    x[0] = Vec3(0.18f, 0.15f, 0.05f), v[0] = Vec3(-2, 1, 0);
    x[1] = Vec3(0.12f, 0.04f, 0.05f), v[1] = Vec3(1, -3, 0.5f);
    x[2] = Vec3(0.3f, 0.3f, 0.3f), v[2] = Vec3(-1, -1, -1);
    run_system(BoundaryCollisionSystem({sphere, box}), w);
    EXPECT_NEAR((x[0].cast<double>() - Vec3d(0.2, 0.15, 0.05)).norm(), 0.0, 1e-7);
    EXPECT_NEAR(v[0].x(), 0.0f, 1e-6f);  // v - (v.n) n with n computed from float d / |d|
    EXPECT_EQ(v[0].y(), 1.0f);
    EXPECT_EQ(x[1], Vec3(0.12f, Real(0.05), 0.05f));
    EXPECT_EQ(v[1], Vec3(1, 0, 0.5f));
    EXPECT_EQ(x[2], Vec3(0.3f, 0.3f, 0.3f));
    EXPECT_EQ(v[2], Vec3(-1, -1, -1));
    EXPECT_EQ(w.counter_value("collisions"), 2u);
}
