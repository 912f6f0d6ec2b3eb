// BM_StepMode_PeerDamBreak/<mode>/threads:T: one whole step of scenes/peer_dam_break.json in
// every stepping mode the scene loader knows (registered at start-up from
// stepping_mode_names(), so a mode added later is benchmarked with no new code), after 0.05 s
// of flow, at 1 and 2 threads. items/s = fluid-particle-steps per second; an `individual`
// step evaluates only the active particles (counter active_fraction).
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include "engine/core/errors.hpp"
#include "systems/methods/recipes.hpp"

using namespace sph;

namespace {

void step_mode(benchmark::State& state, const std::string& mode) {
    tbb::global_control threads(tbb::global_control::max_allowed_parallelism, std::size_t(state.range(0)));
    const Scene scene = load_scene(SPH_SOURCE_DIR "/scenes/peer_dam_break.json",
                                   {{"/simulation/stepping/mode", mode}, {"/simulation/frame_rate", 0}});
    auto sim = make_simulation(scene);
    sim->run_until(0.05);
    double active = 0;
    for (auto _ : state) {
        sim->step();
        active += double(sim->world().counter_value("active"));
    }
    const double n = double(sim->world().fluid.size());
    state.SetItemsProcessed(state.iterations() * std::int64_t(n));
    state.counters["fluid_particles"] = n;
    state.counters["active_fraction"] = state.iterations() ? active / (n * double(state.iterations())) : 0.0;
    state.counters["neighbours_per_particle"] = double(sim->world().fluid_neighbours.total()) / n;
    state.counters["bytes_per_particle"] = double(sim->particle_bytes()) / n;
}

const bool registered = [] {
    for (const std::string& mode : stepping_mode_names()) {
        try {
            load_scene(SPH_SOURCE_DIR "/scenes/peer_dam_break.json", {{"/simulation/stepping/mode", mode}});
        } catch (const SceneError&) {  // a mode of another method
            continue;
        }
        benchmark::RegisterBenchmark(("BM_StepMode_PeerDamBreak/" + mode).c_str(),
                                     [mode](benchmark::State& s) { step_mode(s, mode); })
            ->Arg(1)
            ->Arg(2)
            ->ArgName("threads")
            ->Unit(benchmark::kMillisecond)
            ->UseRealTime()
            ->MinTime(2.0);
    }
    return true;
}();

}  // namespace
