// Ihmsen et al. 2010 Alg. 2: p_i = 0, F^p_i = 0 (and p_b = 0) before the loop.
#include "systems/pcisph/pcisph_reset_system.hpp"

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

Access PcisphResetSystem::access() const {
    return Access()
        .write(fluid(comp::pressure), fluid(comp::pressure_acceleration))
        .write_if(m_ihmsen, boundary(comp::pressure));
}

void PcisphResetSystem::register_components(World& w) {
    w.fluid.store.add(comp::pressure);
    w.fluid.store.add(comp::pressure_acceleration);
    if (m_ihmsen) w.boundary.store.add(comp::pressure);
}

void PcisphResetSystem::run(Context& ctx) {
    auto p = ctx.write(fluid(comp::pressure));
    auto ap = ctx.write(fluid(comp::pressure_acceleration));
    std::fill(p.begin(), p.end(), Real(0));
    std::fill(ap.begin(), ap.end(), Vec3::Zero());
    if (m_ihmsen) {
        auto pb = ctx.write(boundary(comp::pressure));
        std::fill(pb.begin(), pb.end(), Real(0));
    }
}

}  // namespace sph
