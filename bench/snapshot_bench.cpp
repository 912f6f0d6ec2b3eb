// Benchmarks on a disordered snapshot: the scene after 0.5 s of flow (a dam break has hit the
// far wall and splashed, so particles are no longer on the start lattice, which understates the
// neighbour search 2-2.5x). The snapshot is computed once per scene and stepping mode and saved
// as a checkpoint fixture in the build tree (bench/fixtures/<scene>_<mode>.ckpt); later runs
// load it. Every benchmark takes `simd` (1: the vectorised pair loops, 0: the scalar reference
// loops) and `threads`, so one run gives the vectorised/scalar and 2/1-thread ratios side by side.
//
// BM_Snapshot_Step/<scene>/<mode>: one whole step of the flow graph from the snapshot (each
//   iteration restores the snapshot first, outside the timing, so every iteration times the same
//   step). items/s = fluid-particle-steps per second. The first step after a restore costs more
//   than a step of a run (dam_break_obstacles `global`, one thread: 14.4 ms against a run's
//   median 10.7 ms, 2026-12-05): compare modes with runs' per-step medians (stats.csv).
// BM_Snapshot_<system>/<scene>: one system of the `global` recipe on the snapshot (fluid_grid,
//   fluid_neighbours, boundary_neighbours, density, forces), the systems before it run once.
//   .../binned_every_row_due: the pair system as the `binned` recipe has it, on the same
//   snapshot with every particle due (what a `binned` step that evaluates every row costs).
// BM_Snapshot_dfsph_<pass>/<scene>: DFSPH's pair passes on its own snapshot (factor: density,
//   factor, stored gradients and viscosity; pressure and source: one pass of the density solver),
//   the recipe's systems before the density solve run once.
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <numeric>

#include "engine/data/components.hpp"
#include "engine/graph/system.hpp"
#include "engine/run/checkpoint.hpp"
#include "systems/dfsph/dfsph_systems.hpp"
#include "systems/methods/recipes.hpp"

using namespace sph;

namespace {

constexpr double kSnapshotTime = 0.5;

Scene scene_for(const std::string& scene, const std::string& mode) {
    std::vector<std::pair<std::string, nlohmann::json>> o{{"/simulation/frame_rate", 0}};
    if (mode == "adaptive") o.push_back({"/simulation/method", "pcisph"});
    if (mode == "dfsph") o.push_back({"/simulation/method", "dfsph"});
    o.push_back({"/simulation/stepping/mode", mode == "dfsph" ? std::string("adaptive") : mode});
    return load_scene(SPH_SOURCE_DIR "/scenes/" + scene + ".json", o);
}

/// A simulation of `scene` in `mode` at t = 0.5 s: from the fixture file if it exists and this
/// engine can restore it, else run there (at the machine's thread count) and saved. A fixture
/// an older engine wrote (another checkpoint format) is computed again, not a crash.
std::unique_ptr<Simulation> snapshot(const std::string& scene, const std::string& mode, bool simd) {
    Scene s = scene_for(scene, mode);
    s.simulation.simd = simd;
    auto sim = make_simulation(s);
    const std::filesystem::path dir = SPH_BENCH_FIXTURE_DIR;
    const std::filesystem::path file = dir / (scene + "_" + mode + ".ckpt");
    if (std::filesystem::exists(file)) {
        try {
            restore_checkpoint(*sim, read_checkpoint(file));
            return sim;
        } catch (const CheckpointError& e) {
            std::fprintf(stderr, "%s: not this engine's fixture (%s); computing it again\n", file.c_str(), e.what());
            sim = make_simulation(s);
        }
    }
    std::filesystem::create_directories(dir);
    sim->run_until(kSnapshotTime);
    write_checkpoint(file, *sim, nlohmann::json{{"fixture", "bench/snapshot_bench.cpp"}});
    return sim;
}

void set_counters(benchmark::State& state, const Simulation& sim, double items_per_iteration) {
    const double n = double(sim.world().fluid.size());
    state.SetItemsProcessed(std::int64_t(double(state.iterations()) * items_per_iteration));
    state.counters["fluid_particles"] = n;
    state.counters["neighbours_per_particle"] = double(sim.world().fluid_neighbours.total()) / n;
    state.counters["bytes_per_particle"] = double(sim.particle_bytes()) / n;
}

void snapshot_step(benchmark::State& state, const std::string& scene, const std::string& mode) {
    const bool simd = state.range(0) != 0;
    tbb::global_control threads(tbb::global_control::max_allowed_parallelism, std::size_t(state.range(1)));
    auto sim = snapshot(scene, mode, simd);
    const Checkpoint ck = read_checkpoint(std::filesystem::path(SPH_BENCH_FIXTURE_DIR) / (scene + "_" + mode + ".ckpt"));
    double updated = 0;
    for (auto _ : state) {
        state.PauseTiming();
        restore_checkpoint(*sim, ck);
        state.ResumeTiming();
        sim->step();
        updated += double(sim->world().counter_value("force_evaluations"));
    }
    set_counters(state, *sim, double(sim->world().fluid.size()));
    state.counters["evaluated_fraction"] =
        state.iterations() ? updated / (double(sim->world().fluid.size()) * double(state.iterations())) : 0.0;
}

/// One system of the `global` recipe, by name, on the snapshot; with `mode` "binned", the same
/// system as the `binned` recipe has it, on the same snapshot with every particle due (the
/// base state is the current one, so the drifts leave every row as it is).
void snapshot_system(benchmark::State& state, const std::string& scene, const std::string& system,
                     const std::string& mode = "global") {
    const bool simd = state.range(0) != 0;
    tbb::global_control threads(tbb::global_control::max_allowed_parallelism, std::size_t(state.range(1)));
    auto sim = snapshot(scene, "global", simd);
    World& w = sim->world();
    Recipe recipe = make_recipe(scene_for(scene, mode));
    System* target = nullptr;
    for (auto& s : recipe.step) s->register_components(w);
    if (mode == "binned") {
        ComponentStore& f = w.fluid.store;
        std::copy_n(f.get(comp::position).data(), w.fluid.size(), f.get(comp::position_last).data());
        std::copy_n(f.get(comp::velocity).data(), w.fluid.size(), f.get(comp::velocity_last).data());
        std::copy_n(f.get(comp::density).data(), w.fluid.size(), f.get(comp::density_last).data());
        std::ranges::fill(f.get(comp::t_last), w.clock.t_ticks);
        std::ranges::fill(f.get(comp::active), std::uint8_t(1));
        w.active_set.resize(w.fluid.size());
        std::iota(w.active_set.begin(), w.active_set.end(), Index(0));
    }
    for (auto& s : recipe.step) {
        if (s->name() == system) {
            target = s.get();
            break;
        }
        if (mode == "binned" && (s->name() == "drift" || s->name() == "binned_select")) continue;  // set above
        run_system(*s, w);  // what the system reads: grid, lists, density as this step has them
    }
    if (!target) {
        state.SkipWithError(("no system " + system + " in the " + mode + " recipe").c_str());
        return;
    }
    for (auto _ : state) run_system(*target, w);
    set_counters(state, *sim, double(w.fluid.size()));
}

/// One DFSPH pass on the DFSPH snapshot: the recipe's systems up to the density solve run once,
/// then `factor` (dfsph_factor) or one `pressure` / `source` pass of the density solver is timed.
void snapshot_dfsph_pass(benchmark::State& state, const std::string& scene, const std::string& pass) {
    const bool simd = state.range(0) != 0;
    tbb::global_control threads(tbb::global_control::max_allowed_parallelism, std::size_t(state.range(1)));
    auto sim = snapshot(scene, "dfsph", simd);
    World& w = sim->world();
    const Scene sc = scene_for(scene, "dfsph");
    Recipe recipe = make_recipe(sc);
    for (auto& s : recipe.step) s->register_components(w);
    System* factor = nullptr;
    for (auto& s : recipe.step) {
        if (s->name() == "dfsph_density") break;
        if (s->name() == "dfsph_factor") factor = s.get();
        run_system(*s, w);
    }
    const bool moving = has_moving_boundaries(sc);
    DfsphPressureSystem pressure(DfsphSolver::Density, !sc.boundaries.empty());
    DfsphSourceSystem source(DfsphSolver::Density, !sc.boundaries.empty(), moving, sc.dfsph.relaxation);
    run_system(source, w);  // a stiffness to apply
    System* target = pass == "factor" ? factor : pass == "pressure" ? static_cast<System*>(&pressure) : &source;
    for (auto _ : state) run_system(*target, w);
    set_counters(state, *sim, double(w.fluid.size()));
}

const bool registered = [] {
    auto args = [](benchmark::internal::Benchmark* b) {
        b->ArgNames({"simd", "threads"})
            ->ArgsProduct({{1, 0}, {1, 2}})
            ->Unit(benchmark::kMillisecond)
            ->UseRealTime()
            ->MinTime(1.0);
    };
    for (const std::string scene : {"peer_dam_break", "dam_break_obstacles"}) {
        for (const std::string mode : {"global", "individual", "binned", "adaptive", "dfsph"})
            args(benchmark::RegisterBenchmark(("BM_Snapshot_Step/" + scene + "/" + mode).c_str(),
                                              [scene, mode](benchmark::State& s) { snapshot_step(s, scene, mode); }));
        for (const std::string system : {"fluid_grid", "fluid_neighbours", "boundary_neighbours", "density", "forces"})
            args(benchmark::RegisterBenchmark(("BM_Snapshot_" + system + "/" + scene).c_str(),
                                              [scene, system](benchmark::State& s) { snapshot_system(s, scene, system); }));
        // The same pair systems as `binned` runs them in a step with every particle due.
        for (const std::string system : {"fluid_neighbours", "boundary_neighbours", "density", "forces"})
            args(benchmark::RegisterBenchmark(("BM_Snapshot_" + system + "/" + scene + "/binned_every_row_due").c_str(),
                                              [scene, system](benchmark::State& s) { snapshot_system(s, scene, system, "binned"); }));
        for (const std::string pass : {"factor", "pressure", "source"})
            args(benchmark::RegisterBenchmark(("BM_Snapshot_dfsph_" + pass + "/" + scene).c_str(),
                                              [scene, pass](benchmark::State& s) { snapshot_dfsph_pass(s, scene, pass); }));
    }
    return true;
}();

}  // namespace
