// BM_DensitySystem: summation density + Tait EOS (systems/density).
#include <benchmark/benchmark.h>

#include "bench_util.hpp"
#include "engine/data/components.hpp"
#include "systems/density/density_system.hpp"
#include "systems/neighbours/boundary_neighbours_system.hpp"
#include "systems/neighbours/fluid_grid_system.hpp"
#include "systems/neighbours/fluid_neighbours_system.hpp"

using namespace sph;

namespace {
/// Times one density pass per iteration; items and `particles` count every fluid row.
double time_density(benchmark::State& state, DensitySystem& density, World& w) {
    for (auto _ : state) {
        run_system(density, w);
        benchmark::ClobberMemory();
    }
    const double n = double(w.fluid.size());
    state.SetItemsProcessed(state.iterations() * std::int64_t(n));
    state.counters["particles"] = n;
    return n;
}
}  // namespace

static void BM_DensitySystem(benchmark::State& state) {
    auto w = bench::lattice_world(std::size_t(state.range(0)));
    DensitySystem density(false);
    density.register_components(*w);
    run_system(FluidGridSystem(), *w);
    run_system(FluidNeighbourSystem(), *w);
    const double n = time_density(state, density, *w);
    state.counters["neighbours_per_particle"] = double(w->fluid_neighbours.total()) / n;
}
BENCHMARK(BM_DensitySystem)->Arg(10'000)->Arg(100'000)->Arg(1'000'000)->Unit(benchmark::kMillisecond)->UseRealTime();

// The continuity density (fluid.density: continuity): drho/dt (He eq. 5 + delta-SPH) and the
// advance of every row (`global`, range(1) = 100) or of an active share of range(1) % of the
// rows, every (100 / share)-th row (`individual`/`binned`: only those rows are touched). Side by
// side with BM_DensitySystem, which sums every row.
static void BM_DensitySystemContinuity(benchmark::State& state) {
    auto w = bench::lattice_world(std::size_t(state.range(0)));
    const int share = int(state.range(1));
    const bool individual = share < 100;
    DensitySystem density(false, individual, true);
    density.register_components(*w);
    if (individual) w->fluid.store.add(comp::t_last);  // stamped by the force system in a run
    w->fluid.store.resize(w->fluid.size());
    w->physics.continuity = true;
    w->physics.density_diffusion = 0.1f;
    run_system(FluidGridSystem(), *w);
    run_system(FluidNeighbourSystem(), *w);
    for (std::size_t i = 0; i < w->fluid.size(); ++i) w->active_set.push_back(Index(i));
    run_system(density, *w);  // every row starts from its summation
    w->active_set.clear();
    for (std::size_t i = 0; i < w->fluid.size(); i += std::size_t(100 / share)) w->active_set.push_back(Index(i));
    w->clock.t_ticks = to_ticks(1e-4);
    const double n = time_density(state, density, *w);
    state.counters["active_rows"] = individual ? double(w->active_set.size()) : n;
}
BENCHMARK(BM_DensitySystemContinuity)
    ->Args({10'000, 100})
    ->Args({100'000, 100})
    ->Args({100'000, 50})
    ->Args({100'000, 10})
    ->Args({100'000, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
