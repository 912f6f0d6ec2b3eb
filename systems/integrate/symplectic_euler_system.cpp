// He et al. Alg. 1 lines 9-10 (semi-implicit Euler).
#include "systems/integrate/symplectic_euler_system.hpp"

#include <tbb/parallel_for.h>

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"

namespace sph {

Access SymplecticEulerSystem::access() const {
    return Access().read(fluid(comp::acceleration), res::dt).write(fluid(comp::velocity), fluid(comp::position));
}

void SymplecticEulerSystem::run(Context& ctx) {
    auto x = ctx.write(fluid(comp::position));
    auto v = ctx.write(fluid(comp::velocity));
    const auto a = ctx.read(fluid(comp::acceleration));
    const Real dt = Real(ctx.read(res::dt).dt);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x.size(), 4096), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            v[i] += dt * a[i];
            x[i] += dt * v[i];
        }
    });
}

}  // namespace sph
