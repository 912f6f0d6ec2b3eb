// He et al., Alg. 2 line 4 (find neighbours). Uniform grid with cell size = support radius h,
// candidates from the 27 surrounding cells, exact test |x_i - x_j| < h.
#include "systems/neighbours/boundary_neighbours_system.hpp"

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"
#include "systems/neighbours/fluid_neighbours_system.hpp"

namespace sph {

Access BoundaryNeighbourSystem::access() const {
    return Access()
        .read(fluid(comp::position), boundary(comp::position), res::boundary_grid)
        .write(res::boundary_neighbours)
        .read_if(m_individual, res::active_set)
        .write_if(m_individual && m_keep_others, counter::boundary_contributions);
}
void BoundaryNeighbourSystem::run(Context& ctx) {
    build_neighbour_lists(ctx.read(res::boundary_grid), ctx.read(boundary(comp::position)), ctx.read(fluid(comp::position)),
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
