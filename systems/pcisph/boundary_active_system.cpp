// Ihmsen et al. 2010 sec. 3.4: only boundary particles with a fluid neighbour are active.
#include "systems/pcisph/boundary_active_system.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"
#include "systems/pcisph/pcisph_components.hpp"
#include "systems/pcisph/pcisph_kernels.hpp"
#include "systems/pcisph/pcisph_state.hpp"

namespace sph {

Access BoundaryActiveSystem::access() const {
    return Access().read(res::boundary_neighbours).write(res::boundary_active, counter::boundary_active);
}

void BoundaryActiveSystem::register_components(World& w) {
    w.resources.add<BoundaryActive>(res::boundary_active.name, Lifetime::Scratch);
}

void BoundaryActiveSystem::run(Context& ctx) {
    BoundaryActive& act = ctx.write(res::boundary_active);
    const std::size_t nb = ctx.size(SetId::Boundary), nf = ctx.size(SetId::Fluid);
    m_count.assign(nb, 0);
    const NeighbourLists& lists = ctx.read(res::boundary_neighbours);
    for (std::size_t i = 0; i < nf; ++i)
        for (Index b : lists.of(Index(i))) ++m_count[b];
    act.set.clear();
    act.start.assign(1, 0);
    for (std::size_t b = 0; b < nb; ++b)
        if (m_count[b] > 0) {
            act.set.push_back(Index(b));
            act.start.push_back(act.start.back() + m_count[b]);
        }
    // m_count becomes each active particle's write cursor (its row start).
    for (std::size_t k = 0; k < act.set.size(); ++k) m_count[act.set[k]] = act.start[k];
    act.fluid.resize(act.start.back());
    for (std::size_t i = 0; i < nf; ++i)  // ascending i: rows come out sorted
        for (Index b : lists.of(Index(i))) act.fluid[m_count[b]++] = Index(i);
    ctx.write(counter::boundary_active) = act.set.size();
}

}  // namespace sph
