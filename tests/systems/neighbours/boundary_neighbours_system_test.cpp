// BoundaryNeighbourSystem (He et al. Alg. 2 line 4 for the fluid -> boundary lists, against the
// boundary grid built once by initialise_world for a static container) against an O(N^2)
// brute force on a jittered block in a tank: every searched row holds exactly the boundary
// particles b with r < h (the engine's predicate, |x_i - x_b|^2 < h^2 in Real; no self
// exclusion: the two sets differ), as a set, without duplicates; with individual stepping only
// the rows of w.active_set are searched (100 %, 50 %, 10 %, 0 %) and every other row keeps its
// old list entry for entry. All comparisons are exact (integer indices, the same predicate).
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/data/world_init.hpp"
#include "engine/graph/system.hpp"
#include "systems/neighbours/boundary_neighbours_system.hpp"
#include "test_scenes.hpp"

using namespace sph;

namespace {

// 8 x 10 x 5 = 400 fluid particles in the corner of a 0.3 x 0.3 x 0.1 m container (so they
// touch the floor, one side wall, and the front and back walls 0.1 m apart), jittered by 0.3 r.
void make_tank(World& w, std::uint32_t seed) {
    initialise_world(w, test::tank_scene(Vec3d(0.16, 0.2, 0.1), Vec3d(0.3, 0.3, 0.1)));
    test::jitter(w, seed, 0.3f);
}

void move(World& w, std::uint32_t seed) { test::jitter(w, seed, 0.5f); }

std::vector<Index> brute(std::span<const Vec3> x, std::span<const Vec3> xb, Index i, Real h) {
    std::vector<Index> out;
    for (std::size_t b = 0; b < xb.size(); ++b)
        if ((x[i] - xb[b]).squaredNorm() < h * h) out.push_back(Index(b));
    return out;
}

std::vector<Index> sorted(std::span<const Index> s) { return test::sorted_copy(s); }

}  // namespace

TEST(BoundaryNeighbours, GlobalSearchMatchesBruteForce) {
    World w;
    make_tank(w, 11);
    const std::size_t n = w.fluid.size();
    ASSERT_EQ(n, 400u);
    ASSERT_GT(w.boundary.size(), 800u);  // 898: one layer over the six walls
    run_system(BoundaryNeighbourSystem(false), w);
    const auto x = w.fluid.store.get(comp::position);
    const auto xb = w.boundary.store.get(comp::position);
    ASSERT_EQ(w.boundary_neighbours.rows(), n);
    std::size_t with_walls = 0, total = 0;
    for (Index i = 0; i < n; ++i) {
        const auto want = brute(x, xb, i, w.physics.h);
        ASSERT_EQ(w.boundary_neighbours.of(i).size(), want.size()) << "particle " << i;
        EXPECT_EQ(sorted(w.boundary_neighbours.of(i)), want) << "particle " << i;
        with_walls += !want.empty();
        total += want.size();
    }
    EXPECT_EQ(w.boundary_neighbours.total(), total);
    // Not vacuous, and both kinds of row occur: the particles near the floor, the x = 0 wall
    // and the front and back walls have boundary neighbours (measured 296 of 400, 2,258
    // entries), the middle of the block has none (an empty row must stay empty).
    EXPECT_GT(with_walls, n / 2);
    EXPECT_LT(with_walls, n);
    EXPECT_GT(total, 4 * n);
}

namespace {

void check_individual(double fraction) {
    SCOPED_TRACE("active fraction " + std::to_string(fraction));
    World w;
    make_tank(w, 23);
    const std::size_t n = w.fluid.size();
    run_system(BoundaryNeighbourSystem(false), w);
    const NeighbourLists before = w.boundary_neighbours;

    move(w, 5);
    std::vector<Index> perm(n);
    for (Index i = 0; i < n; ++i) perm[i] = i;
    std::shuffle(perm.begin(), perm.end(), std::mt19937(9));
    const std::size_t k = std::size_t(std::llround(fraction * double(n)));
    std::vector<std::uint8_t> searched(n, 0);
    for (std::size_t q = 0; q < k; ++q) searched[perm[q]] = 1;
    w.active_set.clear();
    for (Index i = 0; i < n; ++i)
        if (searched[i]) w.active_set.push_back(i);
    run_system(BoundaryNeighbourSystem(true), w);

    const auto x = w.fluid.store.get(comp::position);
    const auto xb = w.boundary.store.get(comp::position);
    std::size_t stale = 0;
    for (Index i = 0; i < n; ++i) {
        const auto want = brute(x, xb, i, w.physics.h);
        if (searched[i]) {
            EXPECT_EQ(sorted(w.boundary_neighbours.of(i)), want) << "searched particle " << i;
        } else {
            EXPECT_TRUE(std::ranges::equal(w.boundary_neighbours.of(i), before.of(i))) << "particle " << i;
            if (sorted(before.of(i)) != want) ++stale;
        }
    }
    // The move changes most lists, so "kept its old list" is not the same as "is correct".
    if (k < n) {
        EXPECT_GT(stale, (n - k) / 2);
    }
}

}  // namespace

TEST(BoundaryNeighbours, IndividualAllActiveMatchesBruteForce) { check_individual(1.0); }
TEST(BoundaryNeighbours, IndividualHalfActiveSearchesOnlyActiveRows) { check_individual(0.5); }
TEST(BoundaryNeighbours, IndividualTenPercentActiveSearchesOnlyActiveRows) { check_individual(0.1); }
TEST(BoundaryNeighbours, IndividualNoneActiveKeepsEveryList) { check_individual(0.0); }
