// The uniform grid's neighbour lists must equal brute force exactly (engine/grid.hpp).
#include <gtest/gtest.h>

#include "simd_test_targets.hpp"  // before any other Highway header (the engine's target list)

#include <algorithm>
#include <random>
#include <set>

#include "engine/core/errors.hpp"
#include "engine/core/grid.hpp"

#include <tbb/task_arena.h>

using namespace sph;

namespace {

// |q_i - x_j|^2 summed as Eigen's squaredNorm sums it, (dx^2 + dy^2) + dz^2, on raw floats: the
// same test at a fraction of the time in the sanitizer stages, which compile the tests at -O0.
std::vector<Index> brute(std::span<const Vec3> q, std::span<const Vec3> pts, Index i, Real r, bool exclude_self) {
    std::vector<Index> out;
    const Real* a = q[i].data();
    const Real r2 = r * r;
    for (Index j = 0; j < pts.size(); ++j) {
        const Real* b = pts[j].data();
        const Real dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
        if (dx * dx + dy * dy + dz * dz < r2 && !(exclude_self && j == i)) out.push_back(j);
    }
    return out;
}

// Random cloud with negative coordinates, plus points exactly on cell borders and pairs at
// exactly the radius (which must be excluded: the test is strict, r^2 < h^2).
std::vector<Vec3> cloud(std::size_t n, Real h, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<Real> u(-1.0f, 0.5f);
    std::vector<Vec3> pts;
    for (std::size_t i = 0; i < n; ++i) pts.emplace_back(u(rng), u(rng), u(rng));
    for (int i = -5; i <= 5; ++i) {
        pts.emplace_back(i * h, 0, 0);              // on cell borders (origin at -1 - h)
        pts.emplace_back(i * h, i * h, -i * h);
        pts.emplace_back(Real(-1 + h * 3), i * h * 0.5f, 0);
    }
    pts.emplace_back(0.1f, 0.1f, 0.1f);
    pts.emplace_back(0.1f + h, 0.1f, 0.1f);  // exactly h apart (up to rounding)
    pts.emplace_back(0.1f, 0.1f, 0.1f);      // duplicate position
    return pts;
}

void expect_equal_to_brute(const UniformGrid& grid, std::span<const Vec3> q, std::span<const Vec3> pts, Real h,
                           bool exclude_self, const NeighbourLists& lists, std::span<const Index> which) {
    for (Index i : which) {
        auto got = std::vector<Index>(lists.of(i).begin(), lists.of(i).end());
        std::sort(got.begin(), got.end());
        EXPECT_EQ(got, brute(q, pts, i, h, exclude_self)) << "particle " << i;
    }
}

}  // namespace

TEST(NeighbourSearch, EqualsBruteForceOnRandomCloud) {
    // Both filters, the vectorised one (simulation.simd) and the scalar reference; candidates
    // copied from the grid's own coordinates (the fluid grid) or gathered from the positions.
    for (const bool keep : {false, true})
        for (const bool simd : {false, true}) {
            SCOPED_TRACE(std::string(simd ? "vectorised filter" : "scalar filter") + (keep ? ", kept coordinates" : ""));
            const Real h = 0.07f;
            auto pts = cloud(3000, h, 1);
            UniformGrid grid(Aabb{Vec3d(-1, -1, -1), Vec3d(0.5, 0.5, 0.5)}, h, "grid", keep);
            grid.build(pts);
            EXPECT_EQ(grid.sorted_x() != nullptr, keep);
            NeighbourLists lists;
            build_neighbour_lists(grid, pts, pts, h, true, QuerySubset{}, lists, simd);
            std::vector<Index> all(pts.size());
            for (Index i = 0; i < all.size(); ++i) all[i] = i;
            expect_equal_to_brute(grid, pts, pts, h, true, lists, all);
        }
}

// The cell table packs a 16-bit offset per cell under a 32-bit start per 16 cells; a build with
// 65,536 or more particles in 16 cells falls back to a 32-bit start per cell. Both give every
// cell's particles (checked against the particles' own cells) and brute-force lists.
TEST(NeighbourSearch, CellTableHoldsPilesOfParticlesInOneCell) {
    const Real h = 0.1f;
    std::vector<Vec3> pts = cloud(2000, h, 3);
    const std::size_t spread = pts.size();
    std::mt19937 rng(5);
    std::uniform_real_distribution<Real> u(0.0f, 0.04f);
    for (int k = 0; k < 70000; ++k) pts.emplace_back(0.2f + u(rng), 0.2f + u(rng), 0.2f + u(rng));  // one cell
    for (const std::size_t n : {spread, pts.size()}) {
        SCOPED_TRACE(n);
        const std::span<const Vec3> set(pts.data(), n);
        UniformGrid grid(Aabb{Vec3d(-1, -1, -1), Vec3d(0.5, 0.5, 0.5)}, h);
        grid.build(set);
        std::vector<std::size_t> in_cell(grid.cell_count(), 0);
        for (const Vec3& p : set) ++in_cell[std::size_t(grid.cell_of(p))];
        std::size_t mismatched = 0;
        for (std::size_t c = 0; c < grid.cell_count(); ++c) {
            mismatched += grid.cell_start(std::int64_t(c + 1)) - grid.cell_start(std::int64_t(c)) != in_cell[c];
            for (Index s = grid.cell_start(std::int64_t(c)); s < grid.cell_start(std::int64_t(c + 1)); ++s)
                mismatched += std::size_t(grid.cell_of(set[grid.sorted_index()[s]])) != c;
        }
        EXPECT_EQ(mismatched, 0u);
        EXPECT_EQ(grid.cell_start(std::int64_t(grid.cell_count())), n);
        // The packed table is 2.25 bytes a cell, the fallback adds 4 (table_bytes() counts both).
        const double table = double(grid.table_bytes()) / double(grid.cell_count());
        if (n == spread)
            EXPECT_NEAR(table, 2.25, 0.01);
        else
            EXPECT_NEAR(table, 6.25, 0.01);
        // Lists of the spread particles only (a pile's lists are 70,000 long each).
        NeighbourLists lists;
        std::vector<Index> some;
        for (Index i = 0; i < spread; i += 7) some.push_back(i);
        build_neighbour_lists(grid, set, set, h, true, QuerySubset{some, false, false}, lists, true);
        expect_equal_to_brute(grid, set, set, h, true, lists, some);
    }
}

// A build is one stable counting sort: slots in (cell, index) order, each cell's start the count
// of the particles in lower cells, for any number of threads (its keys and table are computed in
// parallel) and on a rebuild into the same grid, against std::stable_sort
// of the indices by cell (the oracle): 150,000 particles with piles, air and particles clamped
// in from outside the box.
TEST(NeighbourSearch, BuildIsOneStableCountingSortForAnyThreadCount) {
    const Real h = 0.05f;
    std::vector<Vec3> pts = cloud(140'000, h, 11);
    std::mt19937 rng(12);
    std::uniform_real_distribution<Real> u(0.0f, 0.01f);
    for (int k = 0; k < 9'000; ++k) pts.emplace_back(0.3f + u(rng), -0.4f + u(rng), 0.1f + u(rng));  // a pile
    for (int k = 0; k < 1'000; ++k) pts.emplace_back(3.0f + u(rng), -2.0f, 0.2f);  // outside: clamped to a border cell
    std::shuffle(pts.begin(), pts.end(), rng);  // no order to lean on
    UniformGrid ref_grid(Aabb{Vec3d(-1, -1, -1), Vec3d(0.5, 0.5, 0.5)}, h);
    std::vector<Index> order(pts.size());
    for (Index i = 0; i < order.size(); ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(), [&](Index a, Index b) { return ref_grid.cell_of(pts[a]) < ref_grid.cell_of(pts[b]); });
    std::vector<Index> starts(ref_grid.cell_count() + 1, 0);
    for (const Vec3& p : pts) ++starts[std::size_t(ref_grid.cell_of(p)) + 1];
    for (std::size_t c = 1; c < starts.size(); ++c) starts[c] += starts[c - 1];
    for (const int threads : {1, 2, 3, 4}) {
        SCOPED_TRACE(threads);
        tbb::task_arena arena(threads);
        UniformGrid grid(Aabb{Vec3d(-1, -1, -1), Vec3d(0.5, 0.5, 0.5)}, h);
        for (int build = 0; build < 2; ++build) arena.execute([&] { grid.build(pts); });  // a rebuild as well
        ASSERT_EQ(grid.sorted_index().size(), pts.size());
        EXPECT_TRUE(std::equal(order.begin(), order.end(), grid.sorted_index().begin()));
        std::size_t wrong_starts = 0;
        for (std::size_t c = 0; c < starts.size(); ++c) wrong_starts += grid.cell_start(std::int64_t(c)) != starts[c];
        EXPECT_EQ(wrong_starts, 0u);
    }
}

TEST(NeighbourSearch, CrossSetQueriesIncludeEveryMatch) {
    // Both filters, the vectorised one (simulation.simd) and the scalar reference.
    for (const bool simd : {false, true}) {
        SCOPED_TRACE(simd ? "vectorised filter" : "scalar filter");
        const Real h = 0.1f;
        auto pts = cloud(2000, h, 2);
        auto q = cloud(500, h, 3);
        UniformGrid grid(Aabb{Vec3d(-1, -1, -1), Vec3d(0.5, 0.5, 0.5)}, h);
        grid.build(pts);
        NeighbourLists lists;
        build_neighbour_lists(grid, pts, q, h, false, QuerySubset{}, lists, simd);
        for (Index i = 0; i < q.size(); ++i) {
            auto got = std::vector<Index>(lists.of(i).begin(), lists.of(i).end());
            std::sort(got.begin(), got.end());
            EXPECT_EQ(got, brute(q, pts, i, h, false)) << "query " << i;
        }
    }
}

// mark_empty_neighbourhoods (the boundary grid's): a cell is marked empty exactly when its 27
// cells offer no candidate, for every cell of the grid and for queries outside it (clamped to
// its border cells); the marks follow a second build; a drifted grid reports none; and cross-set
// lists, built in both layouts, equal brute force with the marks on. The particles sit in two
// clusters of a 30-cell box, so most cells are empty around and the rest are not.
TEST(NeighbourSearch, EmptyNeighbourhoodMarksEqualTheCandidateRanges) {
    const Real h = 0.1f;
    std::mt19937 rng(11);
    std::uniform_real_distribution<Real> u(0, 1);
    auto cluster = [&](const Vec3& c, Real r, std::size_t n, std::vector<Vec3>& out) {
        for (std::size_t k = 0; k < n; ++k) out.push_back(c + r * Vec3(u(rng) - 0.5f, u(rng) - 0.5f, u(rng) - 0.5f));
    };
    std::vector<Vec3> pts;
    cluster(Vec3(0.5f, 0.5f, 0.5f), 0.3f, 400, pts);
    cluster(Vec3(2.6f, 0.2f, 1.2f), 0.2f, 200, pts);
    UniformGrid grid(Aabb{Vec3d(0, 0, 0), Vec3d(3, 1.5, 1.5)}, h);
    grid.mark_empty_neighbourhoods(true);
    // ASSERT_* returns void: the count comes back through `empty`.
    auto check = [&](const std::vector<Vec3>& at, std::size_t& empty) {
        grid.build(at);
        empty = 0;
        const Eigen::Vector3i d = grid.dims();
        for (int z = 0; z < d[2]; ++z)
            for (int y = 0; y < d[1]; ++y)
                for (int x = 0; x < d[0]; ++x) {
                    const Vec3 centre = grid.origin() + (Vec3(Real(x), Real(y), Real(z)) + Vec3::Constant(0.5f)) * h;
                    const std::int64_t c = grid.cell_of(centre);
                    ASSERT_EQ(c, grid.cell_index({x, y, z}));
                    ASSERT_EQ(grid.empty_around(c), grid.candidate_ranges(centre).total == 0) << "cell " << x << " " << y << " " << z;
                    empty += grid.empty_around(c);
                }
        for (int k = 0; k < 500; ++k) {  // anywhere, also outside the grid
            const Vec3 q(u(rng) * 5 - 1, u(rng) * 4 - 1, u(rng) * 4 - 1);
            ASSERT_EQ(grid.empty_around(grid.cell_of(q)), grid.candidate_ranges(q).total == 0);
        }
    };
    std::size_t empty = 0;
    check(pts, empty);
    EXPECT_GT(empty, grid.cell_count() / 2);
    EXPECT_LT(empty, grid.cell_count());
    // Every particle moved into one corner: the marks are the new build's.
    std::vector<Vec3> corner(pts.size(), Vec3(0.05f, 0.05f, 0.05f));
    check(corner, empty);
    EXPECT_EQ(empty, grid.cell_count() - 27);  // all in cell (1, 1, 1): the 27 around it are not empty
    grid.build(pts);
    grid.set_drift(0.01f);
    for (std::int64_t c = 0; c < std::int64_t(grid.cell_count()); ++c) ASSERT_FALSE(grid.empty_around(c));
    grid.build(pts);
    // Cross-set lists with the marks (the queries spread over the whole box), both layouts.
    std::vector<Vec3> q;
    for (int k = 0; k < 3000; ++k) q.emplace_back(u(rng) * 3, u(rng) * 1.5f, u(rng) * 1.5f);
    for (const bool slab : {false, true}) {
        std::vector<Index> half;
        for (Index i = 0; i < q.size(); i += 2) half.push_back(i);
        NeighbourLists lists;
        build_neighbour_lists(grid, pts, q, h, false, QuerySubset{half, false, slab}, lists, true);
        std::size_t found = 0;
        for (Index i : half) {
            auto got = std::vector<Index>(lists.of(i).begin(), lists.of(i).end());
            std::sort(got.begin(), got.end());
            ASSERT_EQ(got, brute(q, pts, i, h, false)) << (slab ? "slab" : "compact") << " query " << i;
            found += !got.empty();
        }
        EXPECT_GT(found, 0u);
    }
}

// A subset rebuild touches only the subset; a dense cluster forces the capacity to grow and
// every list to be rebuilt in the new layout.
TEST(NeighbourSearch, SubsetRebuildAndCapacityGrowth) {
    // Both filters, the vectorised one (simulation.simd) and the scalar reference.
    for (const bool simd : {false, true}) {
        SCOPED_TRACE(simd ? "vectorised filter" : "scalar filter");
        const Real h = 0.1f;
        auto pts = cloud(1500, h, 4);
        UniformGrid grid(Aabb{Vec3d(-1, -1, -1), Vec3d(0.5, 0.5, 0.5)}, h);
        grid.build(pts);
        NeighbourLists lists;
        build_neighbour_lists(grid, pts, pts, h, true, QuerySubset{}, lists, simd);
        // Move 600 particles into one dense clump, then rebuild only them: more than two of the
        // slab build's 256-row tasks overflow the capacity at once (the thread sanitizer's stage
        // sees their shared overflow flag).
        std::vector<Index> moved;
        for (Index i = 0; i < 600; ++i) {
            pts[i * 2] = Vec3(0.2f + 0.0001f * Real(i % 120), 0.2f + 0.0001f * Real(i / 120), 0.2f);
            moved.push_back(i * 2);
        }
        grid.build(pts);
        const Index cap_before = lists.capacity;
        build_neighbour_lists(grid, pts, pts, h, true, QuerySubset{moved, false}, lists, simd);
        EXPECT_GT(lists.capacity, cap_before);
        expect_equal_to_brute(grid, pts, pts, h, true, lists, moved);
        // After growth every list was rebuilt, so all match brute force for the new positions.
        std::vector<Index> all(pts.size());
        for (Index i = 0; i < all.size(); ++i) all[i] = i;
        expect_equal_to_brute(grid, pts, pts, h, true, lists, all);
    }
}

// The vectorised filter writes the same lists in the same order as the scalar one (the
// density and force sums then add the same terms in the same order), with and without the
// self-exclusion, across a capacity growth.
TEST(NeighbourSearch, VectorisedFilterEqualsScalarInOrderOnEveryTarget) {
    test::for_each_simd_target([] {
        const Real h = 0.07f;
        auto pts = cloud(4000, h, 7);
        for (Index i = 0; i < 200; ++i) pts[i * 7] = Vec3(0.1f + 0.00005f * i, 0.1f, 0.1f);  // a clump: growth
        UniformGrid grid(Aabb{Vec3d(-1, -1, -1), Vec3d(0.5, 0.5, 0.5)}, h);
        grid.build(pts);
        std::vector<Index> all(pts.size());
        for (Index i = 0; i < all.size(); ++i) all[i] = i;
        // Both layouts: every list at once (compact) and an explicit subset (slab).
        for (const auto& [self, subset] : {std::pair{true, QuerySubset{}}, std::pair{false, QuerySubset{}},
                                           std::pair{true, QuerySubset{all, false}}}) {
            NeighbourLists scalar, vectorised;
            build_neighbour_lists(grid, pts, pts, h, self, subset, scalar, false);
            build_neighbour_lists(grid, pts, pts, h, self, subset, vectorised, true);
            ASSERT_EQ(scalar.capacity, vectorised.capacity);
            if (subset.all)
                EXPECT_TRUE(scalar.compact());
            else
                EXPECT_GT(scalar.capacity, 48u);  // the clump grew the slab
            for (Index i = 0; i < pts.size(); ++i) {
                const auto a = scalar.of(i), b = vectorised.of(i);
                ASSERT_EQ(std::vector<Index>(a.begin(), a.end()), std::vector<Index>(b.begin(), b.end()))
                    << "particle " << i << (self ? " (self excluded)" : "");
            }
        }
        // A scattered subset on a grid that keeps its coordinates: the filter reads the grid's
        // slot ranges (masked last vectors) instead of the candidate cache.
        UniformGrid kept(Aabb{Vec3d(-1, -1, -1), Vec3d(0.5, 0.5, 0.5)}, h, "grid", true);
        kept.build(pts);
        std::vector<Index> scattered;
        for (Index i = 0; i < pts.size(); i += 37) scattered.push_back(i);
        NeighbourLists scalar, vectorised;
        build_neighbour_lists(kept, pts, pts, h, true, QuerySubset{scattered, false, false}, scalar, false);
        build_neighbour_lists(kept, pts, pts, h, true, QuerySubset{scattered, false, false}, vectorised, true);
        for (Index i : scattered) {
            const auto a = scalar.of(i), b = vectorised.of(i);
            ASSERT_EQ(std::vector<Index>(a.begin(), a.end()), std::vector<Index>(b.begin(), b.end()))
                << "particle " << i << " (scattered subset)";
        }
    });
}

// The compact layout (every list at once) follows a permutation of the particles like the slab
// does, survives the checkpoint form (concatenated / assign_compact) entry for entry, and a
// subset rebuild after it keeps the other particles' lists (the slab takes them over).
TEST(NeighbourSearch, CompactListsPermuteRoundTripAndBecomeASlab) {
    const Real h = 0.08f;
    auto pts = cloud(2500, h, 8);
    UniformGrid grid(Aabb{Vec3d(-1, -1, -1), Vec3d(0.5, 0.5, 0.5)}, h);
    grid.build(pts);
    NeighbourLists lists;
    build_neighbour_lists(grid, pts, pts, h, true, QuerySubset{}, lists, true);
    ASSERT_TRUE(lists.compact());
    ASSERT_EQ(lists.blocks.size(), (pts.size() + NeighbourLists::kBlock - 1) / NeighbourLists::kBlock);

    NeighbourLists copy;
    copy.assign_compact(lists.counts(), lists.concatenated());
    for (Index i = 0; i < pts.size(); ++i) {
        const auto a = lists.of(i), b = copy.of(i);
        ASSERT_EQ(std::vector<Index>(a.begin(), a.end()), std::vector<Index>(b.begin(), b.end())) << "particle " << i;
    }

    std::vector<Index> perm(pts.size());
    for (Index i = 0; i < perm.size(); ++i) perm[i] = i;
    std::shuffle(perm.begin(), perm.end(), std::mt19937(4));
    std::vector<Vec3> moved(pts.size());
    for (Index i = 0; i < perm.size(); ++i) moved[i] = pts[perm[i]];
    lists.permute(perm, true);
    std::vector<Index> all(pts.size());
    for (Index i = 0; i < all.size(); ++i) all[i] = i;
    expect_equal_to_brute(grid, moved, moved, h, true, lists, all);

    // A subset rebuild turns the layout into a slab and keeps everybody else's list.
    grid.build(moved);
    const std::vector<Index> few{3, 500, 1700};
    build_neighbour_lists(grid, moved, moved, h, true, QuerySubset{few, false}, lists, true);
    EXPECT_FALSE(lists.compact());
    expect_equal_to_brute(grid, moved, moved, h, true, lists, all);
}

// Binned stepping's layout (QuerySubset::keep_others = false): the subset's lists are built
// compact and equal brute force; every other list is empty, including those of the previous
// subset (also after a subset of every row); a permutation carries the subset along; a full build
// afterwards is whole again.
TEST(NeighbourSearch, CompactSubsetListsHoldTheSubsetOnly) {
    for (const bool simd : {false, true}) {
        SCOPED_TRACE(simd ? "vectorised filter" : "scalar filter");
        const Real h = 0.08f;
        auto pts = cloud(2500, h, 11);
        UniformGrid grid(Aabb{Vec3d(-1, -1, -1), Vec3d(0.5, 0.5, 0.5)}, h);
        grid.build(pts);
        NeighbourLists lists;
        std::vector<Index> all(pts.size());
        for (Index i = 0; i < all.size(); ++i) all[i] = i;
        std::mt19937 rng(5);
        std::vector<Index> first, second;  // 10 % and 50 % of the rows, ascending
        for (Index i = 0; i < pts.size(); ++i) {
            if (rng() % 10 == 0) first.push_back(i);
            if (rng() % 2 == 0) second.push_back(i);
        }
        auto check = [&](const std::vector<Vec3>& at, const std::vector<Index>& subset) {
            std::vector<char> in(at.size(), 0);
            for (Index i : subset) in[i] = 1;
            expect_equal_to_brute(grid, at, at, h, true, lists, subset);
            for (Index i = 0; i < at.size(); ++i) {
                if (!in[i]) {
                    ASSERT_EQ(lists.size_of(Index(i)), 0u) << "particle " << i << " is not in the subset";
                }
            }
            EXPECT_EQ(lists.queried, subset);
        };
        build_neighbour_lists(grid, pts, pts, h, true, QuerySubset{first, false, false}, lists, simd);
        ASSERT_TRUE(lists.compact());
        check(pts, first);
        build_neighbour_lists(grid, pts, pts, h, true, QuerySubset{second, false, false}, lists, simd);
        check(pts, second);
        // A permutation carries the subset's lists and its rows along.
        std::vector<Index> perm(pts.size()), inverse(pts.size());
        for (Index i = 0; i < perm.size(); ++i) perm[i] = i;
        std::shuffle(perm.begin(), perm.end(), std::mt19937(6));
        for (Index i = 0; i < perm.size(); ++i) inverse[perm[i]] = i;
        std::vector<Vec3> moved(pts.size());
        for (Index i = 0; i < perm.size(); ++i) moved[i] = pts[perm[i]];
        lists.permute(perm, true);
        std::vector<Index> carried;
        for (Index i : second) carried.push_back(inverse[i]);
        std::sort(carried.begin(), carried.end());
        grid.build(moved);
        check(moved, carried);
        // The next subset build empties the carried rows that it does not query.
        build_neighbour_lists(grid, moved, moved, h, true, QuerySubset{first, false, false}, lists, simd);
        check(moved, first);
        // A subset of every row (built as every list) and then a smaller one: every row's list,
        // then the smaller subset's alone.
        build_neighbour_lists(grid, moved, moved, h, true, QuerySubset{all, false, false}, lists, simd);
        check(moved, all);
        build_neighbour_lists(grid, moved, moved, h, true, QuerySubset{second, false, false}, lists, simd);
        check(moved, second);
        build_neighbour_lists(grid, moved, moved, h, true, QuerySubset{}, lists, simd);
        EXPECT_TRUE(lists.queried.empty());
        expect_equal_to_brute(grid, moved, moved, h, true, lists, all);
    }
}

// A subset build whose queries are scattered (binned and individual stepping) reads most cells'
// candidates straight from a grid that keeps its coordinates, range by range with the last
// vector of each range masked, instead of filling the cell's cache: its lists must equal the
// cache's entry for entry, in order (a tail read past a range would add candidates of the next
// range twice or out of order), and brute force. 3 % and 30 % of the rows, both layouts, both
// filters.
TEST(NeighbourSearch, ScatteredSubsetsReadTheGridDirectlyWithTheSameLists) {
    for (const bool simd : {false, true}) {
        SCOPED_TRACE(simd ? "vectorised filter" : "scalar filter");
        const Real h = 0.08f;
        const auto pts = cloud(3000, h, 13);
        UniformGrid grid(Aabb{Vec3d(-1, -1, -1), Vec3d(0.5, 0.5, 0.5)}, h, "grid", true);
        grid.build(pts);
        NeighbourLists every;
        build_neighbour_lists(grid, pts, pts, h, true, QuerySubset{}, every, simd);
        std::mt19937 rng(21);
        for (const unsigned per_hundred : {3u, 30u}) {
            std::vector<Index> subset;
            for (Index i = 0; i < pts.size(); ++i)
                if (rng() % 100 < per_hundred) subset.push_back(i);
            for (const bool keep_others : {false, true}) {
                NeighbourLists lists;
                build_neighbour_lists(grid, pts, pts, h, true, QuerySubset{subset, false, keep_others}, lists, simd);
                EXPECT_EQ(lists.compact(), !keep_others);
                for (Index i : subset) {
                    const auto a = every.of(i), b = lists.of(i);
                    ASSERT_EQ(std::vector<Index>(a.begin(), a.end()), std::vector<Index>(b.begin(), b.end()))
                        << "particle " << i << ", " << per_hundred << " % subset, " << (keep_others ? "slab" : "compact");
                }
                expect_equal_to_brute(grid, pts, pts, h, true, lists, subset);
            }
        }
    }
}

// A grid kept after its particles moved (UniformGrid::set_drift, binned stepping's sparse steps)
// must give exactly what a grid built from the moved positions gives: the same lists in the
// same order (so that sums over them are bit for bit the same), and for_each_candidate the
// same in-range candidates in the same order. Every particle moves by a random vector of
// length up to the declared drift (0.2 h), so many change cell; the subset of queries is 3 %,
// 30 % and 100 %. A drift declared too short must be caught by the comparison (the last block
// checks the test can fail: with the reach not widened, lists lose particles).
TEST(NeighbourSearch, DriftedGridEqualsAFreshGridInOrder) {
    for (const bool simd : {false, true})
        for (const bool keep_coordinates : {true, false}) {
            SCOPED_TRACE(std::string(simd ? "vectorised filter" : "scalar filter") +
                         (keep_coordinates ? ", kept coordinates" : ", gathered"));
            const Real h = 0.08f, drift = 0.2f * h;
            const auto built = cloud(4000, h, 17);
            std::mt19937 rng(5);
            std::uniform_real_distribution<Real> u(-1, 1);
            std::vector<Vec3> moved(built);
            std::size_t changed_cell = 0;
            const Aabb box{Vec3d(-1, -1, -1), Vec3d(0.5, 0.5, 0.5)};
            UniformGrid kept(box, h, "grid", keep_coordinates), fresh(box, h, "grid", keep_coordinates);
            kept.build(built);
            for (auto& x : moved) {
                Vec3 d;
                do d = Vec3(u(rng), u(rng), u(rng)); while (d.norm() > 1);
                const std::int64_t before = kept.cell_of(x);
                x += Real(0.999) * drift * d;
                changed_cell += kept.cell_of(x) != before;
            }
            ASSERT_GT(changed_cell, moved.size() / 10);  // the test moves particles across cells
            kept.set_drift(drift);
            fresh.build(moved);
            for (const unsigned per_hundred : {3u, 30u, 100u}) {
                std::vector<Index> subset;
                for (Index i = 0; i < moved.size(); ++i)
                    if (per_hundred == 100 || rng() % 100 < per_hundred) subset.push_back(i);
                NeighbourLists a, b;
                build_neighbour_lists(fresh, moved, moved, h, true, QuerySubset{subset, false, false}, a, simd);
                build_neighbour_lists(kept, moved, moved, h, true, QuerySubset{subset, false, false}, b, simd);
                for (Index i : subset) {
                    const auto la = a.of(i), lb = b.of(i);
                    ASSERT_EQ(std::vector<Index>(la.begin(), la.end()), std::vector<Index>(lb.begin(), lb.end()))
                        << "particle " << i << ", " << per_hundred << " % subset";
                }
            }
            // The walls' gather (WallPressureSystem): the in-range candidates of points anywhere.
            for (int k = 0; k < 300; ++k) {
                const Vec3 at(Real(-1) + Real(1.5) * (u(rng) + 1) / 2, Real(-1) + Real(1.5) * (u(rng) + 1) / 2,
                              Real(-1) + Real(1.5) * (u(rng) + 1) / 2);
                std::vector<Index> fa, fb;
                fresh.for_each_candidate(at, moved, [&](Index j, const Vec3& xj) {
                    if ((at - xj).squaredNorm() < h * h) fa.push_back(j);
                });
                kept.for_each_candidate(at, moved, [&](Index j, const Vec3& xj) {
                    if ((at - xj).squaredNorm() < h * h) fb.push_back(j);
                });
                ASSERT_EQ(fa, fb) << "point " << k;
            }
            // The same grid declared to have drifted too little loses neighbours.
            UniformGrid understated(box, h, "grid", keep_coordinates);
            understated.build(built);
            understated.set_drift(Real(0.01) * drift);
            NeighbourLists a, c;
            build_neighbour_lists(fresh, moved, moved, h, true, QuerySubset{}, a, simd);
            std::vector<Index> every(moved.size());
            for (Index i = 0; i < every.size(); ++i) every[i] = i;
            build_neighbour_lists(understated, moved, moved, h, true, QuerySubset{every, false, false}, c, simd);
            EXPECT_LT(c.total(), a.total());
            EXPECT_THROW(understated.set_drift(Real(0.5) * h), std::logic_error);
        }
}

// A box far too large for its cell size (the 171 x 40 x 40 m dam break of the robustness
// issue: 2^31 cells and more) is refused with the cell count and the memory, before anything
// is allocated; one just below the limit's order of magnitude is built.
// UniformGrid::in_built_cells: true exactly when every particle of the range lies in the cell
// it was sorted into, and then the grid equals a build from the moved positions; false without
// keep_cells, with a drift, or when the set's size changed.
TEST(NeighbourSearch, InBuiltCellsTellsWhenABuildWouldChangeNothing) {
    const Real h = 0.1f;
    std::vector<Vec3> pts = cloud(3000, h, 4);
    const Aabb box{Vec3d(-1.5, -1.5, -1.5), Vec3d(1, 1, 1)};
    UniformGrid grid(box, h);
    grid.mark_empty_neighbourhoods(true);
    grid.keep_cells(true);
    grid.build(pts);
    // Moved inside their cells: the particles 1000..1999 towards their cell's centre by a tenth.
    std::vector<Vec3> moved = pts;
    for (std::size_t i = 1000; i < 2000; ++i) {
        const Eigen::Vector3i c = grid.cell_coords(pts[i]);
        const Vec3 centre = grid.origin() + (c.cast<Real>() + Vec3::Constant(0.5f)) * h;
        moved[i] = pts[i] + Real(0.1) * (centre - pts[i]);
        ASSERT_EQ(grid.cell_of(moved[i]), grid.cell_of(pts[i]));
    }
    EXPECT_TRUE(grid.in_built_cells(moved, 1000, 2000));
    UniformGrid fresh(box, h);
    fresh.mark_empty_neighbourhoods(true);
    fresh.build(moved);
    EXPECT_TRUE(std::equal(fresh.sorted_index().begin(), fresh.sorted_index().end(), grid.sorted_index().begin()));
    for (std::int64_t c = 0; c < std::int64_t(fresh.cell_count()); ++c) {
        ASSERT_EQ(fresh.cell_start(c), grid.cell_start(c)) << "cell " << c;
        ASSERT_EQ(fresh.empty_around(c), grid.empty_around(c)) << "cell " << c;
    }
    // One particle of the range across a cell face: false (a build would move it to another slot).
    moved[1500] = pts[1500] + Vec3(h, 0, 0);
    EXPECT_FALSE(grid.in_built_cells(moved, 1000, 2000));
    EXPECT_TRUE(grid.in_built_cells(moved, 1501, 2000));  // the range without it
    // Without keep_cells, with a drift, or another set size: false.
    std::vector<Vec3> fewer(pts.begin(), pts.end() - 1);
    EXPECT_FALSE(grid.in_built_cells(fewer, 0, 10));
    UniformGrid plain(box, h);
    plain.build(pts);
    EXPECT_FALSE(plain.in_built_cells(pts, 0, pts.size()));
    grid.build(pts);
    EXPECT_TRUE(grid.in_built_cells(pts, 0, pts.size()));
    grid.set_drift(0.01f);
    EXPECT_FALSE(grid.in_built_cells(pts, 0, pts.size()));
}

TEST(UniformGridLimits, TooManyCellsIsRefusedWithCountAndMemory) {
    try {
        UniformGrid grid(Aabb{Vec3d(0, 0, 0), Vec3d(171, 40, 40)}, 0.04f, "fluid grid");
        FAIL() << "a grid of 4275 x 1000 x 1000 cells was built";
    } catch (const InputError& e) {
        const std::string m = e.what();
        EXPECT_NE(m.find("fluid grid over [0 0 0] - [171  40  40] m"), std::string::npos) << m;
        EXPECT_NE(m.find("4278 x 1003 x 1003 = 4.30371e+09 cells (16.0326 GiB"), std::string::npos) << m;
        EXPECT_NE(m.find("GiB for its cell table"), std::string::npos) << m;
        EXPECT_NE(m.find("at most 4294967294 cells"), std::string::npos) << m;
    }
    UniformGrid ok(Aabb{Vec3d(0, 0, 0), Vec3d(10, 4, 4)}, 0.04f);  // 2.7 M cells
    EXPECT_EQ(ok.cell_count(), std::size_t(ok.dims().prod()));
    EXPECT_GT(ok.cell_count(), 2'500'000u);
}

// The re-sort's order (Simulation::spatial_sort) against brute force: cells by Morton code
// (bit i of x, y, z at bits 3i, 3i + 1, 3i + 2), ties by index, from a bit-by-bit interleave and
// std::stable_sort. Exact equality; on a cloud and on a grid 3,000 cells long, whose codes take
// four of the radix sort's 11-bit passes.
TEST(NeighbourSearch, ZOrderPermutationIsMortonThenIndex) {
    const auto brute = [](const UniformGrid& grid, const std::vector<Vec3>& pts) {
        std::vector<std::uint64_t> code(pts.size());
        for (std::size_t i = 0; i < pts.size(); ++i) {
            const Eigen::Vector3i c = grid.cell_coords(pts[i]);
            for (int b = 0; b < 21; ++b)
                for (int a = 0; a < 3; ++a) code[i] |= std::uint64_t((c[a] >> b) & 1) << (3 * b + a);
        }
        std::vector<Index> order(pts.size());
        for (std::size_t i = 0; i < order.size(); ++i) order[i] = Index(i);
        std::stable_sort(order.begin(), order.end(), [&](Index a, Index b) { return code[a] < code[b]; });
        return order;
    };
    const Real h = 0.1f;
    const auto pts = cloud(5000, h, 7);
    UniformGrid grid(Aabb{Vec3d(-1, -1, -1), Vec3d(0.5, 0.5, 0.5)}, h);
    EXPECT_EQ(zorder_permutation(grid, pts), brute(grid, pts));

    UniformGrid long_grid(Aabb{Vec3d(0, 0, 0), Vec3d(300, 0.3, 0.3)}, h);
    ASSERT_GT(long_grid.dims()[0], 2048);
    std::vector<Vec3> line;
    std::uint64_t state = 12345;
    const auto uniform = [&] {
        state = state * 6364136223846793005ULL + 1442695040888963407ULL;
        return double(state >> 11) / double(1ULL << 53);
    };
    for (int i = 0; i < 20000; ++i) line.emplace_back(Real(300 * uniform()), Real(0.3 * uniform()), Real(0.3 * uniform()));
    EXPECT_EQ(zorder_permutation(long_grid, line), brute(long_grid, line));
}

TEST(NeighbourSearch, ZOrderPermutationIsAPermutation) {
    const Real h = 0.1f;
    auto pts = cloud(1000, h, 5);
    UniformGrid grid(Aabb{Vec3d(-1, -1, -1), Vec3d(0.5, 0.5, 0.5)}, h);
    auto perm = zorder_permutation(grid, pts);
    std::set<Index> s(perm.begin(), perm.end());
    EXPECT_EQ(s.size(), pts.size());
    EXPECT_EQ(*s.rbegin(), pts.size() - 1);
    // Consecutive particles in z-order are mostly in the same or adjacent cells.
    std::size_t near = 0;
    for (std::size_t i = 1; i < perm.size(); ++i)
        if ((grid.cell_coords(pts[perm[i]]) - grid.cell_coords(pts[perm[i - 1]])).cwiseAbs().maxCoeff() <= 1) ++near;
    EXPECT_GT(near, perm.size() / 2);
}
