// BM_Individual/<system>/<particles>/<active per mille>: each individual-stepping system
// (He et al. Alg. 2) on a jittered lattice with a given share of scattered active particles.
// The pipeline runs once in recipe order outside the timed loop; the loop repeats one system.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <functional>
#include <string>
#include <vector>

#include "bench_util.hpp"
#include "systems/active/select_active_system.hpp"
#include "systems/density/density_system.hpp"
#include "systems/forces/forces_system.hpp"
#include "systems/forces/gradient_correction_system.hpp"
#include "systems/integrate/async_integration_system.hpp"
#include "systems/neighbours/boundary_neighbours_system.hpp"
#include "systems/neighbours/fluid_grid_system.hpp"
#include "systems/neighbours/fluid_neighbours_system.hpp"
#include "systems/timestep/dt_propagation_system.hpp"
#include "systems/timestep/individual_dt_system.hpp"

using namespace sph;

namespace {

struct Pipeline {
    std::unique_ptr<World> w;
    std::vector<std::unique_ptr<System>> systems;
    std::vector<Tick> due_t_last;  ///< t_last of the due step (select_active's input)

    Pipeline(std::size_t n, double active_share) : w(bench::lattice_world(n)) {
        systems.push_back(std::make_unique<SelectActiveSystem>());
        systems.push_back(std::make_unique<FluidGridSystem>());
        systems.push_back(std::make_unique<FluidNeighbourSystem>(true));
        systems.push_back(std::make_unique<DensitySystem>(false, true));
        // The correction's own cost (fluid.pressure_gradient: corrected); `forces` below stays
        // the symmetric form, comparable with the global benchmarks.
        systems.push_back(std::make_unique<GradientCorrectionSystem>(false, true));
        systems.push_back(std::make_unique<ForcesSystem>(false, true));
        systems.push_back(std::make_unique<DtPropagationSystem>());
        systems.push_back(std::make_unique<IndividualGlobalDtSystem>(w->scene.simulation.stepping.activation,
                                                                      w->scene.simulation.stepping.dt_max));
        systems.push_back(std::make_unique<AsyncIntegrationSystem>());
        for (auto& s : systems) s->register_components(*w);
        // As in a simulation, the first step evaluates every particle (density, forces, base
        // state of He Alg. 2 lines 19-21); then a scattered share is due at the second step.
        run_system(FluidGridSystem(), *w);
        run_system(FluidNeighbourSystem(), *w);
        auto t_last = w->fluid.store.get(comp::t_last);
        auto dt = w->fluid.store.get(comp::dt);
        std::ranges::fill(t_last, Tick(0));
        std::ranges::fill(dt, 1e-4);
        w->clock.t_ticks = to_ticks(1e-4);  // t_last + dt_i <= t: all due
        w->clock.t = 1e-4;
        for (auto& s : systems) run_system(*s, *w);
        const Tick now = to_ticks(1e-3);
        for (std::size_t i = 0; i < t_last.size(); ++i) {
            const bool due = double((i * 2654435761u) % 1000u) < 1000.0 * active_share;
            t_last[i] = due ? 0 : now;
            dt[i] = 1e-4;
        }
        w->clock.t_ticks = now;
        w->clock.t = to_seconds(now);
        due_t_last.assign(t_last.begin(), t_last.end());
        // The deadline rule (select_active_system.hpp) looks one last stable step ahead: with
        // it at 1e-4 s the particles just evaluated (due at now + 1e-4 s) stay asleep.
        w->step_size.dt_stable = 1e-4;
        for (auto& s : systems) run_system(*s, *w);
    }
    System& get(const std::string& name) {
        for (auto& s : systems)
            if (s->name() == name) return *s;
        throw std::runtime_error("no system " + name);
    }
};

void bench_named(benchmark::State& state, const std::string& name) {
    Pipeline p(std::size_t(state.range(0)), double(state.range(1)) / 1000.0);
    System& s = p.get(name);
    // The pipeline's step stamped the active rows' t_last (forces, async_integrate): the selection
    // is timed on the due step's state, or it would select nothing (until 2026-12-06 it did).
    if (name == "select_active") std::ranges::copy(p.due_t_last, p.w->fluid.store.get(comp::t_last).begin());
    for (auto _ : state) {
        run_system(s, *p.w);
        benchmark::ClobberMemory();
    }
    const double n = double(p.w->fluid.size());
    state.SetItemsProcessed(state.iterations() * std::int64_t(n));
    state.counters["particles"] = n;
    state.counters["active_fraction"] = double(p.w->active_set.size()) / n;
}

void args(benchmark::internal::Benchmark* b) {
    for (int n : {10'000, 100'000, 1'000'000})
        for (int per_mille : {1000, 500, 100, 10}) b->Args({n, per_mille});
    b->Unit(benchmark::kMillisecond)->UseRealTime();
}

}  // namespace

#define SPH_INDIVIDUAL_BENCH(system)                                                          \
    static void BM_Individual_##system(benchmark::State& state) { bench_named(state, #system); } \
    BENCHMARK(BM_Individual_##system)->Apply(args)

SPH_INDIVIDUAL_BENCH(select_active);
SPH_INDIVIDUAL_BENCH(fluid_neighbours);
SPH_INDIVIDUAL_BENCH(density);
SPH_INDIVIDUAL_BENCH(gradient_correction);
SPH_INDIVIDUAL_BENCH(forces);
SPH_INDIVIDUAL_BENCH(dt_propagation);
SPH_INDIVIDUAL_BENCH(individual_dt);
SPH_INDIVIDUAL_BENCH(async_integrate);
