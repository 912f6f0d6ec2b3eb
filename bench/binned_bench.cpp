// BM_Binned_<system>/<particles>/<active per mille>: the systems of binned stepping
// (systems/timestep/binned_step_system.hpp) on a jittered lattice where a given, scattered share
// of the particles is due. The pipeline runs once in recipe order outside the timed loop; each
// iteration restores the state the measured system changes (the bins, ends, timeline and
// buckets) with the timer paused, then runs the system once.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <string>
#include <vector>

#include "bench_util.hpp"
#include "systems/active/binned_body_system.hpp"
#include "systems/active/binned_select_system.hpp"
#include "systems/density/density_system.hpp"
#include "systems/forces/forces_system.hpp"
#include "systems/integrate/async_integration_system.hpp"
#include "systems/integrate/drift_system.hpp"
#include "systems/metrics/step_stats_system.hpp"
#include "systems/neighbours/fluid_grid_system.hpp"
#include "systems/neighbours/fluid_neighbours_system.hpp"
#include "systems/timestep/binned_state.hpp"
#include "systems/timestep/binned_step_system.hpp"

using namespace sph;

namespace {

/// A fresh timeline at now = 0 with a scattered `share` of the rows due at quantum 4 (bin 2) and
/// the rest at 8 (bin 3), so that the limiter and the wake-up have neighbours on other bins.
void file_due_share(World& w, double share) {
    const SteppingParams& st = w.scene.simulation.stepping;
    auto& tl = w.resources.get<BinTimeline>(res::bin_timeline.name);
    tl = BinTimeline::for_range(st.dt_min, st.dt_max);
    tl.now = 0;
    tl.next = 4;
    auto bin = w.fluid.store.get(comp::bin);
    auto end = w.fluid.store.get(comp::ti_end);
    for (std::size_t i = 0; i < bin.size(); ++i) {
        const bool due = double((i * 2654435761u) % 1000u) < 1000.0 * share;
        bin[i] = due ? 2 : 3;
        end[i] = due ? 4 : 8;
    }
}

struct Pipeline {
    std::unique_ptr<World> w;
    std::vector<std::unique_ptr<System>> systems;
    std::vector<std::uint8_t> bin0;
    std::vector<std::uint64_t> end0;
    BinTimeline tl0;
    DueBuckets buckets0;

    Pipeline(std::size_t n, double share) : w(bench::lattice_world(n)) {
        const SteppingParams& st = w->scene.simulation.stepping;
        // The recipe's order (systems/methods/wcsph.cpp, no boundary).
        systems.push_back(std::make_unique<DriftSystem>());
        systems.push_back(std::make_unique<BinnedSelectSystem>(st.dt_min, st.dt_max));
        systems.push_back(std::make_unique<FluidGridSystem>());
        systems.push_back(std::make_unique<FluidNeighbourSystem>(true, false));
        systems.push_back(std::make_unique<DriftRowsSystem>());
        systems.push_back(std::make_unique<DensitySystem>(false, true));
        systems.push_back(std::make_unique<ForcesSystem>(false, true));
        systems.push_back(std::make_unique<StepStatsSystem>(true, StepStatsSystem::Rows::Active));
        systems.push_back(std::make_unique<BinnedStepSystem>(st.dt_min, st.dt_max));
        systems.push_back(std::make_unique<AsyncIntegrationSystem>(true));
        for (auto& s : systems) s->register_components(*w);
        for (auto& s : systems) run_system(*s, *w);  // t = 0: every particle due
        // Then a scattered share is due at quantum 4 and the rest at 8.
        file_due_share(*w, share);
        auto& tl = w->resources.get<BinTimeline>(res::bin_timeline.name);
        auto bin = w->fluid.store.get(comp::bin);
        auto end = w->fluid.store.get(comp::ti_end);
        w->clock.t_ticks = ticks_of(tl, 4);
        w->clock.t = to_seconds(w->clock.t_ticks);
        w->resources.get<DueBuckets>(res::due_buckets.name).layout = ~std::uint64_t(0);  // refile
        bin0.assign(bin.begin(), bin.end());
        end0.assign(end.begin(), end.end());
        tl0 = tl;
        for (auto& s : systems) run_system(*s, *w);  // the step at quantum 4, every system
        // The state before that step's binned_select, to restore before each measured run.
        std::copy(bin0.begin(), bin0.end(), bin.begin());
        std::copy(end0.begin(), end0.end(), end.begin());
        tl = tl0;
        auto& buckets = w->resources.get<DueBuckets>(res::due_buckets.name);
        buckets.layout = ~std::uint64_t(0);
        w->clock.t_ticks = ticks_of(tl, 4);
        run_system(get("binned_select"), *w);  // the active set and the refiled buckets
        buckets0 = buckets;
    }
    System& get(const std::string& name) {
        for (auto& s : systems)
            if (s->name() == name) return *s;
        throw std::runtime_error("no system " + name);
    }
    /// Back to the state after binned_select of the step at quantum 4.
    void restore(bool before_select) {
        auto bin = w->fluid.store.get(comp::bin);
        auto end = w->fluid.store.get(comp::ti_end);
        std::copy(bin0.begin(), bin0.end(), bin.begin());
        std::copy(end0.begin(), end0.end(), end.begin());
        auto& tl = w->resources.get<BinTimeline>(res::bin_timeline.name);
        tl = tl0;
        auto& buckets = w->resources.get<DueBuckets>(res::due_buckets.name);
        buckets = buckets0;
        if (before_select) {  // the bucket of quantum 4 back in place, the flags cleared
            tl.next = 4;
            tl.now = 0;
        } else {
            tl.now = 4;
        }
    }
};

void bench_named(benchmark::State& state, const std::string& name) {
    Pipeline p(std::size_t(state.range(0)), double(state.range(1)) / 1000.0);
    System& s = p.get(name);
    const bool select = name == "binned_select";
    const bool mutates = select || name == "binned_step";
    std::vector<Index> active = p.w->active_set;
    for (auto _ : state) {
        if (mutates) {
            state.PauseTiming();
            p.restore(select);
            if (select) {
                // Its buckets as before it ran: the due bucket is refiled from the ends.
                auto& b = p.w->resources.get<DueBuckets>(res::due_buckets.name);
                b.due[4] = active;
                p.w->active_set = active;
                for (Index i : active) p.w->fluid.store.get(comp::active)[i] = 1;
            }
            state.ResumeTiming();
        }
        run_system(s, *p.w);
        benchmark::ClobberMemory();
    }
    const double n = double(p.w->fluid.size());
    state.SetItemsProcessed(state.iterations() * std::int64_t(n));
    state.counters["particles"] = n;
    state.counters["active_fraction"] = double(active.size()) / n;
}

void args(benchmark::internal::Benchmark* b) {
    for (int n : {100'000, 1'000'000})
        for (int per_mille : {1000, 500, 100, 10}) b->Args({n, per_mille});
    b->Unit(benchmark::kMillisecond)->UseRealTime();
}

}  // namespace

/// BM_Binned_fluid_neighbours_drifted/<particles>/<due per mille>/<drift per mille of h>: the due
/// rows' search against a grid kept from an earlier step (UniformGrid::set_drift, what
/// FluidGridSystem does on binned's sparse steps), against BM_Binned_fluid_grid plus
/// BM_Binned_fluid_neighbours (a fresh grid and the 27-cell search) at the same share.
void BM_Binned_fluid_neighbours_drifted(benchmark::State& state) {
    Pipeline p(std::size_t(state.range(0)), double(state.range(1)) / 1000.0);
    System& s = p.get("fluid_neighbours");
    p.w->fluid_grid.set_drift(Real(double(state.range(2)) / 1000.0) * p.w->physics.h);
    for (auto _ : state) {
        run_system(s, *p.w);
        benchmark::ClobberMemory();
    }
    state.counters["active_fraction"] = double(p.w->active_set.size()) / double(p.w->fluid.size());
}
BENCHMARK(BM_Binned_fluid_neighbours_drifted)
    ->ArgsProduct({{100'000, 1'000'000}, {100, 30, 10}, {30, 125}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

/// BM_Binned_drift_around_due/<particles>/<due per mille>: DriftSystem's lazy placement on a step
/// that keeps the grid (declared drift 0.1 h): the due rows and the rows of the cells within
/// h + drift of each, against BM_Binned_drift (every row). `placed` is the share placed (every
/// row once the cells reach DriftSystem::kStreamShare of them).
void BM_Binned_drift_around_due(benchmark::State& state) {
    Pipeline p(std::size_t(state.range(0)), double(state.range(1)) / 1000.0);
    DriftSystem s(DriftSystem::Rows::AroundDue);
    p.w->fluid_grid.set_drift(Real(0.1) * p.w->physics.h);
    for (auto _ : state) {
        run_system(s, *p.w);
        benchmark::ClobberMemory();
    }
    const double n = double(p.w->fluid.size());
    state.counters["active_fraction"] = double(p.w->active_set.size()) / n;
    state.counters["placed"] = double(p.w->placed.size()) / n;
}
BENCHMARK(BM_Binned_drift_around_due)
    ->ArgsProduct({{100'000, 1'000'000}, {100, 10, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

/// BM_Binned_body/<particles>/<list made>: BinnedBodySystem on a due step with 1 % of the rows
/// due and a 0.08 x 0.08 m rod at rest through the middle of the lattice (a moving body, speed
/// 0.8 m/s as `stirring_pool`'s): with its candidate list kept (0: the rows within reach + h of
/// the rod are tested) or made anew from every row (1: what a step pays when the list's margin is
/// used up, or after a re-sort; also the order of the scan of every row binned_select made before
/// the system existed). `candidates` is the list's share of the rows.
void BM_Binned_body(benchmark::State& state) {
    const bool made = state.range(1) != 0;
    auto w = bench::lattice_world(std::size_t(state.range(0)));
    const std::size_t n = w->fluid.size();  // the nearest cube
    const Aabb cube = w->domain;
    const Vec3d mid = 0.5 * (cube.min + cube.max);
    Scene& s = w->scene;
    s.simulation.stepping.mode = SteppingMode::Binned;
    w->moving_bodies.push_back(MovingBody{0, 0, 0, Aabb{Vec3d(mid.x() - 0.04, cube.min.y(), mid.z() - 0.04),
                                                          Vec3d(mid.x() + 0.04, cube.max.y(), mid.z() + 0.04)}, 0.8});
    const SteppingParams& st = s.simulation.stepping;
    DriftSystem drift;
    BinnedSelectSystem select(st.dt_min, st.dt_max);
    BinnedBodySystem body(st);
    drift.register_components(*w);
    select.register_components(*w);
    body.register_components(*w);
    file_due_share(*w, 0.01);
    const auto& tl = w->resources.get<BinTimeline>(res::bin_timeline.name);
    auto bin = w->fluid.store.get(comp::bin);
    auto end = w->fluid.store.get(comp::ti_end);
    DriftBound& bound = w->resources.get<DriftBound>(res::drift_bound.name);
    bound.membership = made ? 0 : w->fluid.store.membership();  // 0: void, the list is made every time
    bound.shortest_raw = 1e-3;  // a slow fluid: the list stays valid
    bound.quantum = 0;
    w->clock.t_ticks = ticks_of(tl, 4);
    w->clock.t = to_seconds(w->clock.t_ticks);
    run_system(select, *w);
    const std::vector<Index> set = w->active_set;
    const std::vector<std::uint8_t> bin0(bin.begin(), bin.end());
    const std::vector<std::uint64_t> end0(end.begin(), end.end());
    run_system(body, *w);  // the first list
    auto active = w->fluid.store.get(comp::active);
    for (auto _ : state) {
        state.PauseTiming();
        std::copy(bin0.begin(), bin0.end(), bin.begin());
        std::copy(end0.begin(), end0.end(), end.begin());
        std::fill(active.begin(), active.end(), std::uint8_t(0));
        for (Index i : set) active[i] = 1;
        w->active_set = set;
        state.ResumeTiming();
        run_system(body, *w);
        benchmark::ClobberMemory();
    }
    state.counters["candidates"] = double(w->counter_value(counter::body_candidates.name)) / double(n);
    state.counters["added"] = double(w->active_set.size() - set.size()) / double(n);
    state.counters["lists_made"] = double(body.lists_made());
}
BENCHMARK(BM_Binned_body)->ArgsProduct({{100'000, 1'000'000}, {0, 1}})->Unit(benchmark::kMillisecond)->UseRealTime();

#define SPH_BINNED_BENCH(system)                                                          \
    static void BM_Binned_##system(benchmark::State& state) { bench_named(state, #system); } \
    BENCHMARK(BM_Binned_##system)->Apply(args)

SPH_BINNED_BENCH(drift);
SPH_BINNED_BENCH(binned_select);
SPH_BINNED_BENCH(fluid_grid);
SPH_BINNED_BENCH(fluid_neighbours);
SPH_BINNED_BENCH(drift_rows);
SPH_BINNED_BENCH(density);
SPH_BINNED_BENCH(forces);
SPH_BINNED_BENCH(step_stats);
SPH_BINNED_BENCH(binned_step);
SPH_BINNED_BENCH(async_integrate);
