// Boundary and per-step bookkeeping systems at 10^4, 10^5 and 10^6 fluid particles:
//   BM_BoundaryNeighbours/<N>/<active per mille>  fluid->boundary lists (systems/neighbours),
//                                                  all particles or a scattered active set
//   BM_WallPressure/<N>/<active per mille>         the walls' extrapolated pressure (Adami et al. 2012):
//                                                  every row (fixed-point scatter) or the walls a
//                                                  scattered active set reaches (grid gather)
//   BM_BoundaryCollision/<N>                       the wall safety net (systems/boundary)
//   BM_BoundaryMotion/<N>                          kinematic container motion + boundary grid
//   BM_StepStats/<N>, BM_GlobalDt/<N>,             density error, v/a max, the global step,
//   BM_SymplecticEuler/<N>, BM_Probes/<N>          integration, the probes of a scene
// The fixture is a cube of N fluid particles (jittered lattice, r = 0.01 m) filling a container
// whose six walls are sampled (6 N^(2/3) boundary particles); for BM_BoundaryMotion the
// container oscillates (sinusoidal motion). One step runs before the timed loop so every list
// and column is filled.
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <cstdio>
#include <random>

#include "engine/data/components.hpp"
#include "engine/run/probes.hpp"
#include "systems/boundary/boundary_collision_system.hpp"
#include "systems/boundary/boundary_motion_system.hpp"
#include "systems/boundary/wall_pressure_system.hpp"
#include "systems/integrate/symplectic_euler_system.hpp"
#include "systems/methods/recipes.hpp"
#include "systems/metrics/step_stats_system.hpp"
#include "systems/neighbours/boundary_neighbours_system.hpp"
#include "systems/neighbours/fluid_grid_system.hpp"
#include "systems/neighbours/fluid_neighbours_system.hpp"
#include "systems/timestep/global_dt_system.hpp"

using namespace sph;

namespace {

std::unique_ptr<Simulation> tank(std::size_t n, bool moving) {
    const int side = static_cast<int>(std::lround(std::cbrt(double(n))));
    const double r = 0.01, edge = side * 2 * r;
    Scene s;
    s.name = "bench_tank";
    s.fluid.particle_radius = r;
    s.simulation.frame_rate = 0;
    s.fluid_blocks.push_back(FluidBlock{Aabb{Vec3d::Zero(), Vec3d::Constant(edge)}, Vec3d::Zero(), false});
    BoundaryDesc b;
    b.shape = BoundaryShape::Container;
    b.box = Aabb{Vec3d::Zero(), Vec3d::Constant(edge)};
    if (moving) b.motion = sinusoidal_motion(Vec3d::UnitX(), 0.01, 1.0);
    s.boundaries.push_back(b);
    s.domain = Aabb{Vec3d::Constant(-0.2), Vec3d::Constant(edge + 0.2)};
    auto sim = make_simulation(s);
    std::mt19937 rng(3);
    std::uniform_real_distribution<Real> u(-0.2f, 0.2f);
    for (auto& x : sim->world().fluid.store.get(comp::position)) x += Vec3(u(rng), u(rng), u(rng)) * Real(r);
    sim->step();
    return sim;
}

void counters(benchmark::State& state, const World& w, double processed) {
    state.SetItemsProcessed(state.iterations() * std::int64_t(processed));
    state.counters["particles"] = double(w.fluid.size());
    state.counters["boundary_particles"] = double(w.boundary.size());
    state.counters["neighbours_per_particle"] = double(w.fluid_neighbours.total()) / double(w.fluid.size());
}

void sizes(benchmark::internal::Benchmark* b) {
    for (int n : {10'000, 100'000, 1'000'000}) b->Arg(n);
    b->Unit(benchmark::kMillisecond)->UseRealTime();
}

/// Times one system made by `make(scene)` on the tank.
template <class Make>
void bench_system(benchmark::State& state, Make make, bool moving = false) {
    auto sim = tank(std::size_t(state.range(0)), moving);
    World& w = sim->world();
    auto system = make(w.scene);
    for (auto _ : state) {
        run_system(system, w);
        benchmark::ClobberMemory();
    }
    counters(state, w, double(w.fluid.size()));
}

}  // namespace

static void BM_BoundaryNeighbours(benchmark::State& state) {
    auto sim = tank(std::size_t(state.range(0)), false);
    World& w = sim->world();
    const double share = double(state.range(1)) / 1000.0;
    const bool individual = state.range(1) < 1000;
    // Scattered active set (a hash of the index: the worst case for locality).
    w.active_set.clear();
    for (std::size_t i = 0; i < w.fluid.size(); ++i)
        if (double((i * 2654435761u) % 1000u) < 1000.0 * share) w.active_set.push_back(Index(i));
    BoundaryNeighbourSystem system(individual);
    for (auto _ : state) {
        run_system(system, w);
        benchmark::ClobberMemory();
    }
    counters(state, w, individual ? double(w.active_set.size()) : double(w.fluid.size()));
    state.counters["active_fraction"] = individual ? double(w.active_set.size()) / double(w.fluid.size()) : 1.0;
    state.counters["boundary_neighbours_per_particle"] = double(w.boundary_neighbours.total()) / double(w.fluid.size());
}
BENCHMARK(BM_BoundaryNeighbours)->ArgsProduct({{10'000, 100'000, 1'000'000}, {1000, 500, 100, 10}})
    ->Unit(benchmark::kMillisecond)->UseRealTime();

static void BM_WallPressure(benchmark::State& state) {
    auto sim = tank(std::size_t(state.range(0)), false);
    World& w = sim->world();
    const bool individual = state.range(1) < 1000;
    w.active_set.clear();
    for (std::size_t i = 0; i < w.fluid.size(); ++i)
        if ((i * 2654435761u) % 1000u < std::size_t(state.range(1))) w.active_set.push_back(Index(i));
    WallPressureSystem system(individual);
    system.register_components(w);
    for (auto _ : state) {
        run_system(system, w);
        benchmark::ClobberMemory();
    }
    counters(state, w, individual ? double(w.active_set.size()) : double(w.fluid.size()));
    state.counters["active_fraction"] = individual ? double(w.active_set.size()) / double(w.fluid.size()) : 1.0;
}
BENCHMARK(BM_WallPressure)->ArgsProduct({{10'000, 100'000, 1'000'000}, {1000, 500, 100, 10}})
    ->Unit(benchmark::kMillisecond)->UseRealTime();

static void BM_BoundaryCollision(benchmark::State& state) { bench_system(state, [](const Scene& s) { return BoundaryCollisionSystem(s.boundaries, false); }); }
BENCHMARK(BM_BoundaryCollision)->Apply(sizes);

/// BM_BoundaryMotion/<particles>/<moved>: moved 0 runs at one time, so no body particle changes
/// cell and the grid is kept (most steps); moved 1 alternates the clock between t = 0 and a
/// quarter period (the body 1 cm apart), so every call rebuilds the grid.
static void BM_BoundaryMotion(benchmark::State& state) {
    auto sim = tank(std::size_t(state.range(0)), true);
    World& w = sim->world();
    BoundaryMotionSystem system(w.scene.boundaries);
    const bool moved = state.range(1) != 0;
    const std::uint64_t builds = w.boundary_grid.builds();
    std::int64_t k = 0;
    for (auto _ : state) {
        if (moved) w.clock.t = (k++ % 2) * 0.25;
        run_system(system, w);
        benchmark::ClobberMemory();
    }
    counters(state, w, double(w.boundary.size()));
    state.counters["rebuilt"] = double(w.boundary_grid.builds() - builds) / double(state.iterations());
}
BENCHMARK(BM_BoundaryMotion)->ArgsProduct({{10'000, 100'000, 1'000'000}, {0, 1}})->Unit(benchmark::kMillisecond)->UseRealTime();

static void BM_StepStats(benchmark::State& state) { bench_system(state, [](const Scene&) { return StepStatsSystem(false); }); }
BENCHMARK(BM_StepStats)->Apply(sizes);

static void BM_GlobalDt(benchmark::State& state) { bench_system(state, [](const Scene& s) { return GlobalDtSystem(s.simulation.stepping); }); }
BENCHMARK(BM_GlobalDt)->Apply(sizes);

static void BM_SymplecticEuler(benchmark::State& state) { bench_system(state, [](const Scene&) { return SymplecticEulerSystem(); }); }
BENCHMARK(BM_SymplecticEuler)->Apply(sizes);

// A scene's probes, sampled once per iteration: a front (neighbours), a height line, an
// interpolated and a wall pressure, the whole-fluid totals (the probes' own grid build included).
static void BM_Probes(benchmark::State& state) {
    auto sim = tank(std::size_t(state.range(0)), false);
    const World& w = sim->world();
    const double edge = w.boundary.size() ? double(w.scene.boundaries[0].box.max.x()) : 1.0;
    std::vector<ProbeDesc> d(5);
    d[0].type = ProbeType::Front;
    d[1].type = ProbeType::Height;
    d[1].from = {edge / 2, 0, edge / 2};
    d[1].to = {edge / 2, edge, edge / 2};
    d[2].type = ProbeType::Pressure;
    d[2].point = Vec3d::Constant(edge / 2);
    d[3].type = ProbeType::Pressure;
    d[3].source = PressureSource::Boundary;
    d[3].point = {edge / 2, 0, edge / 2};
    d[3].radius = 0.04;
    d[4].type = ProbeType::Fluid;
    // Named through a buffer: "p" + std::to_string(k) draws a false -Wrestrict from GCC 12.
    for (std::size_t k = 0; k < d.size(); ++k) {
        char name[24];
        std::snprintf(name, sizeof name, "p%zu", k);
        d[k].name = name;
    }
    ProbeSet probes(d);
    for (auto _ : state) probes.sample_all(w);
    counters(state, w, double(w.fluid.size()));
}
BENCHMARK(BM_Probes)->Apply(sizes);
