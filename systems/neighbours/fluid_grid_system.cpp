// He et al., Alg. 2 line 4 (find neighbours). Uniform grid with cell size = support radius h,
// candidates from the 27 surrounding cells, exact test |x_i - x_j| < h.
#include "systems/neighbours/fluid_grid_system.hpp"

#include <cmath>
#include <numeric>

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"
#include "systems/integrate/drift_system.hpp"
#include "systems/timestep/binned_state.hpp"

namespace sph {

Access FluidGridSystem::access() const {
    Access acc = Access()
                     .read(fluid(comp::position))
                     .write(res::fluid_grid)
                     .read_if(m_keep, res::drift_bound)
                     .write_if(m_keep, counter::grid_kept);
    if (m_place)
        acc.read(fluid(comp::position_last), fluid(comp::velocity_last), fluid(comp::acceleration), fluid(comp::t_last))
            .write(fluid(comp::position), res::placed)
            .rows(res::placed);
    return acc;
}

void FluidGridSystem::register_components(World& w) {
    if (m_keep) w.resources.add<DriftBound>(res::drift_bound.name, Lifetime::Scratch);
}

bool FluidGridSystem::kept(Context& ctx) {
    const UniformGrid& grid = ctx.read(res::fluid_grid);
    const std::size_t n = ctx.size(SetId::Fluid);
    const DriftBound& bound = ctx.read(res::drift_bound);
    // The collision net's jumps in the last step (0 when it moved no row): added up since the
    // build, before any return, so that the sum is whole whenever the grid is kept.
    m_net_shift += bound.net_shift;
    if (grid.particle_count() != n || ctx.layout(SetId::Fluid) != m_layout || !(m_net_shift < kMaxDrift * ctx.physics().h))
        return false;
    if (double(bound.next_due) >= kBuildShare * double(n)) return false;
    // The bound holds over the time since its reset: one reset after the build (a step that
    // evaluated every row while the grid was kept, e.g. rows a moving body made due) does not
    // cover the drift before it.
    if (bound.membership != ctx.membership(SetId::Fluid) || bound.reset_at > m_built_at) return false;
    const double h = ctx.physics().h;
    // The rounding of a drifted float position, a few units in the last place of the largest
    // coordinate in the grid, for each step since the build (a row evaluated at a step starts
    // its next drift from its rounded position).
    const double extent = grid.origin().cwiseAbs().maxCoeff() + double(grid.dims().maxCoeff()) * grid.cell_size();
    const double rounding = 8 * double(std::numeric_limits<Real>::epsilon()) * extent * double(++m_steps_kept + 1);
    const double drift =
        bound.speed(m_lambda_v, m_lambda_f, h) * to_seconds(ctx.clock().t_ticks - m_built_at) * 1.001 + rounding + m_net_shift;
    if (!(drift < kMaxDrift * h)) return false;
    ctx.write(res::fluid_grid).set_drift(Real(drift));
    return true;
}

void FluidGridSystem::run(Context& ctx) {
    if (m_keep) {
        const bool keep = kept(ctx);
        ctx.write(counter::grid_kept) = keep;
        if (keep) {
            if (m_place) ctx.write(res::placed).clear();  // DriftSystem places the rows read
            return;
        }
        m_built_at = ctx.clock().t_ticks;
        m_layout = ctx.layout(SetId::Fluid);
        m_steps_kept = 0;
        m_net_shift = 0;
    }
    if (m_place) {
        // Every row at the step's time, the positions the build reads (drift_system.hpp).
        auto x = ctx.write(fluid(comp::position));
        place_every_row(x, ctx.read(fluid(comp::position_last)), ctx.read(fluid(comp::velocity_last)),
                        ctx.read(fluid(comp::acceleration)), ctx.read(fluid(comp::t_last)), ctx.clock().t_ticks);
        auto& placed = ctx.write(res::placed);
        placed.resize(x.size());
        std::iota(placed.begin(), placed.end(), Index(0));
    }
    ctx.write(res::fluid_grid).build(ctx.read(fluid(comp::position)));
}

}  // namespace sph
