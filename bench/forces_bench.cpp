// BM_ForcesSystem/<particles>/<corrected>: pressure + viscosity + gravity (systems/forces), with
// the symmetric pressure gradient (0, He et al. eq. 4) or the corrected one (1, Bonet & Lok 1999).
// BM_GradientCorrection: the correction matrices L_i that the corrected form reads.
#include <benchmark/benchmark.h>

#include "bench_util.hpp"
#include "systems/density/density_system.hpp"
#include "systems/forces/forces_system.hpp"
#include "systems/forces/gradient_correction_system.hpp"
#include "systems/neighbours/boundary_neighbours_system.hpp"
#include "systems/neighbours/fluid_grid_system.hpp"
#include "systems/neighbours/fluid_neighbours_system.hpp"

using namespace sph;

static void BM_ForcesSystem(benchmark::State& state) {
    auto w = bench::lattice_world(std::size_t(state.range(0)));
    const bool corrected = state.range(1) != 0;
    DensitySystem density(false);
    GradientCorrectionSystem correction(false, false);
    ForcesSystem forces(false, false, false, corrected);
    density.register_components(*w);
    correction.register_components(*w);
    forces.register_components(*w);
    run_system(FluidGridSystem(), *w);
    run_system(FluidNeighbourSystem(), *w);
    run_system(density, *w);
    run_system(correction, *w);
    for (auto _ : state) {
        run_system(forces, *w);
        benchmark::ClobberMemory();
    }
    const double n = double(w->fluid.size());
    state.SetItemsProcessed(state.iterations() * std::int64_t(n));
    state.counters["particles"] = n;
    state.counters["neighbours_per_particle"] = double(w->fluid_neighbours.total()) / n;
}
BENCHMARK(BM_ForcesSystem)
    ->ArgsProduct({{10'000, 100'000, 1'000'000}, {0, 1}})
    ->ArgNames({"", "corrected"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

static void BM_GradientCorrection(benchmark::State& state) {
    auto w = bench::lattice_world(std::size_t(state.range(0)));
    DensitySystem density(false);
    GradientCorrectionSystem correction(false, false);
    density.register_components(*w);
    correction.register_components(*w);
    run_system(FluidGridSystem(), *w);
    run_system(FluidNeighbourSystem(), *w);
    run_system(density, *w);
    for (auto _ : state) {
        run_system(correction, *w);
        benchmark::ClobberMemory();
    }
    const double n = double(w->fluid.size());
    state.SetItemsProcessed(state.iterations() * std::int64_t(n));
    state.counters["particles"] = n;
}
BENCHMARK(BM_GradientCorrection)->Arg(10'000)->Arg(100'000)->Arg(1'000'000)->Unit(benchmark::kMillisecond)->UseRealTime();
