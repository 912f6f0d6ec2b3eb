// BinnedStepSystem (systems/timestep/binned_step_system.hpp) in a step where every particle is
// due: the neighbour limiter's fixed point (bin_i <= bin_j + 2 for every j in i's list, bins
// only lowered from their raw values) against a brute-force serial relaxation over the same
// lists. One fast particle at the end of a long block bounds its neighbours, which bound
// theirs: the bins rise by 2 per ring of neighbours, so the fixed point needs several rounds
// and is only reached if every lowered particle passes its new bound on.
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>
#include <random>
#include <utility>

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/data/world_init.hpp"
#include "engine/graph/system.hpp"
#include "systems/active/binned_body_system.hpp"
#include "systems/active/binned_select_system.hpp"
#include "systems/active/select_active_system.hpp"
#include "systems/integrate/drift.hpp"
#include "systems/integrate/drift_system.hpp"
#include "systems/neighbours/fluid_grid_system.hpp"
#include "systems/neighbours/fluid_neighbours_system.hpp"
#include "systems/timestep/binned_state.hpp"
#include "systems/timestep/binned_step_system.hpp"
#include "test_scenes.hpp"

using namespace sph;

namespace {

// Raw bins from the step's timeline (as BinnedStepSystem takes them at t = 0, where any bin is
// allowed), relaxed over the lists until nothing changes.
std::vector<int> relaxed_bins(const World& w) {
    const auto& tl = w.resources.get<BinTimeline>(res::bin_timeline.name);
    const auto dt_raw = w.fluid.store.get(comp::dt_raw);
    const NeighbourLists& lists = w.fluid_neighbours;
    std::vector<int> bin(dt_raw.size());
    for (std::size_t i = 0; i < bin.size(); ++i) bin[i] = tl.bin_for(dt_raw[i]);
    for (bool changed = true; changed;) {
        changed = false;
        for (std::size_t i = 0; i < bin.size(); ++i)
            for (Index j : lists.of(Index(i)))
                if (bin[i] > bin[j] + 2) {
                    bin[i] = bin[j] + 2;
                    changed = true;
                }
    }
    return bin;
}

enum class Raw { Chain, Edge, Stripes };

struct Outcome {
    int rings = 0;              ///< (largest bin - the fast row's) / 2
    std::uint64_t visited = 0;  ///< counter::limiter_rows
};

// Every row due at t = 0 on 60 x 10 x 10 particles 2 cm apart (6,000 rows: three of the system's
// 2,048-row tasks, so the pushes run concurrently), jittered by 0.2 r, against relaxed_bins.
// Raw::Chain: every particle may take dt_max except the one nearest x = 0, which needs
// 0.7 dt_max / 2^12 (off the fixed ladder, so that rebasing moves it). Raw::Edge: the half at
// x < 0.6 m needs dt_max / 16, the rest may take dt_max (the limiter works along the plane
// between). headroom 0: the fixed ladder dt_max / 2^k and no rebase; BinnedStepSystem::kHeadroom:
// the timeline rebased at this step, as a run's steps with every particle due are.
// `by_cells`: the rows the limiter visits found by grid cell (the grid built this step, as on a
// run's steps with every row due); otherwise (the grid declared drifted) pushed from every row
// that can bound a neighbour.
Outcome check_fixed_point(Raw raw, double headroom, bool by_cells) {
    Scene s = test::tank_scene(Vec3d(1.2, 0.2, 0.2), Vec3d(1.3, 0.3, 0.3));
    s.simulation.stepping.mode = SteppingMode::Binned;
    World w;
    initialise_world(w, s);
    test::jitter(w, 7, 0.2f);
    const SteppingParams& st = w.scene.simulation.stepping;
    BinnedSelectSystem select(st.dt_min, st.dt_max);
    BinnedStepSystem step(st.dt_min, st.dt_max, headroom);
    select.register_components(w);
    step.register_components(w);
    run_system(FluidGridSystem(), w);
    run_system(FluidNeighbourSystem(), w);
    if (!by_cells) w.fluid_grid.set_drift(Real(1e-6));
    const std::size_t n = w.fluid.size();
    EXPECT_EQ(n, 60u * 10u * 10u);
    w.active_set.resize(n);
    std::iota(w.active_set.begin(), w.active_set.end(), Index(0));
    auto active = w.fluid.store.get(comp::active);
    std::fill(active.begin(), active.end(), std::uint8_t(1));
    auto dt_raw = w.fluid.store.get(comp::dt_raw);
    const auto x = w.fluid.store.get(comp::position);
    std::size_t fast = 0;
    for (std::size_t i = 0; i < n; ++i) {
        const bool slow_stripe = int(std::floor(x[i].x() / 0.03f)) % 2 == 0;
        dt_raw[i] = (raw == Raw::Edge && x[i].x() < 0.6f) || (raw == Raw::Stripes && slow_stripe) ? st.dt_max / 16 : st.dt_max;
        if (x[i].x() < x[fast].x()) fast = i;
    }
    if (raw == Raw::Chain) dt_raw[fast] = 0.7 * std::ldexp(st.dt_max, -12);
    run_system(step, w);
    const auto& tl = w.resources.get<BinTimeline>(res::bin_timeline.name);
    if (headroom > 0 && raw == Raw::Chain) {
        EXPECT_NE(tl.quantum, BinTimeline::for_range(st.dt_min, st.dt_max).quantum) << "not rebased";
    }
    const std::vector<int> expected = relaxed_bins(w);
    const auto bin = w.fluid.store.get(comp::bin);
    Outcome out;
    for (std::size_t i = 0; i < n; ++i) {
        EXPECT_EQ(int(bin[i]), expected[i]) << "particle " << i << " at x = " << x[i].x();
        if (int(bin[i]) != expected[i]) break;
        out.rings = std::max(out.rings, (expected[i] - expected[fast]) / 2);
    }
    out.visited = w.counter_value(counter::limiter_rows.name);
    return out;
}

}  // namespace

TEST(BinnedStepSystem, EveryRowDueReachesTheLimitersFixedPointAlongChains) {
    for (const bool by_cells : {true, false}) {
        SCOPED_TRACE(by_cells ? "by cells" : "pushed from every row");
        for (const double headroom : {0.0, BinnedStepSystem::kHeadroom}) {
            // The chain is long: 12 or 13 bins from the fast particle's to the top, 2 a ring.
            EXPECT_EQ(check_fixed_point(Raw::Chain, headroom, by_cells).rings, 6);
        }
    }
}

namespace {

/// Both limiter paths on the same raw field (the fixed ladder): found by cell, and pushed from
/// every row that can bound a neighbour; prints the rows each visited.
std::pair<Outcome, Outcome> both_paths(Raw raw) {
    const Outcome cells = check_fixed_point(raw, 0, true);
    const Outcome pushed = check_fixed_point(raw, 0, false);
    std::printf("rows visited: %llu by cell, %llu pushed from every row\n",
                static_cast<unsigned long long>(cells.visited), static_cast<unsigned long long>(pushed.visited));
    return {cells, pushed};
}

}  // namespace

// Along a plane where the raw bins drop by 4 (the flow's calm bulk beside its fast rows), the
// same fixed point either way; found by cell, the limiter reads the lists of the rows within a
// cell of the plane (measured: 200 of 6,000, one layer of cells) instead of those of the 3,000 fast rows,
// each of which can bound a neighbour.
TEST(BinnedStepSystem, EveryRowDueVisitsOnlyTheRowsNearABinEdgeByCell) {
    const auto [cells, pushed] = both_paths(Raw::Edge);
    EXPECT_EQ(cells.rings, 2);
    EXPECT_EQ(pushed.rings, 2);
    EXPECT_GE(pushed.visited, 3000u);
    EXPECT_LT(cells.visited, 600u);  // up to three layers of cells (200 rows a layer)
}

// Stripes 3 cm wide alternately needing dt_max / 16 and dt_max along x (39 edges): every slow row
// lies by an edge, so the rows the limiter pulls at, found by cell, are more than one 2,048-row
// task (the thread sanitizer's stage sees the pull's compare-and-swap lowering run concurrently),
// and both paths still reach the serial relaxation's fixed point.
TEST(BinnedStepSystem, EveryRowDueAcrossManyEdgesPullsInSeveralTasks) {
    const auto [cells, pushed] = both_paths(Raw::Stripes);
    // A 3 cm stripe is 1.5 spacings wide: every slow row neighbours a fast one, so each is pulled
    // down to the fast bin + 2 (one ring) and none rises further.
    EXPECT_EQ(cells.rings, 1);
    EXPECT_EQ(pushed.rings, 1);
    EXPECT_GT(cells.visited, 2048u);  // measured 2,983: two tasks
}

// BinnedBodySystem (systems/active/binned_body_system.hpp) against a scan of every row: a 4 x 16
// x 4 cm box moving at +0.5 m/s in x through a 0.4 m pool of 5,760 rows that drift towards it on
// random base states (v_last = -0.4 m/s in x give or take 0.05, |a| <= 1 m/s^2, so |v| <= 0.5 m/s
// over the 40 ms: the box and the rows close at 0.9 m/s), 16 due steps
// 2.5 ms apart with 5 % of the rows due and random bins. At each, the active set must equal,
// row for row, the due rows plus every row whose position at the step's time (drift.hpp, the
// bits the drift writes) lies within h + speed dt_i of the box (near_moving_body), brute force
// over all rows. The declared drift bound (DriftBound: 0.5 m/s) is what lets the system reuse
// its candidate list between steps; rows drift into the reach during its life (counted), and a
// list kept on the box's own motion only (without the rows' drift) misses some at step 11.
TEST(BinnedBodySystem, AddsExactlyTheRowsWithinReachOfAMovingBody) {
    World w;
    initialise_world(w, test::pool_with_pushed_box());
    test::jitter(w, 3, 0.3f);
    const SteppingParams& st = w.scene.simulation.stepping;
    BinnedSelectSystem select(st.dt_min, st.dt_max);
    BinnedBodySystem body(st);
    DriftSystem().register_components(w);
    select.register_components(w);
    body.register_components(w);
    const std::size_t n = w.fluid.size();
    ASSERT_EQ(w.moving_bodies.size(), 1u);
    const Aabb start = w.moving_bodies[0].bounds;
    auto& store = w.fluid.store;
    const auto x0 = store.get(comp::position_last);
    const auto v0 = store.get(comp::velocity_last);
    const auto a = store.get(comp::acceleration);
    const auto t_last = store.get(comp::t_last);
    std::mt19937 rng(17);
    std::uniform_real_distribution<Real> u(-1, 1);
    for (std::size_t i = 0; i < n; ++i) {
        Vec3 vi(u(rng), u(rng), u(rng)), ai(u(rng), u(rng), u(rng));
        v0[i] = Vec3(-0.4f, 0, 0) + Real(0.05) * vi.normalized() * std::abs(u(rng));  // against the box
        a[i] = Real(1) * ai.normalized() * std::abs(u(rng));
        t_last[i] = 0;
    }
    const double h = w.physics.h;
    DriftBound& bound = w.resources.get<DriftBound>(res::drift_bound.name);
    bound.membership = store.membership();
    bound.reset_at = 0;
    bound.quantum = 0;
    bound.shortest_raw = (st.lambda_v + 2 * st.lambda_f * st.lambda_f) * h / 0.5;  // speed(): 0.5 m/s
    ASSERT_NEAR(bound.speed(st.lambda_v, st.lambda_f, h), 0.5, 1e-9);
    auto& tl = w.resources.get<BinTimeline>(res::bin_timeline.name);
    tl = BinTimeline::for_range(st.dt_min, st.dt_max);
    ASSERT_GE(tl.max_bin, 8);
    const std::uint64_t stride = BinTimeline::length(tl.max_bin - 1);  // 2.5 ms at dt_max 5 ms
    tl.now = 0;
    tl.next = stride;
    auto bin = store.get(comp::bin);
    auto ti_end = store.get(comp::ti_end);
    auto dt = store.get(comp::dt);
    auto active = store.get(comp::active);
    std::vector<std::uint8_t> near_before(n, 0);
    std::size_t added = 0, entered = 0;
    for (int k = 0; k < 16; ++k) {
        for (std::size_t i = 0; i < n; ++i) {
            const bool due = (rng() % 20) == 0;
            bin[i] = std::uint8_t(rng() % std::uint32_t(tl.max_bin + 1));
            dt[i] = tl.seconds(BinTimeline::length(bin[i]));
            ti_end[i] = due ? tl.next : tl.next + 2 * stride;
            active[i] = 0;
        }
        w.resources.get<DueBuckets>(res::due_buckets.name).layout = ~std::uint64_t(0);  // refiled from ti_end
        w.active_set.clear();
        w.clock.t_ticks = ticks_of(tl, tl.next);
        w.clock.t = to_seconds(w.clock.t_ticks);
        const Vec3d shift(0.5 * w.clock.t, 0, 0);
        w.moving_bodies[0].bounds = Aabb{start.min + shift, start.max + shift};
        const std::vector<std::uint64_t> end_before(ti_end.begin(), ti_end.end());
        run_system(select, w);
        run_system(body, w);
        std::vector<Index> expected;
        std::size_t step_added = 0;
        for (std::size_t i = 0; i < n; ++i) {
            const Vec3 xi = position_at(w.clock.t_ticks, t_last[i], x0[i], v0[i], a[i]);
            const bool near = near_moving_body(w.moving_bodies, xi, dt[i], Real(h));
            const bool due = end_before[i] == tl.now;
            if (due || near) expected.push_back(Index(i));
            step_added += near && !due;
            entered += near && !due && !near_before[i];
            near_before[i] = near;
        }
        ASSERT_EQ(w.active_set, expected) << "step " << k;
        EXPECT_EQ(w.counter_value(counter::active.name), expected.size());
        added += step_added;
        tl.next += stride;
    }
    std::printf("%zu rows; over 16 steps %zu added for the body (%zu entering its reach since the step before), "
                "candidate list made %zu times\n",
                n, added, entered, body.lists_made());
    EXPECT_GT(added, 1000u);
    EXPECT_GT(entered, 50u);
    // Reused: the list is made when the box and the rows have together moved h (20 mm here, at
    // 0.5 + 0.5 m/s: every 8 steps), not at every step.
    EXPECT_LT(body.lists_made(), 8u);
    EXPECT_GT(body.lists_made(), 1u);
}

namespace {

struct PartOutcome {
    std::size_t due = 0, limited = 0, woken = 0, cut = 0;
    bool by_cells = false;
};

// A step with a share `due` of the rows due, mid-run (now = 5 x 2^6 quanta, so bins 0-6 may end
// here and only bins 0-5 may grow), on 6,000 rows 2 cm apart jittered by 0.2 r, with bins that
// vary smoothly along x as a flow's do (so that a cell's bound on its block's bins is tight, and
// a row found by cell one bin off would be missed): the sleeping rows' bins within one of the
// field, each ending at the first multiple of its step after now; the due rows' old bins random
// in [0, 6] (their steps end now), their raw steps from 4 bins below the field to 3 above. Selection (BinnedSelectSystem, from ti_end), the binned lists
// (the due rows' only) and BinnedStepSystem as a run chains them, against a serial brute force
// of binned_step_system.hpp's rules: raw bins with the growth rule; then, to the fixed point,
// bin_i <= bin_j + 2 for every due i and j in i's list, and a sleeping j in the list of a due
// i lowered to bin_i + 2, its end cut to the first multiple of its new step after now (never
// later than its old end). Exact integer equality of every bin and end, of each due row's dt,
// of the woken counter, the next due time and res::stepped. `kept_grid`: the grid declared
// drifted, so the wake-up's rows come from the bounds on all bins rather than by cell.
PartOutcome check_partly_due(double due_share, bool kept_grid, std::uint32_t seed) {
    Scene s = test::tank_scene(Vec3d(1.2, 0.2, 0.2), Vec3d(1.3, 0.3, 0.3));
    s.simulation.stepping.mode = SteppingMode::Binned;
    World w;
    initialise_world(w, s);
    test::jitter(w, seed, 0.2f);
    const SteppingParams& st = w.scene.simulation.stepping;
    BinnedSelectSystem select(st.dt_min, st.dt_max);
    BinnedStepSystem step(st.dt_min, st.dt_max);
    select.register_components(w);
    step.register_components(w);
    const std::size_t n = w.fluid.size();
    auto& tl = w.resources.get<BinTimeline>(res::bin_timeline.name);
    EXPECT_GE(tl.max_bin, 12);
    const std::uint64_t now = 5 * BinTimeline::length(6);
    tl.now = 0;
    tl.next = now;
    auto& store = w.fluid.store;
    auto bin = store.get(comp::bin);
    auto ti_end = store.get(comp::ti_end);
    auto dt = store.get(comp::dt);
    auto dt_raw = store.get(comp::dt_raw);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0, 1);
    const auto x = store.get(comp::position);
    std::vector<char> due(n, 0);
    for (std::size_t i = 0; i < n; ++i) {
        // A smooth field of bins, 2 at x = 0 to 12 at x = 1.2 m, as a flow's steps vary in space.
        const int field = 2 + int(std::lround(10 * x[i].x() / 1.2));
        due[i] = u(rng) < due_share;
        const int b = due[i] ? int(rng() % 7) : std::clamp(field + int(rng() % 3) - 1, 0, tl.max_bin);
        bin[i] = std::uint8_t(b);
        ti_end[i] = due[i] ? now : BinTimeline::next_aligned(now, b);
        dt[i] = tl.seconds(BinTimeline::length(b));
        // Raw steps from 4 bins below the field to 3 above, anywhere within their bin.
        dt_raw[i] = tl.seconds(BinTimeline::length(std::max(0, field + 3 - int(rng() % 8)))) * (1 + 0.99 * u(rng));
    }
    w.resources.get<DueBuckets>(res::due_buckets.name).layout = ~std::uint64_t(0);  // refiled from ti_end
    w.clock.t_ticks = ticks_of(tl, now);
    w.clock.t = to_seconds(w.clock.t_ticks);
    run_system(select, w);
    EXPECT_EQ(tl.now, now);
    PartOutcome out;
    out.due = w.active_set.size();
    run_system(FluidGridSystem(), w);
    run_system(FluidNeighbourSystem(true, false), w);
    if (kept_grid) w.fluid_grid.set_drift(Real(1e-6));
    out.by_cells = !kept_grid && double(out.due) >= BinnedStepSystem::kWakeByCellsShare * double(n);
    const std::vector<std::uint8_t> old_bin(bin.begin(), bin.end());
    const std::vector<std::uint64_t> old_end(ti_end.begin(), ti_end.end());
    // The brute force, serially over the same lists.
    const NeighbourLists& lists = w.fluid_neighbours;
    std::vector<int> expect(old_bin.begin(), old_bin.end());
    for (Index i : w.active_set) {
        int b = tl.bin_for(dt_raw[i]);
        if (b > old_bin[i]) b = BinTimeline::aligned(now, old_bin[i] + 1) ? old_bin[i] + 1 : old_bin[i];
        expect[i] = b;
    }
    const std::vector<int> unlimited = expect;
    for (bool changed = true; changed;) {
        changed = false;
        for (Index i : w.active_set)
            for (Index j : lists.of(i)) {
                if (expect[i] > expect[j] + 2) expect[i] = expect[j] + 2, changed = true;
                if (!due[j] && expect[j] > expect[i] + 2) expect[j] = expect[i] + 2, changed = true;
            }
    }
    run_system(step, w);
    std::uint64_t earliest = ~std::uint64_t(0);
    std::vector<Index> stepped;
    for (std::size_t i = 0; i < n; ++i) {
        EXPECT_EQ(int(bin[i]), expect[i]) << (due[i] ? "due" : "sleeping") << " row " << i;
        if (int(bin[i]) != expect[i]) break;
        if (due[i]) {
            EXPECT_EQ(ti_end[i], now + BinTimeline::length(expect[i])) << i;
            EXPECT_EQ(dt[i], tl.seconds(BinTimeline::length(expect[i]))) << i;
            out.limited += expect[i] < unlimited[i];
            stepped.push_back(Index(i));
        } else if (expect[i] < old_bin[i]) {
            const std::uint64_t end = std::min(old_end[i], BinTimeline::next_aligned(now, expect[i]));
            EXPECT_EQ(ti_end[i], end) << "woken row " << i;
            EXPECT_EQ(dt[i], tl.seconds(BinTimeline::length(expect[i]))) << i;
            ++out.woken;
            out.cut += end < old_end[i];
            stepped.push_back(Index(i));
        } else {
            EXPECT_EQ(ti_end[i], old_end[i]) << "sleeping row " << i;
        }
        earliest = std::min(earliest, ti_end[i]);
    }
    EXPECT_EQ(w.counter_value(counter::woken.name), out.cut);
    EXPECT_EQ(tl.next, earliest);
    EXPECT_EQ(w.stepped, stepped);
    return out;
}

}  // namespace

// BinnedStepSystem on steps with part of the rows due (binned_step_system.hpp, steps 1-4) against
// the brute force above, at 55 % (the wake-up's rows found by cell, and again from the bounds on
// all bins), 10 % and 1 % due: several of the system's 2,048-row tasks at 55 % (so the limiter's
// and the wake-up's concurrent lowering runs under the thread sanitizer's stage), and a case
// where the limiter, the wake-up and the cut of a sleeping row's end all act (asserted, so that
// the oracle checks more than raw bins). 0 % due: nothing changes and the next step ends at the
// earliest end (the last check).
TEST(BinnedStepSystem, PartlyDueStepsMatchTheLimiterAndWakeUpByBruteForce) {
    struct Case {
        double share;
        bool kept_grid;
    };
    for (const Case c : {Case{0.55, false}, Case{0.55, true}, Case{0.1, false}, Case{0.01, false}}) {
        SCOPED_TRACE(testing::Message() << c.share * 100 << " % due" << (c.kept_grid ? ", kept grid" : ""));
        const PartOutcome o = check_partly_due(c.share, c.kept_grid, 11);
        std::printf("%4.0f %% due%s: %zu due rows, %zu limited, %zu sleeping rows woken (%zu ends cut)%s\n",
                    100 * c.share, c.kept_grid ? " (kept grid)" : "", o.due, o.limited, o.woken, o.cut,
                    o.by_cells ? ", wake-up by cell" : "");
        EXPECT_NEAR(double(o.due), c.share * 6000, 0.25 * c.share * 6000);
        EXPECT_GT(o.limited, 0u);
        EXPECT_GT(o.woken, 0u);
        EXPECT_GT(o.cut, 0u);
        EXPECT_EQ(o.by_cells, !c.kept_grid && c.share > 0.5);
    }
    const PartOutcome none = check_partly_due(0.0, false, 12);
    EXPECT_EQ(none.due, 0u);
    EXPECT_EQ(none.woken, 0u);
}
