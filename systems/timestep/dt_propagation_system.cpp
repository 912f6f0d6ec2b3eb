// He et al. Alg. 2 line 16: Delta t_i = min_j Delta t_j^raw (j over the neighbours of i and i
// itself).
#include "systems/timestep/dt_propagation_system.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <atomic>

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"

namespace sph {

Access DtPropagationSystem::access() const {
    return Access()
        .read(res::active_set, res::halo_set, res::fluid_neighbours, fluid(comp::dt_raw))
        .write(fluid(comp::dt), counter::propagation_updates);
}

void DtPropagationSystem::register_components(World& w) {
    w.fluid.store.add(comp::dt);
    w.fluid.store.add(comp::dt_raw);
}

void DtPropagationSystem::run(Context& ctx) {
    const auto dt_raw = ctx.read(fluid(comp::dt_raw));
    auto dt = ctx.write(fluid(comp::dt));
    const auto& active = ctx.read(res::active_set);
    const auto& halo = ctx.read(res::halo_set);
    const NeighbourLists& lists = ctx.read(res::fluid_neighbours);
    const std::size_t na = active.size(), n = na + halo.size();
    // Gather over each particle's own list (line 16 as written).
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 512), [&](const auto& r) {
        for (std::size_t k = r.begin(); k < r.end(); ++k) {
            const Index i = k < na ? active[k] : halo[k - na];
            double m = dt_raw[i];
            for (Index j : lists.of(i)) m = std::min(m, dt_raw[j]);
            dt[i] = m;
        }
    });
    // Scatter from the active particles' fresh lists: a halo particle's own list is from its
    // last evaluation and may not contain the active particle that now reaches it.
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, na, 256), [&](const auto& r) {
        for (std::size_t k = r.begin(); k < r.end(); ++k) {
            const double mine = dt_raw[active[k]];
            for (Index j : lists.of(active[k])) {
                std::atomic_ref<double> target(dt[j]);
                double cur = target.load(std::memory_order_relaxed);
                while (mine < cur && !target.compare_exchange_weak(cur, mine, std::memory_order_relaxed)) {
                }
            }
        }
    });
    ctx.write(counter::propagation_updates) = n;
}


}  // namespace sph
