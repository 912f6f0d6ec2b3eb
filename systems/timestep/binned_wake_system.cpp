#include "systems/timestep/binned_wake_system.hpp"

#include <algorithm>

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"
#include "systems/density/density_kernels.hpp"
#include "systems/integrate/drift.hpp"
#include "systems/timestep/binned_state.hpp"

namespace sph {

Access BinnedWakeSystem::access() const {
    return Access()
        .rows(res::collided)
        .read(res::collided, res::bin_timeline, res::dt, fluid(comp::position), fluid(comp::velocity),
              fluid(comp::drho_dt))
        .write(fluid(comp::bin), fluid(comp::ti_end), fluid(comp::dt), fluid(comp::position_last),
               fluid(comp::velocity_last), fluid(comp::density_last), fluid(comp::t_last), fluid(comp::density),
               fluid(comp::pressure), res::due_buckets);
}

void BinnedWakeSystem::run(Context& ctx) {
    const auto& hit = ctx.read(res::collided);
    if (hit.empty()) return;
    const BinTimeline& tl = ctx.read(res::bin_timeline);
    auto bin = ctx.write(fluid(comp::bin));
    auto ti_end = ctx.write(fluid(comp::ti_end));
    auto dt = ctx.write(fluid(comp::dt));
    DueBuckets& buckets = ctx.write(res::due_buckets);
    const auto x = ctx.read(fluid(comp::position));
    const auto v = ctx.read(fluid(comp::velocity));
    const auto drho = ctx.read(fluid(comp::drho_dt));
    auto rho = ctx.write(fluid(comp::density));
    auto p = ctx.write(fluid(comp::pressure));
    const Real rest = ctx.physics().rest_density, b_eos = ctx.physics().tait_b;
    auto x0 = ctx.write(fluid(comp::position_last));
    auto v0 = ctx.write(fluid(comp::velocity_last));
    auto rho0 = ctx.write(fluid(comp::density_last));
    auto t_last = ctx.write(fluid(comp::t_last));
    const Tick t_end = ctx.clock().t_ticks + ctx.read(res::dt).dt_ticks;
    const int top = BinTimeline::largest_aligned_bin(tl.next, tl.max_bin);
    for (Index i : hit) {
        // The corrected state (the net wrote x and v at the step's end) becomes the base the
        // particle is drifted from (He Alg. 2 lines 19-21 with t_last at the end of this step),
        // so no later drift undoes it; its density at that time (line 9) too, and the row is
        // current then.
        rho[i] = drifted_density(rho0[i], drho[i], drift_interval(t_end, t_last[i]));
        p[i] = tait_pressure(rho[i], rest, b_eos);
        x0[i] = x[i];
        v0[i] = v[i];
        rho0[i] = rho[i];
        t_last[i] = t_end;
        if (ti_end[i] <= tl.next) continue;
        ti_end[i] = tl.next;
        bin[i] = std::uint8_t(std::min<int>(bin[i], top));
        dt[i] = tl.seconds(BinTimeline::length(bin[i]));
        buckets.bin_lo = std::min<int>(buckets.bin_lo, bin[i]);
        buckets.due[tl.next].push_back(i);
    }
}

}  // namespace sph
