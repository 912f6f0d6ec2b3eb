// Binned stepping's lazy drift (systems/integrate/drift_system.hpp), He et al. Alg. 2 lines
// 19-21 and 9 from each row's base state, against that closed form in double:
//   dt = t - t_last,  v = v_last + dt a,  x = x_last + dt v,  rho = rho_last + dt drho/dt,
//   p = Tait(rho) = B ((max(rho, rho0) / rho0)^7 - 1)
// on a jittered block of 12,000 rows whose base states are random (|a| <= 87 m/s^2) and whose
// t_last are up to 0.4 ms behind the clock (one in eight at the clock: current, left alone).
// * DriftSystem writes every behind row's position and nothing else;
// * DriftRowsSystem writes velocity, density and pressure of exactly the active rows and their
//   fluid neighbours (lists built by FluidNeighbourSystem, which NeighbourSearch tests against
//   brute force), lists them ascending in res::drifted, and leaves every other row's bits as
//   they were, at 5 and 80 active rows (one task; marks and a scan) and n/40 rows lying together
//   (marks and a scan); every row from n/16 active rows on (n/10 here), when the marked rows are
//   half the rows or more (n/30 scattered rows), and with `all`;
// * drift_fluid (World::synchronise) brings every behind row's four columns to the clock.
// Tolerance: 2e-6 relative to the value's scale (float arithmetic of a few roundings); positions
// within 1e-9 + 8e-8 m (a few ulps of 0.4 m), where a wrong term, e.g. v_last for v in line 21,
// is off by dt^2 |a| up to 1.4e-5 m.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <vector>

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/data/world_init.hpp"
#include "engine/graph/system.hpp"
#include "systems/integrate/drift_system.hpp"
#include "systems/neighbours/fluid_grid_system.hpp"
#include "systems/neighbours/fluid_neighbours_system.hpp"
#include "test_scenes.hpp"

using namespace sph;

namespace {

constexpr Tick kNow = 123'000'000'000;  // 0.123 s
constexpr Real kSentinel = 12345.0f;

struct Fixture {
    World w;
    std::vector<Vec3> x0, v0, a;
    std::vector<Real> rho0, drho;
    std::vector<std::int64_t> t_last;

    /// The block 0.4 x 0.2 x 0.15 m at r = 5 mm (12,000 rows) unless given.
    explicit Fixture(Vec3d fluid = Vec3d(0.4, 0.2, 0.15), Vec3d box = Vec3d(0.5, 0.3, 0.2), double r = 0.005) {
        initialise_world(w, test::tank_scene(fluid, box, r));
        test::jitter(w, 11, 0.3f);
        DriftSystem().register_components(w);
        DriftRowsSystem().register_components(w);
        w.clock.t_ticks = kNow;
        w.clock.t = to_seconds(kNow);
        auto& s = w.fluid.store;
        const std::size_t n = s.size();
        std::mt19937 rng(5);
        std::uniform_real_distribution<Real> u(-1, 1);
        std::uniform_int_distribution<std::int64_t> behind(1, 400'000'000);  // up to 0.4 ms
        auto x = s.get(comp::position);
        for (std::size_t i = 0; i < n; ++i) {
            x0.push_back(x[i]);
            v0.push_back(2 * Vec3(u(rng), u(rng), u(rng)));
            a.push_back(50 * Vec3(u(rng), u(rng), u(rng)));
            rho0.push_back(w.physics.rest_density * (1 + Real(0.02) * u(rng)));
            drho.push_back(200 * u(rng));
            t_last.push_back(i % 8 == 0 ? kNow : kNow - behind(rng));
        }
        std::copy(x0.begin(), x0.end(), s.get(comp::position_last).begin());
        std::copy(v0.begin(), v0.end(), s.get(comp::velocity_last).begin());
        std::copy(a.begin(), a.end(), s.get(comp::acceleration).begin());
        std::copy(rho0.begin(), rho0.end(), s.get(comp::density_last).begin());
        std::copy(drho.begin(), drho.end(), s.get(comp::drho_dt).begin());
        std::copy(t_last.begin(), t_last.end(), s.get(comp::t_last).begin());
        run_system(FluidGridSystem(), w);
        run_system(FluidNeighbourSystem(), w);
        reset_outputs();
    }
    void reset_outputs() {
        auto& s = w.fluid.store;
        std::fill(s.get(comp::velocity).begin(), s.get(comp::velocity).end(), Vec3::Constant(kSentinel));
        std::fill(s.get(comp::density).begin(), s.get(comp::density).end(), kSentinel);
        std::fill(s.get(comp::pressure).begin(), s.get(comp::pressure).end(), kSentinel);
    }
    double dt(std::size_t i) const { return to_seconds(kNow - t_last[i]); }
    Vec3d v(std::size_t i) const { return v0[i].cast<double>() + dt(i) * a[i].cast<double>(); }
    Vec3d x(std::size_t i) const { return x0[i].cast<double>() + dt(i) * v(i); }
    double rho(std::size_t i) const { return double(rho0[i]) + dt(i) * double(drho[i]); }
    double p(std::size_t i) const {
        const double r0 = w.physics.rest_density;
        return double(w.physics.tait_b) * (std::pow(std::max(rho(i), r0) / r0, 7) - 1);
    }
    /// Checks velocity, density and pressure: the closed form on `drifted` rows that are behind,
    /// the sentinel elsewhere.
    void expect_rows(const std::vector<Index>& drifted) const {
        const auto& s = w.fluid.store;
        const auto vv = s.get(comp::velocity);
        const auto rr = s.get(comp::density);
        const auto pp = s.get(comp::pressure);
        std::vector<std::uint8_t> in(vv.size(), 0);
        for (Index i : drifted) in[i] = 1;
        int bad = 0;
        for (std::size_t i = 0; i < vv.size() && bad < 5; ++i) {
            if (in[i] && t_last[i] != kNow) {
                const bool ok = (vv[i].cast<double>() - v(i)).norm() <= 2e-6 * (1 + v(i).norm()) &&
                                std::abs(rr[i] - rho(i)) <= 2e-6 * rho(i) &&
                                std::abs(pp[i] - p(i)) <= 2e-6 * (std::abs(p(i)) + double(w.physics.tait_b));
                bad += !ok;
                EXPECT_TRUE(ok) << "row " << i << ": v " << vv[i].transpose() << " / " << v(i).transpose() << ", rho "
                                << rr[i] << " / " << rho(i) << ", p " << pp[i] << " / " << p(i);
            } else {
                const bool ok = vv[i] == Vec3::Constant(kSentinel) && rr[i] == kSentinel && pp[i] == kSentinel;
                bad += !ok;
                EXPECT_TRUE(ok) << "row " << i << " written (drifted " << int(in[i]) << ")";
            }
        }
    }
};

}  // namespace

TEST(Drift, PositionsOfEveryRowBehindTheClock) {
    Fixture f;
    run_system(DriftSystem(), f.w);
    const auto x = f.w.fluid.store.get(comp::position);
    double worst = 0;
    for (std::size_t i = 0; i < x.size(); ++i) {
        if (f.t_last[i] == kNow) {
            ASSERT_EQ(x[i], f.x0[i]) << "row " << i << " is current: left as it was";
            continue;
        }
        worst = std::max(worst, (x[i].cast<double>() - f.x(i)).norm());
    }
    EXPECT_LT(worst, 1e-9 + 2e-7 * 0.4);  // float positions of <= 0.4 m: a few ulps
    EXPECT_GT(x.size(), 10000u);
    // Nothing else written.
    EXPECT_EQ(f.w.fluid.store.get(comp::velocity)[1], Vec3::Constant(kSentinel));
}

TEST(Drift, RowsAreTheActiveRowsAndTheirNeighbours) {
    Fixture f;
    const std::size_t n = f.w.fluid.size();
    std::mt19937 rng(3);
    ASSERT_GT(n, DriftRowsSystem::kStreamRows * (n / 40));  // n/40 active rows take the marking path
    // Scattered sets of 5 (one task), 80 and n/30 (marked; n/30 reach over half the rows, so
    // they are streamed after the count), n/10 (streamed without marking); then n/40 rows lying
    // together (marked; their neighbours are under half the rows: the scan).
    struct Case {
        std::size_t m;
        bool together;
    };
    DriftRowsSystem sys;  // one system through the cases: each finds the last one's claim marks cleared
    for (const Case c : {Case{5, false}, Case{80, false}, Case{n / 30, false}, Case{n / 10, false}, Case{n / 40, true}}) {
        const std::size_t m = c.m;
        f.reset_outputs();
        std::vector<Index> all(n);
        for (std::size_t i = 0; i < n; ++i) all[i] = Index(i);
        if (!c.together) std::shuffle(all.begin(), all.end(), rng);
        f.w.active_set.assign(all.begin(), all.begin() + std::ptrdiff_t(m));
        std::sort(f.w.active_set.begin(), f.w.active_set.end());
        std::set<Index> want(f.w.active_set.begin(), f.w.active_set.end());
        for (Index i : f.w.active_set)
            for (Index j : f.w.fluid_neighbours.of(i)) want.insert(j);
        const bool streamed = DriftRowsSystem::kStreamRows * m >= n ||
                              (m > 64 && double(want.size()) >= DriftRowsSystem::kStreamMarked * double(n));
        std::printf("%zu active rows%s: %zu read, %s\n", m, c.together ? " together" : "", want.size(),
                    streamed ? "every row streamed" : "marked");
        EXPECT_EQ(streamed, m == n / 10 || (m == n / 30 && !c.together)) << "the case does not test the path meant";
        if (streamed)
            for (std::size_t i = 0; i < n; ++i) want.insert(Index(i));
        run_system(sys, f.w);
        EXPECT_EQ(f.w.drifted, std::vector<Index>(want.begin(), want.end())) << m << " active rows";
        f.expect_rows(f.w.drifted);
        // A second step with the same set finds the claim marks cleared.
        f.reset_outputs();
        run_system(sys, f.w);
        EXPECT_EQ(f.w.drifted.size(), want.size()) << m << " active rows, second run";
    }
}

// The marking path with several tasks (the thread sanitizer's stage): 96,000 rows at r = 2.5 mm
// (six 16,384-row scan chunks) and 700 active rows (three 256-row marking tasks, under the n/128
// at which every row is streamed), against the same set as above. The active rows are one run of
// consecutive rows (neighbours on the lattice), so that rows near the end of one task and the
// start of the next mark the same neighbours: a plain store there is a race TSan reports
// (checked); scattered rows rarely share one.
TEST(Drift, RowsAreMarkedInParallelAcrossChunks) {
    Fixture f(Vec3d(0.4, 0.2, 0.15), Vec3d(0.5, 0.3, 0.2), 0.0025);
    const std::size_t n = f.w.fluid.size(), m = 700;
    ASSERT_GT(n, 128u * m);
    ASSERT_GT(n, 4u * 16384u);
    f.w.active_set.resize(m);
    for (std::size_t k = 0; k < m; ++k) f.w.active_set[k] = Index(n / 2 + k);
    std::set<Index> want(f.w.active_set.begin(), f.w.active_set.end());
    for (Index i : f.w.active_set)
        for (Index j : f.w.fluid_neighbours.of(i)) want.insert(j);
    DriftRowsSystem sys;
    run_system(sys, f.w);
    EXPECT_EQ(f.w.drifted, std::vector<Index>(want.begin(), want.end()));
    f.expect_rows(f.w.drifted);
}

TEST(Drift, AllRowsAndTheSynchroniseHook) {
    Fixture f;
    run_system(DriftRowsSystem(true), f.w);
    std::vector<Index> every(f.w.fluid.size());
    for (std::size_t i = 0; i < every.size(); ++i) every[i] = Index(i);
    f.expect_rows(every);
    f.reset_outputs();
    ASSERT_TRUE(bool(f.w.synchronise));
    f.w.synchronise(f.w);
    f.expect_rows(every);
    const auto x = f.w.fluid.store.get(comp::position);
    for (std::size_t i = 0; i < x.size(); ++i)
        if (f.t_last[i] != kNow) {
            ASSERT_LT((x[i].cast<double>() - f.x(i)).norm(), 1e-9 + 2e-7 * 0.4) << "row " << i;
        }
}

// Lazy positions (DriftSystem::Rows::AroundDue) on a step that keeps the grid: the grid was built
// at the base positions and every row has since moved at most d (declared: set_drift(d), d the
// largest displacement of the closed form, 0.05-0.25 h here). Brute force over all rows: every
// row whose position at the build lies within h + d of a due row's current position (what a
// kept grid's search reads) is placed, its bits those DriftSystem(Every) writes; every other
// row is untouched; res::placed lists each placed row once. With a grid built this step
// (drift 0) it places nothing (FluidGridSystem placed every row).
namespace {

struct Around {
    Fixture base;          ///< the positions at the build (x0)
    std::vector<Vec3> xe;  ///< every row placed by DriftSystem(Every): the bits expected
    Real drift = 0;
    Vec3d fluid, box;
    double r;

    Around(Vec3d fluid_max, Vec3d box_max, double radius)
        : base(fluid_max, box_max, radius), fluid(fluid_max), box(box_max), r(radius) {
        Fixture eager(fluid, box, r);
        run_system(DriftSystem(), eager.w);
        const auto x = eager.w.fluid.store.get(comp::position);
        xe.assign(x.begin(), x.end());
        double d = 0;
        for (std::size_t i = 0; i < xe.size(); ++i) d = std::max(d, (xe[i] - base.x0[i]).cast<double>().norm());
        const Real h = base.w.physics.h;
        EXPECT_LT(d, 0.25 * h);
        EXPECT_GT(d, 0.05 * h);
        drift = Real(d * 1.001);
    }

    /// Runs the placement for `due` on a kept grid and checks it by brute force; returns the
    /// rows placed.
    std::size_t check(const char* name, const std::vector<Index>& due) const {
        Fixture g(fluid, box, r);  // positions at the build, the grid kept with its drift
        World& w = g.w;
        const std::size_t n = w.fluid.size();
        const Real h = w.physics.h;
        w.fluid_grid.set_drift(drift);
        w.active_set = due;
        run_system(DriftSystem(DriftSystem::Rows::AroundDue), w);
        const auto x = w.fluid.store.get(comp::position);
        std::vector<std::uint8_t> placed(n, 0);
        for (Index i : w.placed) {
            EXPECT_EQ(placed[i], 0) << name << ": row " << i << " listed twice";
            placed[i] = 1;
        }
        // Plain float arithmetic (the sanitizer stages compile the tests at -O0, where Eigen's
        // expressions cost ~10x): |x0_j - x_i| < h + drift along every axis.
        std::vector<float> q;
        for (Index i : due) q.insert(q.end(), {xe[i].x(), xe[i].y(), xe[i].z()});
        const float reach = float(h + drift);
        std::size_t reached = 0;
        int bad = 0;
        for (std::size_t j = 0; j < n && bad < 5; ++j) {
            const float* p = base.x0[j].data();
            bool near = false;
            for (std::size_t k = 0; k < q.size() && !near; k += 3)
                near = std::abs(p[0] - q[k]) < reach && std::abs(p[1] - q[k + 1]) < reach && std::abs(p[2] - q[k + 2]) < reach;
            reached += near;
            if (near && !placed[j]) {
                ADD_FAILURE() << name << ": row " << j << " within reach of a due row not placed";
                ++bad;
            }
            if (placed[j] ? x[j] != xe[j] : x[j] != base.x0[j]) {
                ADD_FAILURE() << name << ": row " << j << (placed[j] ? " placed with other bits" : " written but not listed");
                ++bad;
            }
        }
        std::printf("%s: %zu due rows, %zu rows within reach, %zu placed (%.1f %% of %zu)\n", name, due.size(), reached,
                    w.placed.size(), 100.0 * double(w.placed.size()) / double(n), n);
        // A grid built this step: nothing placed here.
        Fixture b(fluid, box, r);
        b.w.active_set = due;
        run_system(DriftSystem(DriftSystem::Rows::AroundDue), b.w);
        EXPECT_TRUE(b.w.placed.empty()) << name;
        EXPECT_TRUE(std::equal(base.x0.begin(), base.x0.end(), b.w.fluid.store.get(comp::position).begin())) << name;
        return w.placed.size();
    }
};

}  // namespace

// At one due row and a cluster of eight (cell by cell, one task: under 1/16 of the rows and
// under kParallelRows) and at 60 scattered due rows (their cells reach more: every row, streamed).
TEST(Drift, AroundDuePlacesWhatAKeptGridsSearchReads) {
    const Around a(Vec3d(0.4, 0.2, 0.15), Vec3d(0.5, 0.3, 0.2), 0.005);
    const Fixture& f = a.base;
    const std::size_t n = f.w.fluid.size();
    // A cluster: the rows of the cell of row n/2, up to eight.
    std::vector<Index> cluster;
    const std::int64_t c = f.w.fluid_grid.cell_of(f.x0[n / 2]);
    for (Index k = f.w.fluid_grid.cell_start(c); k < f.w.fluid_grid.cell_start(c + 1) && cluster.size() < 8; ++k)
        cluster.push_back(f.w.fluid_grid.sorted_index()[k]);
    std::sort(cluster.begin(), cluster.end());
    std::vector<Index> scattered;
    for (std::size_t i = 0; i < 60; ++i) scattered.push_back(Index(i * (n / 60)));
    for (const auto& [name, due] : {std::pair<const char*, std::vector<Index>>{"one row", {Index(n / 3)}},
                                    {"a cluster", cluster}}) {
        const std::size_t placed = a.check(name, due);
        EXPECT_LT(double(placed), DriftSystem::kStreamShare * double(n)) << name;
        EXPECT_LT(placed, DriftSystem::kParallelRows) << name;
    }
    EXPECT_EQ(a.check("60 scattered", scattered), n);
}

// The parallel placement (kParallelRows or more rows placed, under 1/16 of them): 64 due rows on
// a 4 x 4 x 4 lattice 2 h apart in a block of 192,000 rows (r = 2.5 mm), whose reach covers about
// 1,000 cells. The tasks claim disjoint cells, so a row placed twice or an entry of res::placed
// left unwritten fails the brute-force check (and the race would show under ThreadSanitizer).
TEST(Drift, AroundDuePlacesManyCellsInParallel) {
    const Around a(Vec3d(0.4, 0.3, 0.2), Vec3d(0.45, 0.35, 0.25), 0.0025);
    const Fixture& f = a.base;
    const std::size_t n = f.w.fluid.size();
    const Real h = f.w.physics.h;
    std::vector<Index> due;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            for (int k = 0; k < 4; ++k) {
                // The first row of the cell of each lattice point.
                const Vec3 target = Vec3(0.2f, 0.15f, 0.1f) + Real(2) * h * Vec3(Real(i - 2), Real(j - 2), Real(k - 2));
                const std::int64_t c = f.w.fluid_grid.cell_of(target);
                ASSERT_LT(f.w.fluid_grid.cell_start(c), f.w.fluid_grid.cell_start(c + 1));
                due.push_back(f.w.fluid_grid.sorted_index()[f.w.fluid_grid.cell_start(c)]);
            }
    std::sort(due.begin(), due.end());
    const std::size_t placed = a.check("a 4 x 4 x 4 lattice", due);
    EXPECT_GE(placed, DriftSystem::kParallelRows);
    EXPECT_LT(double(placed), DriftSystem::kStreamShare * double(n));
}
