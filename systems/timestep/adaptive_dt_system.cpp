// Ihmsen et al. 2010 sec. 3.3, eq. 16-27 (the decision itself: adaptive_controller.hpp).
#include "systems/timestep/adaptive_dt_system.hpp"

#include <algorithm>

#include "engine/world.hpp"

namespace sph {

AdaptiveParams adaptive_params(const World& w) {
    const PcisphParams& p = w.scene.pcisph;
    AdaptiveParams a;
    a.h = w.physics.h;
    a.eta_avg = p.eta;
    a.eta_max = p.eta_max.value_or(10.0 * p.eta);  // sec. 3.3: eta_max = 10 eta_avg
    a.delta_shock = p.delta_shock.value_or(4.0 * p.eta);
    a.dt_max = w.scene.simulation.stepping.dt_max;
    return a;
}

Access AdaptiveDtSystem::access() const { return {{res::stats, res::dt}, {res::pcisph_controller}}; }

void AdaptiveDtSystem::run(World& w) {
    const StepState& st = w.step;
    PcisphState& pc = w.pcisph;
    const AdaptiveStepController c(adaptive_params(w));
    AdaptiveInputs in;
    in.dt = st.dt_stable > 0 ? st.dt_stable : st.dt;  // a last step clipped to the end is not a decision
    in.rho_err_avg = st.rho_err_avg;
    in.rho_err_max = st.rho_err_max;
    in.prev_rho_err_max = pc.prev_err_max;
    in.v_max = st.v_max;
    in.f_max = st.a_max;
    const AdaptiveResult r = c.decide(in);
    pc.reason = int(r.decision);
    if (r.decision == AdaptiveDecision::Shock) {
        pc.rollback_dt = r.dt;  // Simulation::step rolls back two steps and resumes with it
        return;
    }
    pc.pending_dt = r.dt;
    pc.prev_err_max = st.rho_err_max;
    // A last step clipped to land on the end time is short, and PCISPH's pressure acceleration
    // grows as 1/dt^2 (delta, eq. 4-5): its F^max says nothing about the flow, so the tracked
    // maxima of eq. 14-15 skip it.
    if (st.dt < 0.999 * st.dt_stable) return;
    pc.v_max_tracked = std::max(pc.v_max_tracked, st.v_max);
    pc.a_max_tracked = std::max(pc.a_max_tracked, st.a_max);
    pc.rho_err_avg_max = std::max(pc.rho_err_avg_max, st.rho_err_avg);
}

}  // namespace sph
