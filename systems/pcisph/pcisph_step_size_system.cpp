// Ihmsen et al. 2010 sec. 3.3: the initial step dt = 0.25 h / v0_max, then the controller's
// step; Alg. 2 last line: recompute beta (eq. 5) and delta (eq. 4) when dt changes.
#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <cmath>

#include "engine/components.hpp"
#include "engine/world.hpp"
#include "systems/pcisph/pcisph_kernels.hpp"
#include "systems/pcisph/pcisph_systems.hpp"
#include "systems/timestep/adaptive_controller.hpp"
#include "systems/timestep/adaptive_dt_system.hpp"

namespace sph {

Access PcisphStepSizeSystem::access() const {
    Access a{{res::pcisph_controller}, {res::dt, res::pcisph_delta}};
    if (m_adaptive) a.reads.push_back(res::fluid(comp::velocity.name));
    return a;
}

void PcisphStepSizeSystem::run(World& w) {
    StepState& st = w.step;
    PcisphState& pc = w.pcisph;
    if (m_adaptive) {
        if (!(pc.pending_dt > 0)) {
            const auto v = w.fluid.store.get(comp::velocity);
            const double v0 = tbb::parallel_reduce(
                tbb::blocked_range<std::size_t>(0, v.size(), 4096), 0.0,
                [&](const auto& r, double m) {
                    for (std::size_t i = r.begin(); i < r.end(); ++i) m = std::max(m, double(v[i].norm()));
                    return m;
                },
                [](double a, double b) { return std::max(a, b); });
            const AdaptiveStepController c(adaptive_params(w));
            pc.pending_dt = c.initial_dt(v0, w.scene.simulation.gravity.norm(), w.physics.fluid_height);
        }
        st.dt_stable = pc.pending_dt;
        st.set_dt_clipped(pc.pending_dt);
    }
    // The run ends exactly at its end time, but never with a sliver of a step: PCISPH corrects
    // the whole predicted density error within one step, so its velocity change grows as
    // 1/dt (delta ~ 1/dt^2, eq. 4-5) and a last step of a microsecond throws particles out at
    // tens of m/s (measured in `glass`). When between one and two steps remain, both of the
    // last two steps take half of what remains (each at least dt/2).
    if (std::isfinite(st.t_stop)) {
        const double full = st.dt_stable > 0 ? st.dt_stable : st.dt;  // the step before clipping
        const double remaining = st.t_stop - st.t;
        if (remaining > full && remaining < 2.0 * full) st.set_dt(0.5 * remaining);
    }
    if (st.dt != pc.delta_dt) {
        if (m_prototype_sum == 0) m_prototype_sum = pcisph_prototype_sum(w.kernel, w.physics.spacing);
        pc.delta = pcisph_delta(m_prototype_sum, w.physics.mass, st.dt, w.physics.rest_density);
        pc.delta_dt = st.dt;
    }
}

Access PcisphResetSystem::access() const {
    Access a{{}, {res::fluid(comp::pressure.name), res::fluid(comp::pressure_acceleration.name)}};
    if (m_ihmsen) a.writes.push_back(res::boundary(comp::pressure.name));
    return a;
}

void PcisphResetSystem::register_components(World& w) {
    w.fluid.store.add(comp::pressure);
    w.fluid.store.add(comp::pressure_acceleration);
    if (m_ihmsen) w.boundary.store.add(comp::pressure);
}

void PcisphResetSystem::run(World& w) {
    auto p = w.fluid.store.get(comp::pressure);
    auto ap = w.fluid.store.get(comp::pressure_acceleration);
    std::fill(p.begin(), p.end(), Real(0));
    std::fill(ap.begin(), ap.end(), Vec3::Zero());
    if (m_ihmsen) {
        auto pb = w.boundary.store.get(comp::pressure);
        std::fill(pb.begin(), pb.end(), Real(0));
    }
}

}  // namespace sph
