// Ihmsen et al. 2010 Alg. 2, loop line 1: v* = v + dt (g + a^{v,st} + F^p/m), x* = x + dt v*.
#include "systems/pcisph/pcisph_predict_system.hpp"

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

Access PcisphPredictSystem::access() const {
    return Access()
        .read(fluid(comp::position), fluid(comp::velocity), fluid(comp::pressure_acceleration), res::dt)
        .write(fluid(comp::predicted_position))
        .read_if(m_nonpressure, fluid(comp::nonpressure_acceleration));
}

void PcisphPredictSystem::register_components(World& w) { w.fluid.store.add(comp::predicted_position); }

void PcisphPredictSystem::run(Context& ctx) {
    const auto x = ctx.read(fluid(comp::position));
    const auto v = ctx.read(fluid(comp::velocity));
    const auto ap = ctx.read(fluid(comp::pressure_acceleration));
    const std::span<const Vec3> anp =
        m_nonpressure ? ctx.read(fluid(comp::nonpressure_acceleration)) : std::span<const Vec3>{};
    auto xs = ctx.write(fluid(comp::predicted_position));
    const Real dt = Real(ctx.read(res::dt).dt);
    const Vec3 g = ctx.physics().gravity;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x.size(), 4096), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            Vec3 a = g + ap[i];
            if (!anp.empty()) a += anp[i];
            xs[i] = x[i] + dt * (v[i] + dt * a);
        }
    });
}

}  // namespace sph
