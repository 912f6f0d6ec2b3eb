// He et al. Alg. 2 lines 18-21 (semi-implicit Euler from the last evaluated state):
//   Delta t = t_sim + Delta t_sim - t_last_i
//   v_i(t_last + Delta t) = v_i(t_last) + Delta t a_i(t_last)
//   x_i(t_last + Delta t) = x_i(t_last) + Delta t v_i(t_last + Delta t)
// and line 9: rho_i = rho_i(t_last) + Delta t drho_i/dt (He eq. 5), p_i from Tait (He eq. 2).
#include "systems/integrate/async_integration_system.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"
#include "systems/density/density_kernels.hpp"
#include "systems/integrate/drift.hpp"

namespace sph {

Access AsyncIntegrationSystem::access() const {
    // The kick only: the active rows' new base state. It reads t_last, which the forces stamp,
    // so it runs once the base state (x, v with a and drho/dt) is complete rather than beside
    // the density and force loops, whose threads it took (docs/results/benchmarks.md).
    if (m_active_only)
        return Access()
            .read(res::active_set, fluid(comp::position), fluid(comp::velocity), fluid(comp::t_last))
            .copies(fluid(comp::position_last), fluid(comp::velocity_last))  // of x and v, checked when written
            .rows(res::active_set);
    return Access()
        .read(fluid(comp::acceleration), fluid(comp::active), fluid(comp::t_last), fluid(comp::drho_dt),
              fluid(comp::density_last), res::dt)
        .write(fluid(comp::velocity), fluid(comp::position), fluid(comp::position_last), fluid(comp::velocity_last),
               fluid(comp::density), fluid(comp::pressure));
}

void AsyncIntegrationSystem::register_components(World& w) {
    w.fluid.store.add(comp::position_last);
    w.fluid.store.add(comp::velocity_last);
    w.fluid.store.add(comp::density_last);
    w.fluid.store.add(comp::drho_dt);
    w.fluid.store.add(comp::t_last);
    w.fluid.store.add(comp::active);
}

void AsyncIntegrationSystem::run(Context& ctx) {
    if (m_active_only) {
        // Evaluated now: the state at t_sim becomes the base the row is drifted from (lines
        // 19-21 with t_last = t_sim), by the next step's drift or the collision net.
        const auto x = ctx.read(fluid(comp::position));
        const auto v = ctx.read(fluid(comp::velocity));
        auto x0 = ctx.write(fluid(comp::position_last));
        auto v0 = ctx.write(fluid(comp::velocity_last));
        const auto& set = ctx.read(res::active_set);
        if (set.size() == x.size()) {  // every row (the set is 0..n-1): two straight copies
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x.size(), 8192), [&](const auto& r) {
                std::copy(x.begin() + r.begin(), x.begin() + r.end(), x0.begin() + r.begin());
                std::copy(v.begin() + r.begin(), v.begin() + r.end(), v0.begin() + r.begin());
            });
            return;
        }
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, set.size(), 4096), [&](const auto& r) {
            for (std::size_t k = r.begin(); k < r.end(); ++k) {
                x0[set[k]] = x[set[k]];
                v0[set[k]] = v[set[k]];
            }
        });
        return;
    }
    auto x = ctx.write(fluid(comp::position));
    auto v = ctx.write(fluid(comp::velocity));
    auto x0 = ctx.write(fluid(comp::position_last));
    auto v0 = ctx.write(fluid(comp::velocity_last));
    auto rho = ctx.write(fluid(comp::density));
    auto p = ctx.write(fluid(comp::pressure));
    const auto a = ctx.read(fluid(comp::acceleration));
    const auto active = ctx.read(fluid(comp::active));
    const auto t_last = ctx.read(fluid(comp::t_last));
    const auto drho = ctx.read(fluid(comp::drho_dt));
    const auto rho0 = ctx.read(fluid(comp::density_last));
    const Tick t_end = ctx.clock().t_ticks + ctx.read(res::dt).dt_ticks;
    const Real rest = ctx.physics().rest_density, b = ctx.physics().tait_b;
    auto advance = [&](std::size_t i) {
        if (active[i]) {  // evaluated now: this is its new base state (t_last = t_sim)
            x0[i] = x[i];
            v0[i] = v[i];
        }
        const Real dt = drift_interval(t_end, t_last[i]);  // line 19
        v[i] = drifted_velocity(v0[i], a[i], dt);           // line 20
        x[i] = drifted_position(x0[i], v[i], dt);           // line 21
        rho[i] = drifted_density(rho0[i], drho[i], dt);     // line 9, at the new time
        p[i] = tait_pressure(rho[i], rest, b);
    };
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x.size(), 4096), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) advance(i);
    });
}

}  // namespace sph
