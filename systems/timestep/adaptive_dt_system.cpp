// Ihmsen et al. 2010 sec. 3.3, eq. 16-27 (the decision itself: adaptive_controller.hpp).
#include "systems/timestep/adaptive_dt_system.hpp"

#include <algorithm>

#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"
#include "systems/pcisph/pcisph_state.hpp"

namespace sph {

AdaptiveParams adaptive_params(const Scene& scene) {
    const PcisphParams& p = scene.pcisph;
    AdaptiveParams a;
    a.eta_avg = p.eta;
    a.eta_max = p.eta_max.value_or(10.0 * p.eta);  // sec. 3.3: eta_max = 10 eta_avg
    a.delta_shock = p.delta_shock.value_or(4.0 * p.eta);
    a.dt_max = scene.simulation.stepping.dt_max;
    return a;
}

Access AdaptiveDtSystem::access() const {
    return Access().read(res::stats, res::dt).write(res::pcisph_controller, res::rollback);
}

void AdaptiveDtSystem::register_components(World& w) {
    w.resources.add<PcisphController>(res::pcisph_controller.name, Lifetime::Kept);
}

void AdaptiveDtSystem::run(Context& ctx) {
    const StepSize& st = ctx.read(res::dt);
    const StepStats& stats = ctx.read(res::stats);
    PcisphController& pc = ctx.write(res::pcisph_controller);
    AdaptiveParams params = m_params;
    params.h = ihmsen_h(ctx.physics().spacing);
    const AdaptiveStepController c(params);
    AdaptiveInputs in;
    in.dt = st.dt_stable > 0 ? st.dt_stable : st.dt;  // a last step clipped to the end is not a decision
    in.rho_err_avg = stats.rho_err_avg;
    in.rho_err_max = stats.rho_err_max;
    in.prev_rho_err_max = pc.prev_err_max;
    in.v_max = stats.v_max;
    in.f_max = stats.a_max;
    const AdaptiveResult r = c.decide(in);
    pc.reason = int(r.decision);
    if (r.decision == AdaptiveDecision::Shock) {
        // The engine rolls back two steps (Recipe::rollback_steps) and resumes with eq. 24.
        Rollback& rb = ctx.write(res::rollback);
        rb.request_dt = r.dt;
        rb.requested_by = name();
        rb.reason = "shock (Ihmsen 2010 eq. 25-27; resume step from eq. 24)";
        return;
    }
    pc.pending_dt = r.dt;
    pc.prev_err_max = stats.rho_err_max;
    // A last step clipped to land on the end time is short, and PCISPH's pressure acceleration
    // grows as 1/dt^2 (delta, eq. 4-5): its F^max says nothing about the flow, so the tracked
    // maxima of eq. 14-15 skip it.
    if (st.dt < 0.999 * st.dt_stable) return;
    pc.v_max_tracked = std::max(pc.v_max_tracked, stats.v_max);
    pc.a_max_tracked = std::max(pc.a_max_tracked, stats.a_max);
    pc.rho_err_avg_max = std::max(pc.rho_err_avg_max, stats.rho_err_avg);
}

}  // namespace sph
