// He et al., Alg. 2 line 4 (find neighbours). Uniform grid with cell size = support radius h,
// candidates from the 27 surrounding cells, exact test |x_i - x_j| < h.
#include "systems/neighbours/neighbour_search_system.hpp"

#include "engine/components.hpp"
#include "engine/world.hpp"

namespace sph {

Access FluidGridSystem::access() const { return {{res::fluid(comp::position.name)}, {res::fluid_grid}}; }
void FluidGridSystem::run(World& w) { w.fluid_grid.build(w.fluid.store.get(comp::position)); }

Access FluidNeighbourSystem::access() const {
    return {{res::fluid(comp::position.name), res::fluid_grid}, {res::fluid_neighbours}};
}
void FluidNeighbourSystem::run(World& w) {
    build_neighbour_lists(w.fluid_grid, w.fluid.store.get(comp::position), w.physics.h, true, QuerySubset{},
                          w.fluid_neighbours);
}

Access BoundaryNeighbourSystem::access() const {
    return {{res::fluid(comp::position.name), res::boundary_grid}, {res::boundary_neighbours}};
}
void BoundaryNeighbourSystem::run(World& w) {
    build_neighbour_lists(w.boundary_grid, w.fluid.store.get(comp::position), w.physics.h, false, QuerySubset{},
                          w.boundary_neighbours);
}

}  // namespace sph
