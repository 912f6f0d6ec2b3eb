// `constant` stepping: Delta t is the scene's simulation.stepping.dt every step; the last step
// is clipped so that the run ends exactly at its end time.
#include "systems/timestep/constant_dt_system.hpp"

#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"

namespace sph {

Access ConstantDtSystem::access() const { return Access().write(res::dt); }

void ConstantDtSystem::run(Context& ctx) {
    StepSize& s = ctx.write(res::dt);
    s.dt_stable = m_dt;
    s.set_clipped(m_dt, ctx.clock());
}

}  // namespace sph
