// PCISPH benchmarks on scenes/corner_breaking_dam.json (20,625 fluid particles): a whole step
// (three prediction-correction passes, Ihmsen 2010 Alg. 2) and the state ring's save (one
// column-by-column copy of every fluid and boundary column, paid every adaptive step).
// items/s = fluid-particle-steps (saves) per second. Threads: the arg (1 or 2).
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include "engine/run/state_ring.hpp"
#include "systems/methods/recipes.hpp"

using namespace sph;

static void BM_PcisphStep_CornerBreakingDam(benchmark::State& state) {
    tbb::global_control threads(tbb::global_control::max_allowed_parallelism, std::size_t(state.range(0)));
    Scene scene = load_scene(SPH_SOURCE_DIR "/scenes/corner_breaking_dam.json");
    scene.simulation.frame_rate = 0;
    auto sim = make_simulation(scene);
    sim->run_until(0.1);  // into the collapse, not a resting lattice
    for (auto _ : state) sim->step();
    const double n = double(sim->world().fluid.size());
    state.SetItemsProcessed(state.iterations() * std::int64_t(n));
    state.counters["fluid_particles"] = n;
    state.counters["active_boundary_per_fluid"] = double(sim->world().counter_value("boundary_active")) / n;
    state.counters["neighbours_per_particle"] = double(sim->world().fluid_neighbours.total()) / n;
}
BENCHMARK(BM_PcisphStep_CornerBreakingDam)->Arg(1)->Arg(2)->ArgName("threads")->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(3.0);

static void BM_StateRingSave_CornerBreakingDam(benchmark::State& state) {
    tbb::global_control threads(tbb::global_control::max_allowed_parallelism, std::size_t(state.range(0)));
    Scene scene = load_scene(SPH_SOURCE_DIR "/scenes/corner_breaking_dam.json");
    scene.simulation.frame_rate = 0;
    auto sim = make_simulation(scene);
    sim->step();
    StateRing ring(2);
    for (auto _ : state) ring.save(sim->world());
    state.SetItemsProcessed(state.iterations() * std::int64_t(sim->world().fluid.size()));
    state.counters["bytes_per_save"] = double(sim->world().fluid.store.bytes() + sim->world().boundary.store.bytes());
}
BENCHMARK(BM_StateRingSave_CornerBreakingDam)->Arg(1)->Arg(2)->ArgName("threads")->Unit(benchmark::kMillisecond)->UseRealTime();
