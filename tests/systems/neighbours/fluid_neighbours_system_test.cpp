// FluidGridSystem + FluidNeighbourSystem (He et al. Alg. 1 line 3, Alg. 2 lines 3-4) against an
// O(N^2) brute force on a jittered block in a container: every searched row holds exactly the
// fluid particles j != i with r < h (the engine's predicate, |x_i - x_j|^2 < h^2 in Real), as a
// set, without duplicates; with individual stepping only the rows of w.active_set are searched
// (at 100 %, 50 %, 10 % and 0 % of the particles) and every other row keeps its old list
// entry for entry; counter neighbour_searches is the number of rows searched. All comparisons
// are exact (integer indices, the same float predicate).
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/data/world_init.hpp"
#include "engine/graph/system.hpp"
#include "systems/neighbours/fluid_grid_system.hpp"
#include "systems/neighbours/fluid_neighbours_system.hpp"
#include "test_scenes.hpp"

using namespace sph;

namespace {

// 8 x 10 x 5 = 400 fluid particles in the corner of a 0.3 x 0.3 x 0.1 m container, jittered by
// 0.3 r (kept 2 mm inside the walls).
void make_block(World& w, std::uint32_t seed) {
    initialise_world(w, test::tank_scene(Vec3d(0.16, 0.2, 0.1), Vec3d(0.3, 0.3, 0.1)));
    test::jitter(w, seed, 0.3f);
}

// Moves every particle by up to 0.5 r per axis: enough to change many lists.
void move(World& w, std::uint32_t seed) { test::jitter(w, seed, 0.5f); }

std::vector<Index> brute(std::span<const Vec3> x, Index i, Real h) {
    std::vector<Index> out;
    for (std::size_t j = 0; j < x.size(); ++j)
        if (j != i && (x[i] - x[j]).squaredNorm() < h * h) out.push_back(Index(j));
    return out;
}

std::vector<Index> sorted(std::span<const Index> s) { return test::sorted_copy(s); }

}  // namespace

TEST(FluidNeighbours, GlobalSearchMatchesBruteForce) {
    World w;
    make_block(w, 11);
    const std::size_t n = w.fluid.size();
    ASSERT_EQ(n, 400u);
    run_system(FluidGridSystem(), w);
    run_system(FluidNeighbourSystem(false), w);
    const auto x = w.fluid.store.get(comp::position);
    std::size_t total = 0, most = 0;
    for (Index i = 0; i < n; ++i) {
        const auto want = brute(x, i, w.physics.h);
        ASSERT_EQ(w.fluid_neighbours.of(i).size(), want.size()) << "particle " << i;
        EXPECT_EQ(sorted(w.fluid_neighbours.of(i)), want) << "particle " << i;
        total += want.size();
        most = std::max(most, want.size());
    }
    EXPECT_EQ(w.counter_value("neighbour_searches"), n);
    EXPECT_EQ(w.fluid_neighbours.total(), total);
    // Not a vacuous comparison: interior particles of a lattice at h = 4 r have ~30 neighbours.
    EXPECT_GT(most, 25u);
    EXPECT_GT(total, 15 * n);
}

namespace {

// First a global search on the block, then every particle moves and the grid is rebuilt, and
// only a random `fraction` of the rows is searched again (He Alg. 2 lines 3-4).
void check_individual(double fraction) {
    SCOPED_TRACE("active fraction " + std::to_string(fraction));
    World w;
    make_block(w, 23);
    const std::size_t n = w.fluid.size();
    run_system(FluidGridSystem(), w);
    run_system(FluidNeighbourSystem(false), w);
    const NeighbourLists before = w.fluid_neighbours;

    move(w, 5);
    run_system(FluidGridSystem(), w);
    std::vector<Index> perm(n);
    for (Index i = 0; i < n; ++i) perm[i] = i;
    std::shuffle(perm.begin(), perm.end(), std::mt19937(9));
    const std::size_t k = std::size_t(std::llround(fraction * double(n)));
    std::vector<std::uint8_t> searched(n, 0);
    for (std::size_t q = 0; q < k; ++q) searched[perm[q]] = 1;
    w.active_set.clear();
    for (Index i = 0; i < n; ++i)
        if (searched[i]) w.active_set.push_back(i);  // ascending, as select_active builds it
    w.counters.clear();
    run_system(FluidNeighbourSystem(true), w);

    const auto x = w.fluid.store.get(comp::position);
    std::size_t stale = 0;  // rows not searched whose old list is no longer the true one
    for (Index i = 0; i < n; ++i) {
        const auto want = brute(x, i, w.physics.h);
        if (searched[i]) {
            EXPECT_EQ(sorted(w.fluid_neighbours.of(i)), want) << "searched particle " << i;
        } else {
            EXPECT_TRUE(std::ranges::equal(w.fluid_neighbours.of(i), before.of(i))) << "particle " << i;
            if (sorted(before.of(i)) != want) ++stale;
        }
    }
    EXPECT_EQ(w.counter_value("neighbour_searches"), k);
    // The move changes most lists, so "kept its old list" is not the same as "is correct".
    if (k < n) {
        EXPECT_GT(stale, (n - k) / 2);
    }
}

}  // namespace

TEST(FluidNeighbours, IndividualAllActiveMatchesBruteForce) { check_individual(1.0); }
TEST(FluidNeighbours, IndividualHalfActiveSearchesOnlyActiveRows) { check_individual(0.5); }
TEST(FluidNeighbours, IndividualTenPercentActiveSearchesOnlyActiveRows) { check_individual(0.1); }
TEST(FluidNeighbours, IndividualNoneActiveKeepsEveryList) { check_individual(0.0); }
