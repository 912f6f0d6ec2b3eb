// Ihmsen et al. 2010 Alg. 2 after the loop: v(t+dt) = v + dt a, x(t+dt) = x + dt v(t+dt) (Euler-Cromer).
#include "systems/pcisph/pcisph_integrate_system.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"
#include "systems/pcisph/pcisph_components.hpp"
#include "systems/pcisph/pcisph_kernels.hpp"
#include "systems/pcisph/pcisph_state.hpp"

namespace sph {

Access PcisphIntegrateSystem::access() const {
    return Access()
        .read(fluid(comp::pressure_acceleration), res::dt)
        .write(fluid(comp::velocity), fluid(comp::position), fluid(comp::acceleration))
        .read_if(m_nonpressure, fluid(comp::nonpressure_acceleration));
}

void PcisphIntegrateSystem::register_components(World& w) { w.fluid.store.add(comp::acceleration); }

void PcisphIntegrateSystem::run(Context& ctx) {
    auto x = ctx.write(fluid(comp::position));
    auto v = ctx.write(fluid(comp::velocity));
    auto acc = ctx.write(fluid(comp::acceleration));
    const auto ap = ctx.read(fluid(comp::pressure_acceleration));
    const std::span<const Vec3> anp =
        m_nonpressure ? ctx.read(fluid(comp::nonpressure_acceleration)) : std::span<const Vec3>{};
    const Real dt = Real(ctx.read(res::dt).dt);
    const Vec3 g = ctx.physics().gravity;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x.size(), 4096), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            Vec3 a = g + ap[i];
            if (!anp.empty()) a += anp[i];
            acc[i] = a;
            v[i] += dt * a;
            x[i] += dt * v[i];
        }
    });
}

}  // namespace sph
