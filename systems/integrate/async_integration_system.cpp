// He et al. Alg. 2 lines 18-21 (semi-implicit Euler from the last evaluated state):
//   Delta t = t_sim + Delta t_sim - t_last_i
//   v_i(t_last + Delta t) = v_i(t_last) + Delta t a_i(t_last)
//   x_i(t_last + Delta t) = x_i(t_last) + Delta t v_i(t_last + Delta t)
// and line 9: rho_i = rho_i(t_last) + Delta t drho_i/dt (He eq. 5), p_i from Tait (He eq. 2).
#include "systems/integrate/async_integration_system.hpp"

#include <tbb/parallel_for.h>

#include "engine/components.hpp"
#include "engine/world.hpp"
#include "systems/density/density_kernels.hpp"

namespace sph {

Access AsyncIntegrationSystem::access() const {
    return {{res::fluid(comp::acceleration.name), res::fluid(comp::active.name), res::fluid(comp::t_last.name),
             res::fluid(comp::drho_dt.name), res::fluid(comp::density_last.name), res::dt},
            {res::fluid(comp::velocity.name), res::fluid(comp::position.name), res::fluid(comp::position_last.name),
             res::fluid(comp::velocity_last.name), res::fluid(comp::density.name), res::fluid(comp::pressure.name)}};
}

void AsyncIntegrationSystem::register_components(World& w) {
    w.fluid.store.add(comp::position_last);
    w.fluid.store.add(comp::velocity_last);
    w.fluid.store.add(comp::density_last);
    w.fluid.store.add(comp::drho_dt);
    w.fluid.store.add(comp::t_last);
    w.fluid.store.add(comp::active);
}

void AsyncIntegrationSystem::run(World& w) {
    auto x = w.fluid.store.get(comp::position);
    auto v = w.fluid.store.get(comp::velocity);
    auto x0 = w.fluid.store.get(comp::position_last);
    auto v0 = w.fluid.store.get(comp::velocity_last);
    auto rho = w.fluid.store.get(comp::density);
    auto p = w.fluid.store.get(comp::pressure);
    const auto a = w.fluid.store.get(comp::acceleration);
    const auto active = w.fluid.store.get(comp::active);
    const auto t_last = w.fluid.store.get(comp::t_last);
    const auto drho = w.fluid.store.get(comp::drho_dt);
    const auto rho0 = w.fluid.store.get(comp::density_last);
    const Tick t_end = w.step.t_ticks + w.step.dt_ticks;
    const Real rest = w.physics.rest_density, b = w.physics.tait_b;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x.size(), 4096), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            if (active[i]) {  // evaluated now: this is its new base state (t_last = t_sim)
                x0[i] = x[i];
                v0[i] = v[i];
            }
            const Real dt = Real(to_seconds(t_end - t_last[i]));  // line 19
            v[i] = v0[i] + dt * a[i];                               // line 20
            x[i] = x0[i] + dt * v[i];                               // line 21
            rho[i] = rho0[i] + dt * drho[i];                        // line 9, at the new time
            p[i] = tait_pressure(rho[i], rest, b);
        }
    });
}

}  // namespace sph
