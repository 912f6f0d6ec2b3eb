// Collapse of a water column against experiment: scenes/martin_moyce.json and
// scenes/koshizuka_oka.json, whose probes this test reads.
//
// Data (copied verbatim, with their provenance headers, from ../shared/validation to
// data/validation/):
//  * martin_moyce_1952_n2-2_front_table2.csv: surge front Z = x/a at T = t sqrt(2g/a) (Martin &
//    Moyce 1952, Table 2), a = 0.05715 m, column 2a high.
//  * martin_moyce_1952_n2-2_residual_height_table6.csv: residual height eta = h/(2a) at the back
//    wall at tau = t sqrt(g/a) (Table 6).
//  * koshizuka_oka_1996_front_exp_pysph.csv: front Z = x/L at T = t sqrt(2g/L) (Koshizuka & Oka
//    1996, digitised by the PySPH authors).
//
// Rules (data/validation/README.md): one constant time shift |dT| <= 0.2 is allowed (the lab
// gate did not open instantly); the front error is the RMS relative error of Z over the
// measured range. Martin & Moyce: <= 5 % over 0.8 <= T <= 3.3 at the default spacing a/12, in
// `global` and in every other adaptive mode the loader knows (individual stepping today), and
// at a/8 and a/18 in `global`; the residual height within +-0.05 in eta for tau <= 2.5,
// compared without a shift (the value with the front's shift, dtau = dT / sqrt 2, is printed).
//
// Where the residual height is asserted: at a/18 in every mode, not at a/12. The error sits at
// the last two table points (tau = 2.21, 2.45), where the column at the wall probe is ten
// layers high and the colour function's 0.5 level moves a layer at a time (2r / 2a = 0.042 in
// eta at a/12, 0.028 at a/18). Measured 2026-11-24 with tools/resolution_study.py (six runs per
// spacing, lambda_c spread over 0.36 ... 0.44; README, Validation): max |d eta| per run, median
// (range), 0.212 (0.109-0.287) at a/6, 0.041 (0.025-0.048) at a/8, 0.036 (0.027-0.053) at a/12,
// 0.016 (0.013-0.031) at a/18, 0.031 (0.031-0.033) at a/27; `individual` at a/12 ranged
// 0.030-0.068 with lambda_v perturbed by +-4 % and at a/18 0.013-0.022. At a/12 the bound is
// met or missed by chance in every mode; at a/18 it holds with margin. The resolution test
// asserts that fall (median over six runs at a/18 below that at a/8).
//
// The scene's walls are free-slip (fluid.boundary_viscosity 0) and its artificial viscosity
// alpha = 0.02: at the engine's default alpha = 0.1 the column is far too viscous at this size
// (nu ~ alpha h c_s / 10 = 1.7e-4 m^2/s; measured front error 8 %, the front too slow).
//
// What we measured and do not assert: the front error does not fall with resolution (medians
// over six runs 1.4 / 1.9 / 1.8 / 3.3 / 1.7 % at a/6 ... a/27). Its floor is set by the data
// and the model: with the shift free the error is 1.1-1.8 % at every spacing, and the
// simulated front leads the experiment by more as the numerical dissipation falls (best free
// shift +0.155 at a/6, +0.26 at a/18), which the bound |dT| <= 0.2 cannot absorb at a/18.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "engine/core/errors.hpp"
#include "validation/experiment.hpp"

using namespace sph;
using namespace sph::test;

namespace {

const std::string kScene = SPH_SOURCE_DIR "/scenes/martin_moyce.json";
const std::string kData = SPH_SOURCE_DIR "/data/validation/";
constexpr double kA = 0.05715, kG = 9.81;

struct MmErrors {
    ShiftedError front;
    double height_max_abs = 0, height_max_abs_shifted = 0;
    std::int64_t steps = 0;
    std::size_t particles = 0;
};

/// The colour front's error (the 0.5 level of the colour function on the floor), as `front`.
ShiftedError colour_front_error(const std::vector<std::pair<std::string, nlohmann::json>>& overrides) {
    const Scene scene = load_scene(kScene, overrides);
    const ProbeSet probes = run_with_probes(scene, nullptr);
    const Points front = dimensionless(probes.series("front_colour"), "front", std::sqrt(2 * kG / kA), 1 / kA);
    const Points exp = read_points(kData + "martin_moyce_1952_n2-2_front_table2.csv", "T", "Z");
    return front_error(front, exp, 0.8, 3.3, 0.2);
}

MmErrors martin_moyce(const std::vector<std::pair<std::string, nlohmann::json>>& overrides) {
    const Scene scene = load_scene(kScene, overrides);
    MmErrors e;
    const ProbeSet probes = run_with_probes(scene, &e.steps);
    e.particles = std::size_t(std::lround(scene.fluid_blocks[0].box.extent().prod() /
                                          std::pow(2 * scene.particle_radius(), 3)));
    const Points front = dimensionless(probes.series("front"), "front", std::sqrt(2 * kG / kA), 1 / kA);
    const Points exp = read_points(kData + "martin_moyce_1952_n2-2_front_table2.csv", "T", "Z");
    e.front = front_error(front, exp, 0.8, 3.3, 0.2);
    const Points height = dimensionless(probes.series("residual_height"), "height", std::sqrt(kG / kA), 1 / (2 * kA));
    const Points eta = read_points(kData + "martin_moyce_1952_n2-2_residual_height_table6.csv", "tau", "eta");
    e.height_max_abs = max_abs_error(height, eta, 2.5, 0.0);
    e.height_max_abs_shifted = max_abs_error(height, eta, 2.5, e.front.shift / std::sqrt(2.0));
    return e;
}

std::vector<std::string> modes() {
    std::vector<std::string> out;
    for (const auto& m : adaptive_modes()) {
        try {
            load_scene(kScene, {{"/simulation/stepping/mode", m}});
            out.push_back(m);
        } catch (const SceneError&) {  // a mode of another method
        }
    }
    return out;
}

}  // namespace

class MartinMoyce : public ::testing::TestWithParam<std::string> {};

// The front at the default spacing a/12; the residual height at a/18 (median of six runs),
// where one particle layer is 0.028 in eta against the bound 0.05 (at a/12 a layer is 0.042 and
// the value straddles the bound from run to run; see the header).
TEST_P(MartinMoyce, FrontAndResidualHeightMatchTheExperiment) {
    const MmErrors e = martin_moyce({{"/simulation/stepping/mode", GetParam()}});
    std::printf("martin_moyce [%s, a/12]: %zu particles, %lld steps: front RMS relative error %.2f %% (shift dT = "
                "%+.3f), residual height max |d eta| %.3f (tau <= 2.5; %.3f with the front's shift)\n",
                GetParam().c_str(), e.particles, static_cast<long long>(e.steps), 100 * e.front.rms_rel,
                e.front.shift, e.height_max_abs, e.height_max_abs_shifted);
    EXPECT_LE(e.front.rms_rel, 0.05);
    // The residual height at a/18: the median of six runs that differ only in rounding (the
    // store re-sorted every 13 ... 18 steps' worth of rows, so sums run in another order). One
    // run is a chaotic sample. At the scene's lambda_c 0.3 (2026-12-07, AVX-512) the six read
    // 0.013-0.036 in `global` (median 0.015), 0.015-0.018 in `binned` (0.015) and 0.016-0.036 in
    // `individual` (0.024; it ignores lambda_c), and 0.012-0.022 in `global` and `binned` with the
    // scalar loops (simulation.simd false). At lambda_c 0.4 `binned` read 0.041-0.094 (median
    // 0.052, over the bound) and 0.016-0.075 scalar: docs/results/validation.md.
    std::vector<double> eta;
    for (int sort_interval = 13; sort_interval <= 18; ++sort_interval) {
        const MmErrors fine = martin_moyce({{"/simulation/stepping/mode", GetParam()},
                                            {"/simulation/scale", 3.375},
                                            {"/simulation/sort_interval", sort_interval}});
        std::printf("martin_moyce [%s, a/18, sort interval %d]: %zu particles, %lld steps: front %.2f %% (dT = "
                    "%+.3f), residual height max |d eta| %.3f\n",
                    GetParam().c_str(), sort_interval, fine.particles, static_cast<long long>(fine.steps),
                    100 * fine.front.rms_rel, fine.front.shift, fine.height_max_abs);
        eta.push_back(fine.height_max_abs);
    }
    std::sort(eta.begin(), eta.end());
    EXPECT_LE(0.5 * (eta[2] + eta[3]), 0.05) << "median of the six a/18 runs";
}

INSTANTIATE_TEST_SUITE_P(AdaptiveModes, MartinMoyce, ::testing::ValuesIn(modes()),
                         [](const auto& info) { return info.param; });

// Spacing a/8, a/12 (default), a/18: scale = (n / 12)^3, `global`. The front error stays within
// 5 % at each (one run each). The residual height error falls with resolution: over six runs
// per spacing with the acoustic CFL coefficient spread over 0.36 ... 0.44 (the step sequence
// changes, the model does not; the engine's default 0.4 +- 10 %, in place of the scene's 0.3),
// the median of max |d eta| at a/18 is below that at a/8 and within 0.05. The median, not every
// run: one run's eta error is a chaotic sample that a change of rounding alone moves by up to
// three particle layers (0.022 to 0.078 in `global` at a/18 over sort intervals 13-18 on an AVX2
// machine, where these six read 0.012-0.024; docs/results/validation.md), as MartinMoyce.* above
// asserts it. Measured 2026-12-07 (AVX-512): a/8 median 0.045, a/18 0.021.
TEST(MartinMoyceResolution, FrontWithinFivePercentAndResidualHeightErrorFalls) {
    std::vector<double> median_eta;
    for (const double n : {8.0, 12.0, 18.0}) {
        const double scale = std::pow(n / 12.0, 3.0);
        const MmErrors e = martin_moyce({{"/simulation/scale", scale}});
        std::printf("martin_moyce [global, spacing a/%.0f]: %zu particles, %lld steps: front RMS relative error %.2f %% "
                    "(dT = %+.3f), residual height max |d eta| %.3f\n",
                    n, e.particles, static_cast<long long>(e.steps), 100 * e.front.rms_rel, e.front.shift,
                    e.height_max_abs);
        EXPECT_LE(e.front.rms_rel, 0.05) << "a/" << n;
        if (n == 12.0) continue;
        std::vector<double> eta;
        for (int k = 0; k < 6; ++k) {
            const double lambda_c = 0.36 + 0.08 * k / 5.0;
            eta.push_back(martin_moyce({{"/simulation/scale", scale}, {"/simulation/stepping/lambda_c", lambda_c}})
                              .height_max_abs);
        }
        std::sort(eta.begin(), eta.end());
        median_eta.push_back(0.5 * (eta[2] + eta[3]));
        std::printf("  a/%.0f, lambda_c 0.36 ... 0.44: max |d eta| %.3f %.3f %.3f %.3f %.3f %.3f, median %.3f\n", n,
                    eta[0], eta[1], eta[2], eta[3], eta[4], eta[5], median_eta.back());
        if (n == 18.0) {
            EXPECT_LE(median_eta.back(), 0.05) << "median of the six a/18 runs";
        }
    }
    EXPECT_LT(median_eta[1], median_eta[0]) << "median max |d eta|: a/18 against a/8";
}

// The continuity density with delta-SPH (fluid.density: continuity; the scene's alpha 0.02 and
// `global`): the colour front's RMS error falls with resolution and is below 1.5 % at a/12
// (issue 16). Median of three runs per spacing (lambda_c 0.36 / 0.40 / 0.44); the continuity
// runs agree to 0.03 % (docs/results/validation.md). Measured 2026-12-04 (density floored at
// 0.99 rho0; extrapolated walls, the continuity default): 1.57 / 1.26 / 1.03 %
// at a/8, a/12, a/18 (the summation density: 2.18 / 1.16 / 2.71 %). Held: a/12 below 1.5 %,
// a/12 below a/8, a/18 below 0.7 of a/8 (measured 0.66).
TEST(MartinMoyceContinuity, ColourFrontErrorFallsWithResolution) {
    std::vector<double> median;
    for (const double n : {8.0, 12.0, 18.0}) {
        std::vector<double> e;
        for (const double lambda_c : {0.36, 0.40, 0.44})
            e.push_back(colour_front_error({{"/simulation/scale", std::pow(n / 12.0, 3.0)},
                                            {"/simulation/stepping/lambda_c", lambda_c},
                                            {"/fluid/density", "continuity"}})
                            .rms_rel);
        std::sort(e.begin(), e.end());
        median.push_back(e[1]);
        std::printf("martin_moyce [continuity, a/%.0f]: colour front RMS relative error %.2f %% (runs %.2f %.2f %.2f)\n",
                    n, 100 * e[1], 100 * e[0], 100 * e[1], 100 * e[2]);
    }
    EXPECT_LT(median[1], 0.015) << "a/12";
    EXPECT_LT(median[1], median[0]) << "a/12 against a/8";
    EXPECT_LT(median[2], 0.7 * median[0]) << "a/18 against a/8";
}

// Koshizuka & Oka 1996. Tolerance 8 %: the data are digitised from a figure (no tabulated
// values; the PySPH authors' digitisation), the absolute size of the column is not stated in
// the sources (0.146 m is the usual quote; the comparison is dimensionless but viscous effects
// are not), and its early points (T < 1) sit within the gate's opening. See the measured
// figure printed below and in the README.
TEST(KoshizukaOka, FrontMatchesTheExperiment) {
    const Scene scene = load_scene(SPH_SOURCE_DIR "/scenes/koshizuka_oka.json");
    const ProbeSet probes = run_with_probes(scene);
    const double L = 0.146;
    const Points front = dimensionless(probes.series("front"), "front", std::sqrt(2 * kG / L), 1 / L);
    const Points exp = read_points(kData + "koshizuka_oka_1996_front_exp_pysph.csv", "T", "Z");
    const ShiftedError e = front_error(front, exp, 0.3, 3.1, 0.2);
    std::printf("koshizuka_oka [global]: front RMS relative error %.2f %% (shift dT = %+.3f) over 0.3 <= T <= 3.1\n",
                100 * e.rms_rel, e.shift);
    EXPECT_LE(e.rms_rel, 0.08);
}
