// Ihmsen et al. 2010 sec. 3.3: the initial step dt = 0.25 h / v0_max, then the controller's
// step; Alg. 2 last line: recompute beta (eq. 5) and delta (eq. 4) when dt changes.
#include "systems/pcisph/pcisph_step_size_system.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <cmath>
#include <limits>

#include <nlohmann/json.hpp>

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"
#include "systems/pcisph/pcisph_components.hpp"
#include "systems/pcisph/pcisph_kernels.hpp"
#include "systems/pcisph/pcisph_state.hpp"
#include "systems/timestep/adaptive_controller.hpp"

namespace sph {

Access PcisphStepSizeSystem::access() const {
    return Access()
        .write(res::dt, res::pcisph_delta)
        .read_if(m_adaptive, fluid(comp::velocity))
        .write_if(m_adaptive, res::pcisph_controller, res::rollback);
}

void PcisphStepSizeSystem::register_components(World& w) {
    w.resources.add<PcisphDelta>(res::pcisph_delta.name, Lifetime::Kept);
    w.resources.add<PcisphController>(res::pcisph_controller.name, Lifetime::Kept);
}

void PcisphStepSizeSystem::run(Context& ctx) {
    StepSize& st = ctx.write(res::dt);
    const Clock& clock = ctx.clock();
    PcisphDelta& pd = ctx.write(res::pcisph_delta);
    if (m_adaptive) {
        PcisphController& pc = ctx.write(res::pcisph_controller);
        // After a rollback the engine hands back the step to resume with (eq. 24).
        Rollback& rb = ctx.write(res::rollback);
        if (rb.resume_dt > 0) {
            pc.pending_dt = rb.resume_dt;
            rb.resume_dt = 0;
        }
        if (!(pc.pending_dt > 0)) {
            const auto v = ctx.read(fluid(comp::velocity));
            const double v0 = tbb::parallel_reduce(
                tbb::blocked_range<std::size_t>(0, v.size(), 4096), 0.0,
                [&](const auto& r, double m) {
                    for (std::size_t i = r.begin(); i < r.end(); ++i) m = std::max(m, double(v[i].norm()));
                    return m;
                },
                [](double a, double b) { return std::max(a, b); });
            AdaptiveParams params = m_params;
            params.h = ihmsen_h(ctx.physics().spacing);
            const AdaptiveStepController c(params);
            pc.pending_dt = c.initial_dt(v0, m_gravity, ctx.physics().fluid_height);
        }
        st.dt_stable = pc.pending_dt;
        st.set_clipped(pc.pending_dt, clock);
    }
    // The run ends exactly at its end time, but never with a sliver of a step: PCISPH corrects
    // the whole predicted density error within one step, so its velocity change grows as
    // 1/dt (delta ~ 1/dt^2, eq. 4-5) and a last step of a microsecond throws particles out at
    // tens of m/s (measured in `glass`). When between one and two steps remain, both of the
    // last two steps take half of what remains (each at least dt/2).
    if (std::isfinite(clock.t_stop)) {
        const double full = st.dt_stable > 0 ? st.dt_stable : st.dt;  // the step before clipping
        const double remaining = clock.t_stop - clock.t;
        if (remaining > full && remaining < 2.0 * full) st.set(0.5 * remaining);
    }
    if (st.dt != pd.delta_dt) {
        if (m_prototype_sum == 0) m_prototype_sum = pcisph_prototype_sum(ctx.kernel(), ctx.physics().spacing);
        pd.delta = pcisph_delta(m_prototype_sum, ctx.physics().mass, st.dt, ctx.physics().rest_density);
        pd.delta_dt = st.dt;
    }
}

void PcisphStepSizeSystem::summarise(const World& w, const RunTotals& totals, nlohmann::json& j) const {
    const PcisphController& pc = w.resources.get<PcisphController>(res::pcisph_controller.name);
    const double h = w.physics.h;
    // Ihmsen 2010 eq. 14-15 with lambda_v = 0.4 and lambda_f = 0.25 (Monaghan 1992) and the
    // maxima tracked over the run: the fixed step a constant-step run would need.
    double dt_const = std::numeric_limits<double>::infinity();
    if (pc.v_max_tracked > 0) dt_const = std::min(dt_const, 0.4 * h / pc.v_max_tracked);
    if (pc.a_max_tracked > 0) dt_const = std::min(dt_const, 0.25 * std::sqrt(h / pc.a_max_tracked));
    const double steps = double(totals.kept_steps);
    j["pcisph"] = {{"avg_iterations", steps > 0 ? totals.counter_sum(counter::iterations.name) / steps : 0.0},
                   {"avg_active_boundary_per_fluid",
                    steps > 0 ? totals.counter_per_fluid_sum(counter::boundary_active.name) / steps : 0.0},
                   {"v_max_tracked", pc.v_max_tracked},
                   {"a_max_tracked", pc.a_max_tracked},
                   {"dt_eq14_15", std::isfinite(dt_const) ? dt_const : 0.0},
                   {"boundary_handling", m_summary.boundary_handling},
                   {"eta", m_summary.eta}};
}

}  // namespace sph
