#include "systems/debug/nan_injection_system.hpp"

#include <limits>

#include "engine/components.hpp"
#include "engine/world.hpp"

namespace sph {

Access NanInjectionSystem::access() const {
    return {{res::fluid(comp::acceleration.name)}, {res::fluid(comp::acceleration.name)}};
}

void NanInjectionSystem::run(World& w) {
    if (w.step.step != m_step) return;
    const auto id = w.fluid.store.get(comp::id);
    auto a = w.fluid.store.get(comp::acceleration);
    for (std::size_t i = 0; i < id.size(); ++i)
        if (id[i] == m_id) a[i].x() = std::numeric_limits<Real>::quiet_NaN();
}

void add_nan_injection(Recipe& recipe, std::int64_t step, std::uint32_t particle_id) {
    auto at = recipe.step.end();
    for (auto it = recipe.step.begin(); it != recipe.step.end(); ++it)
        if ((*it)->name() == "forces") at = it + 1;
    recipe.step.insert(at, std::make_unique<NanInjectionSystem>(step, particle_id));
}

}  // namespace sph
