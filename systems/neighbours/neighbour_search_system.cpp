// He et al., Alg. 2 line 4 (find neighbours). Uniform grid with cell size = support radius h,
// candidates from the 27 surrounding cells, exact test |x_i - x_j| < h.
#include "systems/neighbours/neighbour_search_system.hpp"

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"

namespace sph {

Access FluidGridSystem::access() const { return Access().read(fluid(comp::position)).write(res::fluid_grid); }
void FluidGridSystem::run(Context& ctx) { ctx.write(res::fluid_grid).build(ctx.read(fluid(comp::position))); }

namespace {
QuerySubset subset_of(const Context& ctx, bool individual) {
    return individual ? QuerySubset{ctx.read(res::active_set), false} : QuerySubset{};
}
}  // namespace

Access FluidNeighbourSystem::access() const {
    return Access()
        .read(fluid(comp::position), res::fluid_grid)
        .write(res::fluid_neighbours, counter::neighbour_searches)
        .read_if(m_individual, res::active_set);
}
// He Alg. 2 lines 3-4: fresh lists for the active particles only; the others keep theirs.
void FluidNeighbourSystem::run(Context& ctx) {
    const QuerySubset subset = subset_of(ctx, m_individual);
    build_neighbour_lists(ctx.read(res::fluid_grid), ctx.read(fluid(comp::position)), ctx.physics().h, true, subset,
                          ctx.write(res::fluid_neighbours));
    ctx.write(counter::neighbour_searches) = subset.all ? ctx.size(SetId::Fluid) : subset.indices.size();
}

Access BoundaryNeighbourSystem::access() const {
    return Access()
        .read(fluid(comp::position), res::boundary_grid)
        .write(res::boundary_neighbours)
        .read_if(m_individual, res::active_set);
}
void BoundaryNeighbourSystem::run(Context& ctx) {
    build_neighbour_lists(ctx.read(res::boundary_grid), ctx.read(fluid(comp::position)), ctx.physics().h, false,
                          subset_of(ctx, m_individual), ctx.write(res::boundary_neighbours));
}

}  // namespace sph
