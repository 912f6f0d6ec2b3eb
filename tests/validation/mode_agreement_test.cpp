// Mode agreement on scenes/dam_break.json (its probes `front` and `fluid`): every adaptive
// stepping mode the loader knows (global, individual, binned today; a mode added later joins
// with no new code) must reproduce the front and kinetic-energy curves of a fine constant-step
// reference over the collapse and the run along the floor (0 <= t <= 0.5 s; the front reaches
// the far wall at about 0.45 s). The reference steps at half the smallest step `global` took.
//
// Tolerances, and why:
//  * front: RMS deviation <= half a particle spacing (0.01 m). The front probe is the position
//    of a particle (the farthest with >= 4 neighbours): it cannot resolve much less than the
//    particle scale. The front travels 1.2 m in this window, 60 spacings. Measured 2026-12-06:
//    global 0.20, individual 0.21, binned 0.17 spacings (2026-11-23: 0.15 and 0.22); half a
//    spacing is 2.4x the largest.
//  * kinetic energy: RMS deviation <= 0.6 % of the reference's peak kinetic energy. The step
//    size changes the energy the artificial viscosity and the symplectic Euler scheme
//    dissipate (both O(dt)); the modes take steps 1.3-3 times the reference's (global 0.4 ms
//    on average against 0.19 ms). Measured 2026-12-06: global 0.15 %, individual 0.19 %
//    (`deadline` activation; He's `paper` rule measured 1.2 % on 2026-11-23 and is not run
//    here), binned 0.12 %; 0.6 % is 3x the largest, while a mode that loses or gains energy
//    visibly (a step too large for the impact) fails.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "engine/core/errors.hpp"
#include "validation/experiment.hpp"

using namespace sph;
using namespace sph::test;

namespace {

const std::string kScene = SPH_SOURCE_DIR "/scenes/dam_break.json";
constexpr double kEnd = 0.5;

struct ModeRun {
    ProbeSet probes;
    double min_dt = std::numeric_limits<double>::infinity();
    std::int64_t steps = 0;
};

ModeRun run_scene(std::vector<std::pair<std::string, nlohmann::json>> overrides) {
    overrides.emplace_back("/simulation/end_time", kEnd);
    overrides.emplace_back("/simulation/frame_rate", 0);
    const Scene scene = load_scene(kScene, overrides);
    auto sim = make_simulation(scene);
    ModeRun r{ProbeSet(scene.probes)};
    r.probes.sample_due(sim->world());
    sim->run_until(kEnd, [&](const Simulation& s) {
        r.probes.sample_due(s.world());
        if (s.time() < kEnd - 1e-9) r.min_dt = std::min(r.min_dt, s.world().step_size.dt_stable);
    });
    r.steps = sim->steps();
    return r;
}

/// RMS over the reference's sample times of (series - reference), the series interpolated.
double rms_deviation(const ProbeSeries& s, const ProbeSeries& ref, const std::string& col) {
    const auto t = s.column("t"), v = s.column(col), tr = ref.column("t"), vr = ref.column(col);
    double sum = 0;
    for (std::size_t i = 0; i < tr.size(); ++i) {
        const double d = interp(t, v, tr[i]) - vr[i];
        sum += d * d;
    }
    return std::sqrt(sum / double(tr.size()));
}

}  // namespace

TEST(ModeAgreement, DamBreakFrontAndEnergyMatchAFineConstantReference) {
    std::vector<std::string> modes;
    for (const auto& m : adaptive_modes()) {
        try {
            load_scene(kScene, {{"/simulation/stepping/mode", m}});
            modes.push_back(m);
        } catch (const SceneError&) {  // a mode of another method
        }
    }
    ASSERT_FALSE(modes.empty());
    std::vector<std::pair<std::string, ModeRun>> runs;
    for (const auto& m : modes) runs.emplace_back(m, run_scene({{"/simulation/stepping/mode", m}}));
    double min_dt = std::numeric_limits<double>::infinity();
    for (const auto& [m, r] : runs)
        if (m == "global") min_dt = r.min_dt;
    if (!std::isfinite(min_dt))
        for (const auto& [m, r] : runs) min_dt = std::min(min_dt, r.min_dt);
    const double dt_ref = 0.5 * min_dt;
    const ModeRun ref = run_scene({{"/simulation/stepping/mode", "constant"}, {"/simulation/stepping/dt", dt_ref}});
    const auto ke = ref.probes.series("fluid").column("kinetic");
    const double ke_peak = *std::max_element(ke.begin(), ke.end());
    const double spacing = 0.02;
    const auto front_ref = ref.probes.series("front").column("front");
    std::printf("mode agreement: reference constant dt = %.4g ms, %lld steps; front %.3f -> %.3f m, peak kinetic "
                "energy %.2f J\n",
                1e3 * dt_ref, static_cast<long long>(ref.steps), front_ref.front(), front_ref.back(), ke_peak);
    for (const auto& [m, r] : runs) {
        const double dev_front = rms_deviation(r.probes.series("front"), ref.probes.series("front"), "front");
        const double dev_ke = rms_deviation(r.probes.series("fluid"), ref.probes.series("fluid"), "kinetic");
        std::printf("mode agreement [%s]: %lld steps; front RMS deviation %.4f m (%.2f spacings), kinetic energy RMS "
                    "deviation %.3f J (%.2f %% of peak)\n",
                    m.c_str(), static_cast<long long>(r.steps), dev_front, dev_front / spacing, dev_ke,
                    100 * dev_ke / ke_peak);
        EXPECT_LE(dev_front, 0.5 * spacing) << m;
        EXPECT_LE(dev_ke, 0.006 * ke_peak) << m;
    }
}
