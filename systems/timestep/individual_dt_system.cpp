// He et al. Alg. 2 line 17: Delta t_sim = min_i Delta t_i (with `activation: deadline` also the
// earliest deadline of an inactive particle, never below the last stable step).
#include "systems/timestep/individual_dt_system.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <limits>

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"

namespace sph {

Access IndividualGlobalDtSystem::access() const {
    return Access().read(fluid(comp::dt), fluid(comp::t_last), fluid(comp::active)).write(res::dt);
}

void IndividualGlobalDtSystem::register_components(World& w) {
    w.fluid.store.add(comp::dt);
    w.fluid.store.add(comp::t_last);
    w.fluid.store.add(comp::active);
}

void IndividualGlobalDtSystem::run(Context& ctx) {
    const auto dt = ctx.read(fluid(comp::dt));
    const auto t_last = ctx.read(fluid(comp::t_last));
    const auto active = ctx.read(fluid(comp::active));
    StepSize& s = ctx.write(res::dt);
    const Tick now = ctx.clock().t_ticks;
    const bool deadline = m_activation == Activation::Deadline;
    struct Min {
        double dt;  // line 17: min_i Delta t_i
        Tick next;  // the earliest deadline of an inactive particle that is still ahead
    };
    const Min none{m_dt_max, std::numeric_limits<Tick>::max()};
    const Min m = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, dt.size(), 8192), none,
        [&](const auto& r, Min best) {
            for (std::size_t i = r.begin(); i < r.end(); ++i) {
                best.dt = std::min(best.dt, dt[i]);
                if (deadline && !active[i]) {
                    const Tick due = t_last[i] + to_ticks(dt[i]);
                    if (due > now) best.next = std::min(best.next, due);
                }
            }
            return best;
        },
        [](Min a, Min b) { return Min{std::min(a.dt, b.dt), std::min(a.next, b.next)}; });
    // The deadline rule: the selection left inactive only particles due at or after
    // now + Delta t_sim' (the last stable step), so a step that stops at the earliest such
    // deadline is never shorter than min(Delta t_sim, Delta t_sim'). A propagated Delta t_i
    // (line 16) can move a halo particle's deadline closer; the floor Delta t_sim' then keeps
    // the step from fragmenting, and that particle is evaluated at the next step.
    Tick cap = 0;  // none
    if (deadline && m.next != std::numeric_limits<Tick>::max())
        cap = std::max(m.next - now, std::max<Tick>(1, to_ticks(s.dt_stable)));
    s.dt_stable = m.dt;
    s.set_clipped(m.dt, cap, ctx.clock());
}

}  // namespace sph
