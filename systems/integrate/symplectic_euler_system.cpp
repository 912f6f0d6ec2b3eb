// He et al. Alg. 1 lines 9-10 (semi-implicit Euler).
#include "systems/integrate/symplectic_euler_system.hpp"

#include <tbb/parallel_for.h>

#include "engine/components.hpp"
#include "engine/world.hpp"

namespace sph {

Access SymplecticEulerSystem::access() const {
    return {{res::fluid(comp::acceleration.name), res::dt},
            {res::fluid(comp::velocity.name), res::fluid(comp::position.name)}};
}

void SymplecticEulerSystem::run(World& w) {
    auto x = w.fluid.store.get(comp::position);
    auto v = w.fluid.store.get(comp::velocity);
    const auto a = w.fluid.store.get(comp::acceleration);
    const Real dt = Real(w.step.dt);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x.size(), 4096), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            v[i] += dt * a[i];
            x[i] += dt * v[i];
        }
    });
}

}  // namespace sph
