// BM_NeighbourSearch: fluid grid build + fluid->fluid lists (systems/neighbours).
// BM_FluidGridBuild: the grid build alone, on rows in the z-order a run's spatial sort keeps.
#include <benchmark/benchmark.h>

#include "bench_util.hpp"
#include "systems/neighbours/boundary_neighbours_system.hpp"
#include "systems/neighbours/fluid_grid_system.hpp"
#include "systems/neighbours/fluid_neighbours_system.hpp"

using namespace sph;

static void BM_NeighbourSearch(benchmark::State& state) {
    auto w = bench::lattice_world(std::size_t(state.range(0)));
    FluidGridSystem grid;
    FluidNeighbourSystem lists;
    for (auto _ : state) {
        run_system(grid, *w);
        run_system(lists, *w);
        benchmark::ClobberMemory();
    }
    const double n = double(w->fluid.size());
    state.SetItemsProcessed(state.iterations() * std::int64_t(n));
    state.counters["particles"] = n;
    state.counters["neighbours_per_particle"] = double(w->fluid_neighbours.total()) / n;
}
BENCHMARK(BM_NeighbourSearch)->Arg(10'000)->Arg(100'000)->Arg(1'000'000)->Unit(benchmark::kMillisecond)->UseRealTime();

static void BM_FluidGridBuild(benchmark::State& state) {
    auto w = bench::lattice_world(std::size_t(state.range(0)));
    FluidGridSystem grid;
    run_system(grid, *w);
    w->fluid.store.permute(zorder_permutation(w->fluid_grid, w->fluid.store.get(comp::position)));
    for (auto _ : state) {
        run_system(grid, *w);
        benchmark::ClobberMemory();
    }
    state.counters["particles"] = double(w->fluid.size());
    state.counters["cells"] = double(w->fluid_grid.cell_count());
}
BENCHMARK(BM_FluidGridBuild)->Arg(100'000)->Arg(1'000'000)->Unit(benchmark::kMillisecond)->UseRealTime();
