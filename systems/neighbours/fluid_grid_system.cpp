// He et al., Alg. 2 line 4 (find neighbours). Uniform grid with cell size = support radius h,
// candidates from the 27 surrounding cells, exact test |x_i - x_j| < h.
#include "systems/neighbours/fluid_grid_system.hpp"

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"

namespace sph {

Access FluidGridSystem::access() const { return Access().read(fluid(comp::position)).write(res::fluid_grid); }
void FluidGridSystem::run(Context& ctx) { ctx.write(res::fluid_grid).build(ctx.read(fluid(comp::position))); }

}  // namespace sph
