// He et al. Alg. 2 line 2: select active (the paper: t_last + Delta t_i < t_sim; `paper` counts the tie
// as active, `deadline`, the default, evaluates before the deadline is passed; in exact ticks).
#include "systems/active/select_active_system.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"

namespace sph {

bool near_moving_body(const std::vector<MovingBody>& bodies, const Vec3& x, double dt, Real h) {
    // Our rule, not in He et al.: a particle is active while it lies within h + speed * Delta t_i
    // of a moving body's bounding box, i.e. wherever the body could come within the kernel's
    // reach before the particle's next evaluation. It therefore never skips a contact, and the
    // body's velocity enters its forces at every step of the contact.
    for (const MovingBody& b : bodies) {
        const Real reach = h + Real(b.speed * dt);
        const Vec3 lo = b.bounds.min.cast<Real>().array() - reach, hi = b.bounds.max.cast<Real>().array() + reach;
        if ((x.array() >= lo.array()).all() && (x.array() <= hi.array()).all()) return true;
    }
    return false;
}

Access SelectActiveSystem::access() const {
    return Access()
        .read(fluid(comp::t_last), fluid(comp::dt), fluid(comp::position), res::moving_bodies, res::dt)
        .write(fluid(comp::active), fluid(comp::wake), res::active_set, counter::active);
}

void SelectActiveSystem::register_components(World& w) {
    w.fluid.store.add(comp::t_last);
    w.fluid.store.add(comp::dt);
    w.fluid.store.add(comp::active);
    w.fluid.store.add(comp::wake);
}

void SelectActiveSystem::run(Context& ctx) {
    const auto t_last = ctx.read(fluid(comp::t_last));
    const auto dt = ctx.read(fluid(comp::dt));
    auto active = ctx.write(fluid(comp::active));
    auto wake = ctx.write(fluid(comp::wake));
    const auto x = ctx.read(fluid(comp::position));
    const Tick now = ctx.clock().t_ticks;
    // The deadline rule (scene key simulation.stepping.activation, default): evaluate a particle
    // at the last step that starts before its deadline t_last + Delta t_i, predicting this step's
    // length by the last stable Delta t_sim (IndividualGlobalDtSystem then keeps the step from
    // carrying anyone past a deadline). He's rule as written (`paper`) evaluates at the first
    // step that starts at or after the deadline: ahead = one tick.
    const Tick ahead = m_activation == Activation::Deadline ? std::max<Tick>(1, to_ticks(ctx.read(res::dt).dt_stable))
                                                           : Tick(1);
    const std::size_t n = t_last.size();
    const Real h = ctx.physics().h;
    const auto& bodies = ctx.read(res::moving_bodies);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            // He Alg. 2 line 2. `paper`: deadline <= now, the tie counted as active (the paper
            // writes "<"; with "<" a particle whose Delta t_i equals Delta t_sim would wait two
            // steps). `deadline`: deadline < now + ahead.
            active[i] = (t_last[i] + to_ticks(dt[i]) < now + ahead) || wake[i] ||
                        (!bodies.empty() && near_moving_body(bodies, x[i], dt[i], h));
            wake[i] = 0;
        }
    });
    auto& set = ctx.write(res::active_set);
    set = collect_indices(n, [&](std::size_t i) { return active[i] != 0; });
    ctx.write(counter::active) = set.size();
}


}  // namespace sph
