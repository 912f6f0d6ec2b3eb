// The globally adaptive step of He et al. eq. 6-8 (systems/timestep/global_dt_system.hpp):
//   eq. 6  dt_v = lambda_v h / v_max                (CFL)
//   eq. 7  dt_f = lambda_f sqrt(h / a_max)          (force)
//   eq. 8  dt   = min(dt_v, dt_f)
// plus our acoustic option dt_c = lambda_c h / (c_s + v_max) and the cap dt_max. Every expected
// value is worked out by hand in the comment next to it, never with global_time_step itself.
// Each branch wins once, first through global_time_step, then through GlobalDtSystem on a World
// (w.stats in, w.step_size out), including the whole-tick quantisation and the clipping of the
// last step to clock.t_stop.
#include <gtest/gtest.h>

#include <cmath>

#include "engine/data/world.hpp"
#include "engine/graph/system.hpp"
#include "systems/timestep/global_dt_system.hpp"

using namespace sph;

namespace {

// h = 0.04 m, c_s = 20 m/s for every case below.
constexpr double kH = 0.04, kCs = 20.0;

// lambda_v = 0.1, lambda_f = 0.05 (He's values, our defaults), lambda_c = 0.4, dt_max = 5 ms.
SteppingParams params(bool acoustic) {
    SteppingParams p;
    p.lambda_v = 0.1;
    p.lambda_f = 0.05;
    p.acoustic = acoustic;
    p.lambda_c = 0.4;
    p.dt_max = 5e-3;
    return p;
}

// The hand values (each a handful of double operations, so EXPECT_DOUBLE_EQ, 4 ulp, holds for
// the function; a wrong branch or coefficient moves the result by > 10 %).
//
// Force wins: v = 2 m/s, a = 50 m/s^2, no acoustic condition.
//   eq. 6: 0.1 * 0.04 / 2 = 0.002 s
//   eq. 7: 0.05 * sqrt(0.04 / 50) = 0.05 * sqrt(8e-4) = 0.05 * 0.0282842712 = 0.00141421356 s
//          (= sqrt(2) * 1e-3 s exactly)
//   eq. 8: min = 0.00141421356 s
constexpr double kForceDt = 1.4142135623730951e-3;
// CFL wins: v = 2 m/s, a = 5 m/s^2, no acoustic condition.
//   eq. 6: 0.1 * 0.04 / 2 = 0.002 s
//   eq. 7: 0.05 * sqrt(0.04 / 5) = 0.05 * sqrt(0.008) = 0.05 * 0.0894427191 = 0.00447213595 s
//   eq. 8: min = 0.002 s (below dt_max = 0.005 s)
constexpr double kCflDt = 2e-3;
// Acoustic wins: v = 2 m/s, a = 5 m/s^2, acoustic on, c_s = 20 m/s.
//   eq. 6, 7 as above: 0.002 s, 0.00447 s
//   acoustic: 0.4 * 0.04 / (20 + 2) = 0.016 / 22 = 0.000727272727 s
constexpr double kAcousticDt = 0.016 / 22.0;
// dt_max wins: v = 0.1 m/s, a = 0.5 m/s^2, no acoustic condition.
//   eq. 6: 0.1 * 0.04 / 0.1 = 0.04 s
//   eq. 7: 0.05 * sqrt(0.04 / 0.5) = 0.05 * sqrt(0.08) = 0.05 * 0.282842712 = 0.0141421356 s
//   cap:   0.005 s
constexpr double kCapDt = 5e-3;
// Nothing moves, nothing accelerates (v = a = 0): eq. 6 and 7 impose nothing.
//   no acoustic: dt_max = 0.005 s
//   acoustic:    0.4 * 0.04 / (20 + 0) = 0.0008 s
constexpr double kRestAcousticDt = 8e-4;

}  // namespace

TEST(GlobalTimeStep, ForceConditionEq7Wins) {
    EXPECT_DOUBLE_EQ(global_time_step(params(false), kH, kCs, 2.0, 50.0), kForceDt);
    EXPECT_NEAR(kForceDt, 0.00141421356, 1e-11);  // the decimal of the comment
}

TEST(GlobalTimeStep, CflConditionEq6Wins) {
    EXPECT_DOUBLE_EQ(global_time_step(params(false), kH, kCs, 2.0, 5.0), kCflDt);
}

TEST(GlobalTimeStep, AcousticConditionWins) {
    EXPECT_DOUBLE_EQ(global_time_step(params(true), kH, kCs, 2.0, 5.0), kAcousticDt);
    EXPECT_NEAR(kAcousticDt, 0.000727272727, 1e-12);
    // The same state without the option falls back to eq. 6.
    EXPECT_DOUBLE_EQ(global_time_step(params(false), kH, kCs, 2.0, 5.0), kCflDt);
}

// Viscous limit wins (Morris et al. 1997 eq. 12): nu = 0.1 m^2/s, v = 2 m/s, a = 5 m/s^2.
//   eq. 6, 7 as above: 0.002 s, 0.00447 s
//   viscous: 0.125 * (0.04 / 2)^2 / 0.1 = 0.125 * 4e-4 / 0.1 = 5e-4 s
// and with nu = 0 the CFL's 0.002 s again.
TEST(GlobalTimeStep, ViscousLimitWinsWithALaminarViscosity) {
    EXPECT_DOUBLE_EQ(global_time_step(params(false), kH, kCs, 2.0, 5.0, 0.1), 5e-4);
    EXPECT_DOUBLE_EQ(global_time_step(params(false), kH, kCs, 2.0, 5.0, 0.0), kCflDt);
}

TEST(GlobalTimeStep, DtMaxCapWins) {
    EXPECT_DOUBLE_EQ(global_time_step(params(false), kH, kCs, 0.1, 0.5), kCapDt);
    // A larger cap lets eq. 7 through: 0.0141421356 s.
    SteppingParams p = params(false);
    p.dt_max = 1.0;
    EXPECT_DOUBLE_EQ(global_time_step(p, kH, kCs, 0.1, 0.5), 1.4142135623730951e-2);
}

TEST(GlobalTimeStep, RestStateGivesDtMaxOrAcoustic) {
    // No division by zero: v = a = 0 gives dt_max exactly (and a finite number).
    EXPECT_DOUBLE_EQ(global_time_step(params(false), kH, kCs, 0.0, 0.0), kCapDt);
    EXPECT_DOUBLE_EQ(global_time_step(params(true), kH, kCs, 0.0, 0.0), kRestAcousticDt);
    // Only one of the two zero: the other condition still applies (eq. 7 alone: 0.00141 s;
    // eq. 6 alone: 0.002 s).
    EXPECT_DOUBLE_EQ(global_time_step(params(false), kH, kCs, 0.0, 50.0), kForceDt);
    EXPECT_DOUBLE_EQ(global_time_step(params(false), kH, kCs, 2.0, 0.0), kCflDt);
}

namespace {

// A World with only what GlobalDtSystem reads: physics.h, physics.speed_of_sound, res::stats
// and the clock. h is stored as Real: 0.04f = 0.04 (1 - 2.2e-8), so dt_stable matches the hand
// values to 3e-8 relative (eq. 6 and the acoustic bound scale as h, eq. 7 as sqrt(h); with
// SPH_DOUBLE the match is to round-off). c_s = 20 is exact in float.
struct DtWorld {
    World w;
    DtWorld(double v_max, double a_max) {
        w.physics.h = Real(kH);
        w.physics.speed_of_sound = Real(kCs);
        w.stats.v_max = v_max;
        w.stats.a_max = a_max;
    }
    void run(bool acoustic) {
        GlobalDtSystem sys(params(acoustic));
        run_system(sys, w);
    }
};
constexpr double kFloatRel = 3e-8;

// The step is dt_stable quantised down to whole ticks (1 tick = 1e-12 s): dt = dt_ticks * 1e-12,
// dt <= dt_stable < dt + 1 tick.
void expect_quantised(const StepSize& s) {
    EXPECT_EQ(s.dt_ticks, std::int64_t(std::floor(s.dt_stable / 1e-12)));
    EXPECT_EQ(s.dt, double(s.dt_ticks) * 1e-12);
    EXPECT_LE(s.dt, s.dt_stable);
    EXPECT_GT(s.dt + 1e-12, s.dt_stable);
}

}  // namespace

TEST(GlobalDtSystem, EachBranchWinsOnAWorld) {
    struct Case {
        const char* name;
        double v, a;
        bool acoustic;
        double expected;  // hand value from the table above
        std::int64_t ticks_lo, ticks_hi;  // dt_ticks, allowing for the float h (3e-8 relative)
    };
    const Case cases[] = {
        {"force (eq. 7)", 2.0, 50.0, false, kForceDt, 1'414'213'500, 1'414'213'563},
        {"CFL (eq. 6)", 2.0, 5.0, false, kCflDt, 1'999'999'900, 2'000'000'000},
        {"acoustic", 2.0, 5.0, true, kAcousticDt, 727'272'700, 727'272'728},
        {"dt_max", 0.1, 0.5, false, kCapDt, 5'000'000'000, 5'000'000'000},  // the cap is exact
        {"rest, no acoustic", 0.0, 0.0, false, kCapDt, 5'000'000'000, 5'000'000'000},
        {"rest, acoustic", 0.0, 0.0, true, kRestAcousticDt, 799'999'900, 800'000'000},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        DtWorld d(c.v, c.a);
        d.run(c.acoustic);
        const StepSize& s = d.w.step_size;
        EXPECT_NEAR(s.dt_stable, c.expected, kFloatRel * c.expected);
        expect_quantised(s);
        EXPECT_GE(s.dt_ticks, c.ticks_lo);
        EXPECT_LE(s.dt_ticks, c.ticks_hi);
    }
}

// The step comes from res::stats alone: the previous step (1 s here) and the density error do
// not enter (He eq. 6-8 have neither).
TEST(GlobalDtSystem, OldStepDoesNotCarryOver) {
    DtWorld d(2.0, 50.0);
    d.w.step_size.set(1.0);
    d.w.step_size.dt_stable = 1.0;
    d.w.stats.rho_err_max = 0.5;
    d.run(false);
    EXPECT_NEAR(d.w.step_size.dt_stable, kForceDt, kFloatRel * kForceDt);
    EXPECT_LT(d.w.step_size.dt, 1.5e-3);
}

// The last step of a run ends exactly on clock.t_stop, in ticks, while dt_stable keeps the
// unclipped step. Clock at t = 1 ms (10^9 ticks); CFL step 0.002 s (hand value above).
TEST(GlobalDtSystem, LastStepIsClippedToEndExactlyAtTStop) {
    {  // t_stop = 1.0005 ms: 0.5 us = 500,000 ticks remain, less than the 2 ms step.
        DtWorld d(2.0, 5.0);
        d.w.clock.t_ticks = 1'000'000'000;
        d.w.clock.t = 1e-3;
        d.w.clock.t_stop = 1.0005e-3;
        d.run(false);
        const StepSize& s = d.w.step_size;
        EXPECT_EQ(s.dt_ticks, 500'000);
        EXPECT_EQ(d.w.clock.t_ticks + s.dt_ticks, 1'000'500'000);  // ends on t_stop, in ticks
        EXPECT_EQ(s.dt, 5e-7);
        EXPECT_NEAR(s.dt_stable, kCflDt, kFloatRel * kCflDt);  // not clipped
    }
    {  // t_stop = 0.1 s, t = 0.1 s - 1234 ticks: a t_stop that is not a whole number of seconds
       // in binary still ends on its tick, 10^11.
        DtWorld d(2.0, 5.0);
        d.w.clock.t_ticks = 100'000'000'000 - 1234;
        d.w.clock.t = to_seconds(d.w.clock.t_ticks);
        d.w.clock.t_stop = 0.1;
        d.run(false);
        EXPECT_EQ(d.w.step_size.dt_ticks, 1234);
        EXPECT_EQ(d.w.clock.t_ticks + d.w.step_size.dt_ticks, 100'000'000'000);
    }
    {  // t_stop 3 ms ahead: more than one step remains, nothing is clipped.
        DtWorld d(2.0, 5.0);
        d.w.clock.t_ticks = 1'000'000'000;
        d.w.clock.t = 1e-3;
        d.w.clock.t_stop = 4e-3;
        d.run(false);
        EXPECT_EQ(d.w.step_size.dt_ticks, to_ticks(d.w.step_size.dt_stable));
        EXPECT_GT(d.w.step_size.dt_ticks, 1'999'999'900);
    }
    {  // Exactly one step remains (t_stop = t + 5 ms with the 5 ms cap): it is taken whole.
        DtWorld d(0.0, 0.0);
        d.w.clock.t_ticks = 1'000'000'000;
        d.w.clock.t = 1e-3;
        d.w.clock.t_stop = 6e-3;
        d.run(false);
        EXPECT_EQ(d.w.step_size.dt_ticks, 5'000'000'000);
        EXPECT_EQ(d.w.clock.t_ticks + d.w.step_size.dt_ticks, 6'000'000'000);
    }
}
