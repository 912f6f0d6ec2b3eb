// He et al. Alg. 2, remark after line 22: lines 9 and 16 are needed only for the inactive
// neighbours of active particles, collected here from the active particles' fresh lists.
#include "systems/active/halo_system.hpp"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <atomic>

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"

namespace sph {

Access HaloSystem::access() const {
    return Access()
        .read(res::active_set, res::fluid_neighbours, fluid(comp::active))
        .write(res::halo_set, counter::boundary_contributions)
        .read_if(m_with_boundary, res::boundary_neighbours);
}

void HaloSystem::register_components(World& w) { w.fluid.store.add(comp::active); }

void HaloSystem::run(Context& ctx) {
    const auto active = ctx.read(fluid(comp::active));
    const auto& set = ctx.read(res::active_set);
    const NeighbourLists& fluid_nb = ctx.read(res::fluid_neighbours);
    const NeighbourLists* boundary_nb = m_with_boundary ? &ctx.read(res::boundary_neighbours) : nullptr;
    auto& halo = ctx.write(res::halo_set);
    // A per-particle claim flag keeps each halo particle once; flags are cleared afterwards
    // by walking the halo itself, so the cost stays proportional to the active set.
    m_claim.resize(active.size());
    if (set.size() == active.size()) {  // everyone active: no halo (global-equivalent steps)
        halo.clear();
        std::uint64_t b = 0;
        if (m_with_boundary)
            for (auto c : boundary_nb->count) b += c;
        ctx.write(counter::boundary_contributions) = b;
        return;
    }
    tbb::enumerable_thread_specific<std::vector<Index>> local;
    tbb::enumerable_thread_specific<std::uint64_t> boundary_entries(0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, set.size(), 256), [&](const auto& r) {
        auto& out = local.local();
        auto& bcount = boundary_entries.local();
        for (std::size_t k = r.begin(); k < r.end(); ++k) {
            const Index i = set[k];
            for (Index j : fluid_nb.of(i)) {
                if (active[j]) continue;
                // A plain load first: most halo particles neighbour several active ones, and
                // the locked exchange (the cost of this system) is only paid on a first claim.
                std::atomic_ref<std::uint8_t> claim(m_claim[j]);
                if (claim.load(std::memory_order_relaxed) != 0) continue;
                if (claim.exchange(1, std::memory_order_relaxed) == 0) out.push_back(j);
            }
            if (m_with_boundary) bcount += boundary_nb->size_of(Index(i));
        }
    });
    halo.clear();
    for (auto& v : local) halo.insert(halo.end(), v.begin(), v.end());
    // No sort: the order varies with the thread schedule, but nothing depends on it (the
    // propagation writes each halo particle's own minimum, then takes atomic minima).
    for (Index j : halo) m_claim[j] = 0;
    std::uint64_t b = 0;
    for (auto c : boundary_entries) b += c;
    ctx.write(counter::boundary_contributions) = b;
}

}  // namespace sph
