// Whole-step benchmarks on scenes/peer_dam_break.json (32,768 fluid particles): one
// iteration is one full step of the flow graph (neighbours, density, forces, dt, integration).
// items/s = fluid-particle-steps per second. Threads: the arg (1 or 2).
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include "engine/data/components.hpp"
#include "systems/methods/recipes.hpp"

using namespace sph;

static void BM_Step_PeerDamBreak(benchmark::State& state) {
    tbb::global_control threads(tbb::global_control::max_allowed_parallelism, std::size_t(state.range(0)));
    Scene scene = load_scene(SPH_SOURCE_DIR "/scenes/peer_dam_break.json");
    scene.simulation.frame_rate = 0;
    auto sim = make_simulation(scene);
    // Advance into the flow (0.05 s) so that the benchmark is not measuring a resting lattice.
    sim->run_until(0.05);
    for (auto _ : state) sim->step();
    const double n = double(sim->world().fluid.size());
    state.SetItemsProcessed(state.iterations() * std::int64_t(n));
    state.counters["fluid_particles"] = n;
    state.counters["boundary_particles"] = double(sim->world().boundary.size());
    state.counters["neighbours_per_particle"] = double(sim->world().fluid_neighbours.total()) / n;
    state.counters["bytes_per_particle"] = double(sim->particle_bytes()) / n;
}
BENCHMARK(BM_Step_PeerDamBreak)->Arg(1)->Arg(2)->ArgName("threads")->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(3.0);
