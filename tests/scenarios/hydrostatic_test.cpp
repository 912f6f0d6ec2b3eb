// scenes/hydrostatic_tank.json: water at rest, in every stepping mode the loader knows. After
// settling, the pressure at depth d must be rho0 g d (../shared/validation/
// analytical_references.md, section 1; copied to data/validation/). The pressure is read by
// the scene's probes (engine/probes.hpp): interpolated on the centre line at y = 0.3, 0.2 and
// 0.1 m, averaged over the last third of the run (2-3 s), with the depth measured from the free
// surface the height probes find (the colour function's 0.5 level), averaged over the same
// window and over five lines (the centre line and four 6 cm from it in x and z). The test
// samples the probes at 1 kHz instead of the scene's 50 Hz, so that the mean of a noisy mode
// has a small standard error. No particle may leave the tank.
//
// The scene uses the corrected pressure gradient (fluid.pressure_gradient: corrected, Bonet &
// Lok 1999). With He et al.'s symmetric eq. 4 the settled column carries 2-6 % more pressure
// than its weight (README, Validation): the discrete equilibrium of the symmetric form on a
// settled, disordered particle set is not the continuum's, and it does not improve with
// resolution (+2.4 / +4.2 / +3.8 % at 8x the particles).
//
// Tolerances: the 2 % for `constant` and `global` at depths 0.2 and 0.3 m. The pressure
// is the mean of five lines, like the surface (a point probe also reads the arrangement of the
// particles around it). The shallowest probe, 0.1 m (5 spacings) below the surface, reads the
// settled surface layer, whose arrangement follows any change in the arithmetic: over eight runs
// of `global` that differ only in rounding (scalar or vectorised pair loops, sort_interval 13, 15,
// 16, 17; 2026-12-02) it read -0.86 to -2.14 % (mean -1.34 %; scalar -0.86 to -1.35 %, vectorised
// -1.16 to -2.14 %), while the density of the two loops agrees to 3e-7 with no bias (mean signed
// difference 1.5e-9). It is held to 2.5 %, the measured spread around its mean.
// `individual` (He's coefficients, no acoustic condition, activation `deadline`) lets resting
// particles take steps of up to dt_max while the acoustic period is h / c_s = 1.4 ms; its point
// pressure carries 200-240 Pa RMS of noise at 1 kHz (against 11-25 Pa in `global`). Its mean is
// held to 2 % plus three standard errors of the 1 kHz samples (the samples are correlated, so
// the true standard error is larger and the bound is the stricter for it); measured
// 2026-11-24: +0.21 / -0.22 / +0.25 % with standard errors of 0.55 / 0.31 / 0.20 %. A build
// that differed only in rounding the step cap to whole ticks read -2.01 / -0.82 / +0.69 %: the
// settled surface moved by 0.6 mm, which is 0.6 % at the shallowest probe. With He's activation rule as written (`paper`), under
// which a particle holds its acceleration for up to twice its step, it read +3.7 / +5.9 / +6.2 %
// with 0.9-2 kPa of noise (README, "Activation").
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>

#include "engine/data/components.hpp"
#include "engine/core/errors.hpp"
#include "engine/run/probes.hpp"
#include "systems/methods/recipes.hpp"

using namespace sph;

namespace {

struct Average {
    double mean = 0, standard_error = 0;
};

/// Mean of a probe column over t >= t0, and its standard error sd / sqrt(n).
Average mean_after(const ProbeSeries& s, const std::string& col, double t0) {
    const auto t = s.column("t"), v = s.column(col);
    double sum = 0, sum2 = 0;
    int n = 0;
    for (std::size_t i = 0; i < t.size(); ++i)
        if (t[i] >= t0 - 1e-9) sum += v[i], sum2 += v[i] * v[i], ++n;
    if (n == 0) return {};
    const double mean = sum / n, var = std::max(0.0, sum2 / n - mean * mean);
    return {mean, std::sqrt(var / n)};
}

/// Every WCSPH stepping mode but `individual`, whose summation tank HydrostaticTankContinuity's
/// `individual` case runs (with every check of PressureMatchesRhoGDepth) to compare its noise.
std::vector<std::string> modes() {
    std::vector<std::string> out;
    for (const auto& m : stepping_mode_names()) {
        if (m == "individual") continue;
        try {
            load_scene(SPH_SOURCE_DIR "/scenes/hydrostatic_tank.json", {{"/simulation/stepping/mode", m}});
            out.push_back(m);
        } catch (const SceneError&) {  // a mode of another method
        }
    }
    return out;
}

}  // namespace

class HydrostaticTank : public ::testing::TestWithParam<std::string> {};

/// The tank in `mode`; with `continuity` the density is integrated with delta-SPH diffusion
/// (fluid.density: continuity, delta 0.1). `noise`, if given, receives the pressure noise at rest
/// at y = 0.3, 0.2 and 0.1 m (Pa, the 1 kHz samples' standard deviation, mean of the five lines).
void check_tank(const std::string& mode, bool continuity, std::vector<double>* noise = nullptr);

TEST_P(HydrostaticTank, PressureMatchesRhoGDepth) { check_tank(GetParam(), false); }

// The continuity density with delta-SPH (docs/methods.md), same scene and tolerances, extrapolated
// walls (its default); measured 2026-12-04 (depths 0.1 / 0.2 / 0.3 m): global -0.65 / -0.34 /
// -0.26 % with 0.5-5.4 Pa of noise, individual +0.37 / -0.61 / -0.31 % with 186-194 Pa (surface
// 0.3993 m), binned -0.89 / -0.23 / -0.19 % with 0.7-6.5 Pa. With the density floored at rho0
// itself, `individual` read -3.24 / -2.61 / -2.10 % (surface 0.4049 m): the floor clipped the
// lower half of its resting noise and lifted the column (density_kernels.hpp,
// continuity_density_floor).
//
// The noise at rest is held no worse than the summation density's. In `global` and `binned` it is
// 0.5-7.3 Pa (2026-12-07, AVX-512), held below 14 Pa, the summation's lowest (14-23 Pa at 50 Hz,
// 2026-12-03). In `individual` the noise comes from its stepping, not the density, and continuity
// lowers it only a little: 188 / 193 / 195 Pa against the summation run's 213 / 226 / 213 Pa on
// this host (ratio of the means 0.885), and 186-194 against 200-240 before. A fixed 200 Pa, the
// bound until then, sat inside that scatter (2-6 % margin), so `individual` is held against a
// summation run of its own in the same test: the mean over the three depths below it ("no worse";
// measured 0.885, an 11 % margin where the fixed bound left 2 %).
class HydrostaticTankContinuity : public ::testing::TestWithParam<std::string> {};
TEST_P(HydrostaticTankContinuity, PressureMatchesRhoGDepthWithLessNoise) {
    std::vector<double> noise;
    check_tank(GetParam(), true, &noise);
    if (GetParam() == "individual" && noise.size() == 3) {
        std::vector<double> summation;
        check_tank(GetParam(), false, &summation);
        ASSERT_EQ(summation.size(), 3u);
        const double c = (noise[0] + noise[1] + noise[2]) / 3, s = (summation[0] + summation[1] + summation[2]) / 3;
        std::printf("hydrostatic [individual]: pressure noise at rest, mean of the three depths: continuity %.1f Pa, "
                    "summation %.1f Pa (ratio %.3f)\n", c, s, c / s);
        EXPECT_LT(c, s) << "continuity's noise at rest against the summation density's, individual";
    }
}
INSTANTIATE_TEST_SUITE_P(PerStepMode, HydrostaticTankContinuity, ::testing::Values("global", "individual", "binned"),
                         [](const auto& info) { return info.param; });

void check_tank(const std::string& mode, bool continuity, std::vector<double>* noise) {
    std::vector<std::pair<std::string, nlohmann::json>> overrides{{"/simulation/stepping/mode", mode},
                                                                   {"/simulation/frame_rate", 0}};
    if (continuity) overrides.push_back({"/fluid/density", "continuity"});
    for (int k : {0, 1, 2, 6, 7, 8, 9, 10, 12, 13, 14, 15, 16, 17, 18, 19, 20, 21, 22, 23})
        overrides.push_back({"/probes/" + std::to_string(k) + "/rate", 1000});
    const Scene scene = load_scene(SPH_SOURCE_DIR "/scenes/hydrostatic_tank.json", overrides);
    ASSERT_EQ(scene.fluid.pressure_gradient, PressureGradient::Corrected);
    auto sim = make_simulation(scene);
    ProbeSet probes(scene.probes);
    probes.sample_due(sim->world());
    const double end = scene.simulation.end_time, t0 = end - end / 3.0;
    double late_rho_err_max = 0;
    sim->run_until(end, [&](const Simulation& s) {
        probes.sample_due(s.world());
        if (s.time() >= t0) late_rho_err_max = std::max(late_rho_err_max, s.world().stats.rho_err_max);
    });
    const double rho0 = scene.fluid.rest_density, g = 9.81;
    // The free surface is flat at rest: its level is the mean of the five height lines (the
    // centre line alone reads up to 2 mm high when a top-layer particle sits on it, and 2 mm
    // is 2 % of the shallowest depth).
    double surface = 0;
    for (const char* name : {"surface", "surface_a", "surface_b", "surface_c", "surface_d"})
        surface += mean_after(probes.series(name), "y", t0).mean / 5;
    std::printf("hydrostatic [%s]: %lld steps, free surface at y = %.4f m (0.4 m at the start)\n", mode.c_str(),
                static_cast<long long>(sim->steps()), surface);
    for (const char* y : {"0.3", "0.2", "0.1"}) {
        const double depth = surface - std::stod(y), expect = rho0 * g * depth;
        // The pressure of the settled column, like its surface, is the mean of the five lines:
        // a point probe reads the local arrangement of the particles around it as well.
        Average p;
        for (const char* line : {"", "_a", "_b", "_c", "_d"}) {
            const Average one = mean_after(probes.series(std::string("p_y") + y + line), "p", t0);
            p.mean += one.mean / 5;
            p.standard_error += one.standard_error / 5;  // an upper bound: the lines correlate
        }
        const double wall = mean_after(probes.series(std::string("wall_y") + y), "p", t0).mean;
        std::printf("hydrostatic [%s%s]: depth %.3f m  rho0 g d = %.1f Pa  interpolated %.1f Pa (%+.2f %%, standard "
                    "error %.2f %%)  wall %.1f Pa (%+.2f %%)\n",
                    mode.c_str(), continuity ? ", continuity" : "", depth, expect, p.mean, 100 * (p.mean - expect) / expect,
                    100 * p.standard_error / expect, wall, 100 * (wall - expect) / expect);
        // The 1 kHz samples' spread (one line's standard deviation, the mean of the five).
        double sd = 0;
        for (const char* line : {"", "_a", "_b", "_c", "_d"}) {
            const auto& series = probes.series(std::string("p_y") + y + line);
            std::size_t n = 0;
            for (double t : series.column("t")) n += t >= t0 - 1e-9;
            sd += mean_after(series, "p", t0).standard_error * std::sqrt(double(n)) / 5;
        }
        std::printf("hydrostatic [%s%s]: y = %s m pressure noise (standard deviation at 1 kHz) %.1f Pa\n", mode.c_str(),
                    continuity ? ", continuity" : "", y, sd);
        if (noise) noise->push_back(sd);
        // Noise at rest no worse with the continuity density (HydrostaticTankContinuity above;
        // `individual` there, against a summation run).
        if (continuity && mode != "individual") {
            EXPECT_LT(sd, 14.0) << "y = " << y << " m";
        }
        const double bound = std::string(y) == "0.3" ? 0.025 : 0.02;  // see the tolerances above
        const double tolerance = mode == "individual" ? bound * expect + 3 * p.standard_error : bound * expect;
        EXPECT_NEAR(p.mean, expect, tolerance) << "y = " << y << " m";
    }
    const auto x = sim->world().fluid.store.get(comp::position);
    const Aabb tank = scene.boundaries[0].box;
    for (std::size_t i = 0; i < x.size(); ++i) ASSERT_TRUE(tank.contains(x[i].cast<double>())) << "particle " << i;
    EXPECT_LT(late_rho_err_max, 0.03);
    std::printf("hydrostatic [%s]: max density error over the last third %.3f %%\n", mode.c_str(),
                100 * late_rho_err_max);
}

INSTANTIATE_TEST_SUITE_P(EveryMode, HydrostaticTank, ::testing::ValuesIn(modes()),
                         [](const auto& info) { return info.param; });

// The stable edge of the acoustic coefficient (stable_lambda_c, engine/data/scene.hpp): the tank at
// rest in `global` with lambda_v = lambda_f = 1, so that the acoustic bound lambda_c h / (c_s + |v|)
// alone sets every step (c_s dt / h = lambda_c at rest). The whole fluid's kinetic energy (the
// scene's `fluid` probe, mean after 0.3 s, past the start's settling) at the edge and 0.1 above it,
// each against the same tank at the default lambda_c 0.4. The summation density runs at --scale 4
// (16,399 particles) for 0.6 s: its edge is 0.9 at the default 4,500 particles but 0.8 from 8,100
// up. Measured 2026-12-07 (AVX-512), mean over 0.3-0.6 s, against lambda_c 0.4: 8,100 particles
// 0.97x at 0.8 and 3.3x at 0.9; 16,399 1.03x and 7.7x; 36,000 1.04x and 13x; 105,393 1.09x and
// 25x. The continuity density runs at the default size for 1 s (0.0021 J at 0.4, 0.0022 J at 0.7
// (1.04x), 0.011 J at 0.8 (5.2x); at 36,000 particles 0.99x at 0.7 and 5.7x at 0.8). Held: at the
// edge at most 1.5x the default's (it is the default's settling, 0.97-1.09x), above it at least
// 3x (5.2x and 7.7x here): a change that moved either edge by 0.1 fails one of the two.
TEST(HydrostaticTankAcoustic, RingsAboveTheStableLambdaC) {
    struct Case {
        const char* density;
        double scale, end;
    };
    for (const Case c : {Case{"summation", 4.0, 0.6}, Case{"continuity", 1.0, 1.0}}) {
        const auto kinetic = [&](double lambda_c) {
            const Scene scene = load_scene(SPH_SOURCE_DIR "/scenes/hydrostatic_tank.json",
                                           {{"/simulation/stepping/mode", "global"},
                                            {"/simulation/stepping/lambda_v", 1.0},
                                            {"/simulation/stepping/lambda_f", 1.0},
                                            {"/simulation/stepping/lambda_c", lambda_c},
                                            {"/simulation/scale", c.scale},
                                            {"/simulation/end_time", c.end},
                                            {"/simulation/frame_rate", 0},
                                            {"/fluid/density", c.density}});
            auto sim = make_simulation(scene);
            ProbeSet probes(scene.probes);
            probes.sample_due(sim->world());
            sim->run_until(scene.simulation.end_time, [&](const Simulation& s) { probes.sample_due(s.world()); });
            return mean_after(probes.series("fluid"), "kinetic", 0.3).mean;
        };
        const Scene probe = load_scene(SPH_SOURCE_DIR "/scenes/hydrostatic_tank.json", {{"/fluid/density", c.density}});
        const double edge = stable_lambda_c(probe);
        const double up = std::min(1.0, edge + 0.1);  // the loader accepts lambda_c up to 1
        const double at_default = kinetic(0.4), at_edge = kinetic(edge), above = kinetic(up);
        std::printf("acoustic edge [%s, scale %g]: kinetic energy 0.3-%g s at lambda_c 0.4 %.4g J, at %.2g (the edge) "
                    "%.4g J (%.2fx), at %.2g %.4g J (%.1fx)\n",
                    c.density, c.scale, c.end, at_default, edge, at_edge, at_edge / at_default, up, above,
                    above / at_default);
        EXPECT_LE(at_edge, 1.5 * at_default) << c.density << ": the tank rings at the stable edge " << edge;
        EXPECT_GE(above, 3.0 * at_default) << c.density << ": the tank is quiet 0.1 above the edge " << edge;
    }
}
