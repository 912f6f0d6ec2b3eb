// He et al., Alg. 2 line 4 (find neighbours). Uniform grid with cell size = support radius h,
// candidates from the 27 surrounding cells, exact test |x_i - x_j| < h.
#include "systems/neighbours/boundary_neighbours_system.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"
#include "systems/integrate/drift.hpp"
#include "systems/neighbours/fluid_neighbours_system.hpp"

namespace sph {

Access BoundaryNeighbourSystem::access() const {
    return Access()
        .read(boundary(comp::position), res::boundary_grid)
        .read_if(!m_from_base, fluid(comp::position))
        .read_if(m_from_base, fluid(comp::position_last), fluid(comp::velocity_last), fluid(comp::acceleration),
                 fluid(comp::t_last))
        .write(res::boundary_neighbours)
        .read_if(m_individual, res::active_set)
        .write_if(m_individual && m_keep_others, counter::boundary_contributions);
}
void BoundaryNeighbourSystem::run(Context& ctx) {
    std::span<const Vec3> x;
    if (m_from_base) {
        // He Alg. 2 lines 20-21 for the active rows (drift.hpp), what the drift places there.
        const auto x0 = ctx.read(fluid(comp::position_last));
        const auto v0 = ctx.read(fluid(comp::velocity_last));
        const auto a = ctx.read(fluid(comp::acceleration));
        const auto t_last = ctx.read(fluid(comp::t_last));
        const Tick now = ctx.clock().t_ticks;
        const auto& set = ctx.read(res::active_set);
        m_query.resize(x0.size());
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, set.size(), 4096), [&](const auto& r) {
            for (std::size_t k = r.begin(); k < r.end(); ++k) {
                const Index i = set[k];
                m_query[i] = position_from_base(now, t_last[i], x0[i], v0[i], a[i]);
            }
        });
        x = m_query;
    } else {
        x = ctx.read(fluid(comp::position));
    }
    build_neighbour_lists(ctx.read(res::boundary_grid), ctx.read(boundary(comp::position)), x,
                          ctx.physics().h, false,
                          active_query_subset(ctx, m_individual, m_keep_others), ctx.write(res::boundary_neighbours), ctx.physics().simd);
    if (m_individual && m_keep_others) {  // He's scheme: the work counter of the rows built
        const NeighbourLists& lists = ctx.read(res::boundary_neighbours);
        std::uint64_t entries = 0;
        for (Index i : ctx.read(res::active_set)) entries += lists.size_of(i);
        ctx.write(counter::boundary_contributions) = entries;
    }
}

}  // namespace sph
