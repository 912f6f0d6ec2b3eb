// He et al., Alg. 2 line 4 (find neighbours). Uniform grid with cell size = support radius h,
// candidates from the 27 surrounding cells, exact test |x_i - x_j| < h.
#include "systems/neighbours/fluid_neighbours_system.hpp"

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"

namespace sph {

QuerySubset active_query_subset(const Context& ctx, bool individual, bool keep_others) {
    return individual ? QuerySubset{ctx.read(res::active_set), false, keep_others} : QuerySubset{};
}

Access FluidNeighbourSystem::access() const {
    return Access()
        .read(fluid(comp::position), res::fluid_grid)
        .write(res::fluid_neighbours, counter::neighbour_searches)
        .read_if(m_individual, res::active_set);
}
// He Alg. 2 lines 3-4: fresh lists for the active particles only; the others keep theirs.
void FluidNeighbourSystem::run(Context& ctx) {
    const QuerySubset subset = active_query_subset(ctx, m_individual, m_keep_others);
    const auto x = ctx.read(fluid(comp::position));
    build_neighbour_lists(ctx.read(res::fluid_grid), x, x, ctx.physics().h, true, subset, ctx.write(res::fluid_neighbours),
                          ctx.physics().simd);
    ctx.write(counter::neighbour_searches) = subset.all ? ctx.size(SetId::Fluid) : subset.indices.size();
}

}  // namespace sph
