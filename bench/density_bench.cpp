// BM_DensitySystem: summation density + Tait EOS (systems/density).
#include <benchmark/benchmark.h>

#include "bench_util.hpp"
#include "systems/density/density_system.hpp"
#include "systems/neighbours/boundary_neighbours_system.hpp"
#include "systems/neighbours/fluid_grid_system.hpp"
#include "systems/neighbours/fluid_neighbours_system.hpp"

using namespace sph;

static void BM_DensitySystem(benchmark::State& state) {
    auto w = bench::lattice_world(std::size_t(state.range(0)));
    DensitySystem density(false);
    density.register_components(*w);
    run_system(FluidGridSystem(), *w);
    run_system(FluidNeighbourSystem(), *w);
    for (auto _ : state) {
        run_system(density, *w);
        benchmark::ClobberMemory();
    }
    const double n = double(w->fluid.size());
    state.SetItemsProcessed(state.iterations() * std::int64_t(n));
    state.counters["particles"] = n;
    state.counters["neighbours_per_particle"] = double(w->fluid_neighbours.total()) / n;
}
BENCHMARK(BM_DensitySystem)->Arg(10'000)->Arg(100'000)->Arg(1'000'000)->Unit(benchmark::kMillisecond)->UseRealTime();
