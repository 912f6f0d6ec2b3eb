// He et al. Alg. 2 line 16: Delta t_i = min_j Delta t_j^raw (j over the neighbours of i and i
// itself), and line 17: Delta t_sim = min_i Delta t_i.
#include "systems/timestep/dt_propagation_system.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <atomic>
#include <limits>

#include "engine/components.hpp"
#include "engine/world.hpp"

namespace sph {

Access DtPropagationSystem::access() const {
    return {{res::active_set, res::halo_set, res::fluid_neighbours, res::fluid(comp::dt_raw.name)},
            {res::fluid(comp::dt.name)}};
}

void DtPropagationSystem::register_components(World& w) {
    w.fluid.store.add(comp::dt);
    w.fluid.store.add(comp::dt_raw);
}

void DtPropagationSystem::run(World& w) {
    const auto dt_raw = w.fluid.store.get(comp::dt_raw);
    auto dt = w.fluid.store.get(comp::dt);
    const auto& active = w.active_set;
    const auto& halo = w.halo_set;
    const std::size_t na = active.size(), n = na + halo.size();
    // Gather over each particle's own list (line 16 as written).
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 512), [&](const auto& r) {
        for (std::size_t k = r.begin(); k < r.end(); ++k) {
            const Index i = k < na ? active[k] : halo[k - na];
            double m = dt_raw[i];
            for (Index j : w.fluid_neighbours.of(i)) m = std::min(m, dt_raw[j]);
            dt[i] = m;
        }
    });
    // Scatter from the active particles' fresh lists: a halo particle's own list is from its
    // last evaluation and may not contain the active particle that now reaches it.
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, na, 256), [&](const auto& r) {
        for (std::size_t k = r.begin(); k < r.end(); ++k) {
            const double mine = dt_raw[active[k]];
            for (Index j : w.fluid_neighbours.of(active[k])) {
                std::atomic_ref<double> target(dt[j]);
                double cur = target.load(std::memory_order_relaxed);
                while (mine < cur && !target.compare_exchange_weak(cur, mine, std::memory_order_relaxed)) {
                }
            }
        }
    });
    w.step.propagation_updates = n;
}

Access IndividualGlobalDtSystem::access() const { return {{res::fluid(comp::dt.name)}, {res::dt}}; }

void IndividualGlobalDtSystem::run(World& w) {
    const auto dt = w.fluid.store.get(comp::dt);
    const double m = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, dt.size(), 8192), w.scene.simulation.stepping.dt_max,
        [&](const auto& r, double best) {
            for (std::size_t i = r.begin(); i < r.end(); ++i) best = std::min(best, dt[i]);
            return best;
        },
        [](double a, double b) { return std::min(a, b); });
    StepState& s = w.step;
    s.dt_stable = m;
    s.set_dt_clipped(m);
}

}  // namespace sph
