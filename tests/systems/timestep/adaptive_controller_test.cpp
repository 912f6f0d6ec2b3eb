// Ihmsen et al. 2010 sec. 3.3: each condition of eq. 16-23 and 25-27 in isolation. A "safe"
// state satisfies all of eq. 16-19 and none of eq. 20-23 / 25-27; each test moves one input
// across one threshold (by 1 % of the threshold, far above round-off) and checks that exactly
// the expected decision follows. Thresholds are computed here from the paper's constants.
#include <gtest/gtest.h>

#include <cmath>

#include "systems/timestep/adaptive_controller.hpp"

using namespace sph;

namespace {

constexpr double h = 0.04, eta = 0.01;

AdaptiveStepController controller() {
    AdaptiveParams p;
    p.h = h;
    p.eta_avg = eta;
    p.eta_max = 10 * eta;
    p.delta_shock = 4 * eta;
    p.dt_max = 1.0;  // out of the way
    return AdaptiveStepController(p);
}

// dt = 1 ms; v and F far below their limits, errors well below eta.
AdaptiveInputs safe() {
    AdaptiveInputs in;
    in.dt = 1e-3;
    in.v_max = 0.5 * 0.39 * h / in.dt;                              // eq. 19 holds with margin 2
    in.f_max = h / std::pow(in.dt / (0.5 * 0.19), 2);               // 0.19 sqrt(h/F) = 2 dt
    in.rho_err_avg = 0.5 * eta;
    in.rho_err_max = 2.0 * eta;
    in.prev_rho_err_max = 2.0 * eta;
    return in;
}

}  // namespace

TEST(AdaptiveController, SafeStateIncreasesByPointTwoPercent) {
    const auto c = controller();
    const AdaptiveInputs in = safe();
    EXPECT_TRUE(c.eq16(in) && c.eq17(in) && c.eq18(in) && c.eq19(in));
    EXPECT_FALSE(c.eq20(in) || c.eq21(in) || c.eq22(in) || c.eq23(in));
    EXPECT_FALSE(c.shock(in));
    const AdaptiveResult r = c.decide(in);
    EXPECT_EQ(r.decision, AdaptiveDecision::Increase);
    EXPECT_DOUBLE_EQ(r.dt, 1.002e-3);
}

// Each increase condition failing alone (while no decrease condition holds) keeps the step.
TEST(AdaptiveController, IncreaseNeedsEveryConditionOf16To19) {
    const auto c = controller();
    {  // eq. 16 fails: 0.19 sqrt(h/F) just below dt, but 0.2 sqrt(h/F) still above it (no eq. 20)
        AdaptiveInputs in = safe();
        in.f_max = h / std::pow(in.dt / 0.195, 2);
        EXPECT_FALSE(c.eq16(in));
        EXPECT_FALSE(c.eq20(in));
        EXPECT_EQ(c.decide(in).decision, AdaptiveDecision::Keep);
    }
    {  // eq. 17 fails: rho_err^max = 5 eta (between 4.5 and 5.5)
        AdaptiveInputs in = safe();
        in.rho_err_max = in.prev_rho_err_max = 5.0 * eta;
        EXPECT_FALSE(c.eq17(in));
        EXPECT_FALSE(c.eq21(in));
        EXPECT_EQ(c.decide(in).decision, AdaptiveDecision::Keep);
    }
    {  // eq. 18 fails: rho_err^avg = 0.95 eta (between 0.9 and 1)
        AdaptiveInputs in = safe();
        in.rho_err_avg = 0.95 * eta;
        EXPECT_FALSE(c.eq18(in));
        EXPECT_FALSE(c.eq22(in));
        EXPECT_EQ(c.decide(in).decision, AdaptiveDecision::Keep);
    }
    {  // eq. 19 fails: 0.39 h / v below dt, 0.4 h / v above it
        AdaptiveInputs in = safe();
        in.v_max = 0.395 * h / in.dt;
        EXPECT_FALSE(c.eq19(in));
        EXPECT_FALSE(c.eq23(in));
        EXPECT_EQ(c.decide(in).decision, AdaptiveDecision::Keep);
    }
}

// Each decrease condition holding alone decreases the step by 0.2 %.
TEST(AdaptiveController, AnyOf20To23Decreases) {
    const auto c = controller();
    auto expect_decrease = [&](const AdaptiveInputs& in) {
        EXPECT_FALSE(c.shock(in));
        const AdaptiveResult r = c.decide(in);
        EXPECT_EQ(r.decision, AdaptiveDecision::Decrease);
        EXPECT_DOUBLE_EQ(r.dt, 0.998e-3);
    };
    {
        AdaptiveInputs in = safe();
        in.f_max = h / std::pow(in.dt / 0.202, 2);  // 0.2 sqrt(h/F) = 0.99 dt
        EXPECT_TRUE(c.eq20(in));
        EXPECT_FALSE(c.eq21(in) || c.eq22(in) || c.eq23(in));
        expect_decrease(in);
    }
    {
        AdaptiveInputs in = safe();
        in.rho_err_max = in.prev_rho_err_max = 5.6 * eta;
        EXPECT_TRUE(c.eq21(in));
        EXPECT_FALSE(c.eq20(in) || c.eq22(in) || c.eq23(in));
        expect_decrease(in);
    }
    {
        AdaptiveInputs in = safe();
        in.rho_err_avg = eta;  // eq. 22 is ">=": equality decreases
        EXPECT_TRUE(c.eq22(in));
        EXPECT_FALSE(c.eq20(in) || c.eq21(in) || c.eq23(in));
        expect_decrease(in);
    }
    {
        AdaptiveInputs in = safe();
        in.v_max = 0.4 * h / in.dt;  // eq. 23 is "<=": equality decreases (and eq. 27 does not hold)
        EXPECT_TRUE(c.eq23(in));
        EXPECT_FALSE(c.eq20(in) || c.eq21(in) || c.eq22(in));
        expect_decrease(in);
    }
}

// Shock conditions (eq. 25-27), each alone, and the step of eq. 24.
TEST(AdaptiveController, ShocksAndTheStepOfEq24) {
    const auto c = controller();
    {  // eq. 25: rho_err^max jumps by more than delta_shock = 4 eta (stays below eta_max)
        AdaptiveInputs in = safe();
        in.prev_rho_err_max = 1.0 * eta;
        in.rho_err_max = 5.1 * eta;
        EXPECT_TRUE(c.eq25(in));
        EXPECT_FALSE(c.eq26(in) || c.eq27(in));
        EXPECT_EQ(c.decide(in).decision, AdaptiveDecision::Shock);
        in.prev_rho_err_max = -1;  // first step: no previous value, no eq. 25
        EXPECT_FALSE(c.eq25(in));
    }
    {  // eq. 26: rho_err^max above eta_max = 10 eta, without a jump
        AdaptiveInputs in = safe();
        in.rho_err_max = in.prev_rho_err_max = 10.1 * eta;
        EXPECT_TRUE(c.eq26(in));
        EXPECT_FALSE(c.eq25(in) || c.eq27(in));
        EXPECT_EQ(c.decide(in).decision, AdaptiveDecision::Shock);
    }
    {  // eq. 27: 0.45 h / v < dt. Resume with eq. 24: min(0.2 sqrt(h/F), 0.25 h/v).
        AdaptiveInputs in = safe();
        in.v_max = 0.46 * h / in.dt;
        EXPECT_TRUE(c.eq27(in));
        EXPECT_FALSE(c.eq25(in) || c.eq26(in));
        const AdaptiveResult r = c.decide(in);
        EXPECT_EQ(r.decision, AdaptiveDecision::Shock);
        const double expected = std::min(0.2 * std::sqrt(h / in.f_max), 0.25 * h / in.v_max);
        EXPECT_DOUBLE_EQ(r.dt, expected);
        EXPECT_DOUBLE_EQ(expected, 0.25 * h / in.v_max);  // the velocity term binds here
    }
}

TEST(AdaptiveController, InitialStep) {
    const auto c = controller();
    EXPECT_DOUBLE_EQ(c.initial_dt(2.0, 9.81, 0.5), 0.25 * h / 2.0);
    // v0_max = 0: the speed of a fall through the fluid height H, sqrt(2 g H).
    EXPECT_DOUBLE_EQ(c.initial_dt(0.0, 9.81, 0.5), 0.25 * h / std::sqrt(2 * 9.81 * 0.5));
    EXPECT_DOUBLE_EQ(c.initial_dt(0.0, 0.0, 0.5), 1.0);  // nothing moves or falls: dt_max
}
