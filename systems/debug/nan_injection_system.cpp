#include "systems/debug/nan_injection_system.hpp"

#include <limits>

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"

namespace sph {

Access NanInjectionSystem::access() const {
    return Access().read(fluid(comp::id)).write(fluid(comp::acceleration));
}

void NanInjectionSystem::run(Context& ctx) {
    if (ctx.clock().step != m_step) return;
    const auto id = ctx.read(fluid(comp::id));
    auto a = ctx.write(fluid(comp::acceleration));
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
