// StepStatsSystem (systems/metrics/step_stats_system.hpp): the per-step statistics that He et
// al. eq. 6-7 (v_max, a_max) and Ihmsen et al. 2010 eq. 16-27 (rho_err avg/max, v_max, F_max)
// feed on, and the work counters of stats.csv, against a brute-force double-precision
// recomputation on a jittered block with random densities (some below rho0: rho_err is the
// compression max(rho/rho0 - 1, 0)), velocities and accelerations. Neighbour pairs are counted
// by brute force over all pairs (r < h, self excluded), not from the lists.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/data/world_init.hpp"
#include "engine/graph/system.hpp"
#include "systems/metrics/step_stats_system.hpp"
#include "systems/neighbours/fluid_grid_system.hpp"
#include "systems/neighbours/fluid_neighbours_system.hpp"
#include "test_scenes.hpp"

using namespace sph;

namespace {

// A 16 x 10 x 10 block (1,600 particles: two blocks of the system's 1,024-particle parallel
// reduction), jittered by 0.3 r, with rho in rho0 (1 +- 3 %), |v| up to 2 sqrt(3) m/s and
// |a| up to 20 sqrt(3) m/s^2, and neighbour lists built by the grid systems.
struct Block {
    World w;
    explicit Block(std::uint32_t seed) {
        Scene s = test::tank_scene(Vec3d(0.32, 0.2, 0.2), Vec3d(0.4, 0.3, 0.3));
        initialise_world(w, s);
        w.fluid.store.add(comp::density);
        w.fluid.store.add(comp::acceleration);
        std::mt19937 rng(seed);
        std::uniform_real_distribution<Real> u(-1, 1);
        auto x = w.fluid.store.get(comp::position);
        auto v = w.fluid.store.get(comp::velocity);
        auto a = w.fluid.store.get(comp::acceleration);
        auto rho = w.fluid.store.get(comp::density);
        for (std::size_t i = 0; i < x.size(); ++i) {
            x[i] += Vec3(u(rng), u(rng), u(rng)) * (0.3f * w.physics.particle_radius);
            v[i] = 2 * Vec3(u(rng), u(rng), u(rng));
            a[i] = 20 * Vec3(u(rng), u(rng), u(rng));
            rho[i] = w.physics.rest_density * (1 + 0.03f * u(rng));
        }
        run_system(FluidGridSystem(), w);
        run_system(FluidNeighbourSystem(), w);
    }
};

struct Reference {
    double err_avg = 0, err_max = 0, v_max = 0, v_mean = 0, a_max = 0, a_second = 0;
    Index a_arg = 0;
    std::uint64_t pairs = 0;
    std::size_t clamped = 0;  // particles with rho < rho0 (zero compression)
};

// Double precision from the float inputs; `active` (optional) limits the pair count, and with
// `active_stats` the density error, v_max and a_max too (binned stepping's Rows::Active).
Reference brute_force(const World& w, const std::vector<std::uint8_t>* active = nullptr, bool active_stats = false) {
    const auto x = w.fluid.store.get(comp::position);
    const auto v = w.fluid.store.get(comp::velocity);
    const auto a = w.fluid.store.get(comp::acceleration);
    const auto rho = w.fluid.store.get(comp::density);
    const double rho0 = w.physics.rest_density;
    const Real hr = w.physics.h;
    Reference r;
    std::size_t counted = 0;
    for (std::size_t i = 0; i < x.size(); ++i) {
        if (active_stats && !(*active)[i]) continue;
        ++counted;
        const double e = double(rho[i]) / rho0 - 1.0;
        if (e < 0) ++r.clamped;
        r.err_avg += std::max(e, 0.0);
        r.err_max = std::max(r.err_max, e);
        r.v_max = std::max(r.v_max, v[i].cast<double>().norm());
        r.v_mean += v[i].cast<double>().norm();
        const double an = a[i].cast<double>().norm();
        if (an > r.a_max) {
            r.a_second = r.a_max;
            r.a_max = an;
            r.a_arg = Index(i);
        } else {
            r.a_second = std::max(r.a_second, an);
        }
        if (active && !(*active)[i]) continue;
        // The engine's definition of a neighbour, r < h as |x_i - x_j|^2 < h^2 in Real.
        for (std::size_t j = 0; j < x.size(); ++j)
            if (j != i && (x[i] - x[j]).squaredNorm() < hr * hr) ++r.pairs;
    }
    r.err_avg /= double(counted);
    r.v_mean /= double(counted);
    return r;
}

// Flags the rows `pick` chooses (called once per row, in order) as active: the `active` column,
// the world's active set, and the returned flags for brute_force.
template <class Pick>
std::vector<std::uint8_t> activate(World& w, Pick pick) {
    auto column = w.fluid.store.add(comp::active);
    std::vector<std::uint8_t> active(w.fluid.size(), 0);
    for (std::size_t i = 0; i < active.size(); ++i)
        if (pick(Index(i))) active[i] = column[i] = 1, w.active_set.push_back(Index(i));
    return active;
}

}  // namespace

// Tolerances: rho_err is computed from the same float rho by the same double expression, so
// max is exact and avg (a double sum of 1,600 terms of ~1e-2, in another order) agrees to
// 1e-12 relative. v_max, v_mean and a_max: the system squares the float vector in float (three
// products and two sums, <= 3 ulp = 2e-7 relative on |v|^2, 1e-7 on |v|; v_mean sums those in
// double), the reference in double: 1e-6 relative. Pair count and indices: exact.
TEST(StepStats, GlobalMatchesBruteForce) {
    Block b(17);
    World& w = b.w;
    const std::size_t n = w.fluid.size();
    ASSERT_EQ(n, 1600u);
    const Reference ref = brute_force(w);
    // The inputs exercise what they should: some particles are not compressed, so the clamp
    // matters (the unclamped mean would be ~0 instead of ~0.0075), and the largest acceleration
    // stands out from the second by more than the tolerance, so its index is unambiguous.
    ASSERT_GT(ref.clamped, n / 4);
    ASSERT_LT(ref.a_second, ref.a_max * (1 - 1e-5));
    ASSERT_GT(ref.pairs, 20 * n);  // ~30 neighbours each at h = 4 r (interior)

    w.counters.clear();
    run_system(StepStatsSystem(false), w);
    const StepStats& s = w.stats;
    EXPECT_NEAR(s.rho_err_avg, ref.err_avg, 1e-12 * ref.err_avg);
    EXPECT_DOUBLE_EQ(s.rho_err_max, ref.err_max);
    EXPECT_NEAR(s.v_max, ref.v_max, 1e-6 * ref.v_max);
    EXPECT_NEAR(s.v_mean, ref.v_mean, 1e-6 * ref.v_mean);
    ASSERT_LT(ref.v_mean, 0.9 * ref.v_max);  // the mean is not the largest speed under another name
    EXPECT_NEAR(s.a_max, ref.a_max, 1e-6 * ref.a_max);
    EXPECT_EQ(s.a_max_particle, ref.a_arg);
    EXPECT_EQ(w.counter_value("updated"), n);
    EXPECT_EQ(w.counter_value("active"), n);
    EXPECT_EQ(w.counter_value("neighbour_pairs"), ref.pairs);
    // Order of magnitude, from the distributions: mean compression of U(-3 %, 3 %) clamped at 0
    // is 0.75 %; max just below 3 %.
    EXPECT_NEAR(s.rho_err_avg, 0.0075, 0.0015);
    EXPECT_GT(s.rho_err_max, 0.029);
}

// a_max_particle breaks ties by the lowest index, also across the two reduction blocks
// (particles 100 and 1500, and 700 in the first block).
TEST(StepStats, LargestAccelerationTieGoesToLowestIndex) {
    Block b(3);
    World& w = b.w;
    auto a = w.fluid.store.get(comp::acceleration);
    for (const Index i : {Index(1500), Index(700), Index(100)}) a[i] = Vec3(300, -400, 0);  // |a| = 500
    run_system(StepStatsSystem(false), w);
    EXPECT_EQ(w.stats.a_max_particle, 100u);
    EXPECT_NEAR(w.stats.a_max, 500.0, 500.0 * 1e-7);
    a[100] = Vec3(0, 0, 0);
    run_system(StepStatsSystem(false), w);
    EXPECT_EQ(w.stats.a_max_particle, 700u);
}

// Individual stepping (StepStatsSystem(true)): the stats are still over the whole fluid, but
// `updated` is the active count and `neighbour_pairs` counts only the active particles' lists.
TEST(StepStats, IndividualCountsActiveParticlesOnly) {
    Block b(29);
    World& w = b.w;
    const std::size_t n = w.fluid.size();
    std::mt19937 rng(1);
    const std::vector<std::uint8_t> active = activate(w, [&](Index) { return rng() % 3 == 0; });
    const std::size_t k = w.active_set.size();
    ASSERT_GT(k, n / 4);
    ASSERT_LT(k, n / 2);
    w.counters.clear();
    w.counters["active"] = k;  // written by select_active in the recipe
    const Reference ref = brute_force(w, &active);
    run_system(StepStatsSystem(true), w);
    EXPECT_EQ(w.counter_value("updated"), k);
    EXPECT_EQ(w.counter_value("active"), k);  // read, not overwritten
    EXPECT_EQ(w.counter_value("neighbour_pairs"), ref.pairs);
    EXPECT_NEAR(w.stats.rho_err_avg, ref.err_avg, 1e-12 * ref.err_avg);
    EXPECT_NEAR(w.stats.v_max, ref.v_max, 1e-6 * ref.v_max);
    EXPECT_EQ(w.stats.a_max_particle, ref.a_arg);
}

// Binned stepping (Rows::Active): statistics and counts over the active set only, against a
// brute force over the same rows (tolerances as above); a set of every row reads as every row
// (no gather) and must then give what StepStatsSystem(false) gives, to the last bit.
TEST(StepStats, ActiveRowsMatchBruteForceAndTheWholeSetMatchesGlobal) {
    Block b(41);
    World& w = b.w;
    const std::size_t n = w.fluid.size();
    std::mt19937 rng(5);
    const Index largest = brute_force(w).a_arg;  // left out, so that a_max must come from the set
    const std::vector<std::uint8_t> active = activate(w, [&](Index i) { return rng() % 4 == 0 && i != largest; });
    const std::size_t k = w.active_set.size();
    ASSERT_GT(k, n / 5);
    ASSERT_LT(k, n / 3);
    const Reference all = brute_force(w, &active);       // its pair count is the active rows'
    const Reference sub = brute_force(w, &active, true);  // and its statistics are too
    ASSERT_LT(sub.a_max, all.a_max * (1 - 1e-5)) << "the subset must miss the largest |a| for the test to tell";
    w.counters.clear();
    w.counters["active"] = k;
    run_system(StepStatsSystem(false, StepStatsSystem::Rows::Active), w);
    EXPECT_EQ(w.counter_value("updated"), k);
    EXPECT_EQ(w.counter_value("neighbour_pairs"), all.pairs);
    EXPECT_NEAR(w.stats.rho_err_avg, sub.err_avg, 1e-12 * sub.err_avg);
    EXPECT_DOUBLE_EQ(w.stats.rho_err_max, sub.err_max);
    EXPECT_NEAR(w.stats.v_max, sub.v_max, 1e-6 * sub.v_max);
    EXPECT_NEAR(w.stats.v_mean, sub.v_mean, 1e-6 * sub.v_mean);
    EXPECT_NEAR(w.stats.a_max, sub.a_max, 1e-6 * sub.a_max);
    EXPECT_EQ(w.stats.a_max_particle, sub.a_arg);

    // Every row active: the same bits as the whole-fluid statistics.
    w.active_set.clear();
    activate(w, [](Index) { return true; });
    w.counters.clear();
    w.counters["active"] = n;
    run_system(StepStatsSystem(false, StepStatsSystem::Rows::Active), w);
    const StepStats binned = w.stats;
    const std::uint64_t binned_pairs = w.counter_value("neighbour_pairs");
    w.counters.clear();
    run_system(StepStatsSystem(false), w);
    EXPECT_EQ(binned.rho_err_avg, w.stats.rho_err_avg);
    EXPECT_EQ(binned.rho_err_max, w.stats.rho_err_max);
    EXPECT_EQ(binned.v_max, w.stats.v_max);
    EXPECT_EQ(binned.v_mean, w.stats.v_mean);
    EXPECT_EQ(binned.a_max, w.stats.a_max);
    EXPECT_EQ(binned.a_max_particle, w.stats.a_max_particle);
    EXPECT_EQ(binned_pairs, w.counter_value("neighbour_pairs"));
}
