// He et al., Alg. 2 line 4 (find neighbours). Uniform grid with cell size = support radius h,
// candidates from the 27 surrounding cells, exact test |x_i - x_j| < h.
#include "systems/neighbours/neighbour_search_system.hpp"

#include "engine/components.hpp"
#include "engine/world.hpp"

namespace sph {

Access FluidGridSystem::access() const { return {{res::fluid(comp::position.name)}, {res::fluid_grid}}; }
void FluidGridSystem::run(World& w) { w.fluid_grid.build(w.fluid.store.get(comp::position)); }

namespace {
QuerySubset subset_of(const World& w, bool individual) {
    return individual ? QuerySubset{w.active_set, false} : QuerySubset{};
}
}  // namespace

Access FluidNeighbourSystem::access() const {
    Access a{{res::fluid(comp::position.name), res::fluid_grid}, {res::fluid_neighbours}};
    if (m_individual) a.reads.push_back(res::active_set);
    return a;
}
// He Alg. 2 lines 3-4: fresh lists for the active particles only; the others keep theirs.
void FluidNeighbourSystem::run(World& w) {
    const QuerySubset subset = subset_of(w, m_individual);
    build_neighbour_lists(w.fluid_grid, w.fluid.store.get(comp::position), w.physics.h, true, subset,
                          w.fluid_neighbours);
    w.step.neighbour_searches = subset.all ? w.fluid.size() : subset.indices.size();
}

Access BoundaryNeighbourSystem::access() const {
    Access a{{res::fluid(comp::position.name), res::boundary_grid}, {res::boundary_neighbours}};
    if (m_individual) a.reads.push_back(res::active_set);
    return a;
}
void BoundaryNeighbourSystem::run(World& w) {
    build_neighbour_lists(w.boundary_grid, w.fluid.store.get(comp::position), w.physics.h, false,
                          subset_of(w, m_individual), w.boundary_neighbours);
}

}  // namespace sph
