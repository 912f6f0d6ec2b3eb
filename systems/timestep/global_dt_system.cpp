// He et al. eq. 6 (CFL), eq. 7 (force) and eq. 8 (their minimum); the acoustic condition
// dt <= lambda_c h / (c_s + v_max) is our named option `stepping.acoustic` (docs/methods.md: why).
#include "systems/timestep/global_dt_system.hpp"

#include <cmath>
#include <limits>

#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"

namespace sph {

double global_time_step(const SteppingParams& p, double h, double c_s, double v_max, double a_max, double nu) {
    return StepBound(p, h, c_s, nu)(v_max, a_max);
}

Access GlobalDtSystem::access() const { return Access().read(res::stats).write(res::dt); }

void GlobalDtSystem::run(Context& ctx) {
    const StepStats& st = ctx.read(res::stats);
    StepSize& s = ctx.write(res::dt);
    const Physics& ph = ctx.physics();
    s.dt_stable = global_time_step(m_stepping, ph.h, ph.speed_of_sound, st.v_max, st.a_max, ph.kinematic_viscosity);
    // The last step is shortened so that the run ends exactly at its end time.
    s.set_clipped(s.dt_stable, ctx.clock());
}


}  // namespace sph
