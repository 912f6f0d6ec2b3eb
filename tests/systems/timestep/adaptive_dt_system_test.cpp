// AdaptiveDtSystem (Ihmsen et al. 2010 sec. 3.3; systems/timestep/adaptive_dt_system.hpp) on a
// World: the controller resource registered as the PCISPH recipe does
// (PcisphStepSizeSystem::register_components), w.stats and w.step_size set by hand, the system
// run once. The decision rules themselves are tested condition by condition in
// adaptive_controller_test.cpp; here the system's wiring is pinned with numbers worked out by
// hand: which step it feeds in (dt_stable, not the clipped dt), what it writes to the controller
// (pending_dt, prev_err_max, the tracked maxima of eq. 14-15) and to res::rollback.
//
// Scene defaults throughout: eta = 0.01, so eta_max = 10 eta = 0.1 and delta_shock = 4 eta =
// 0.04 (adaptive_params), dt_max = 5e-3 s; h = 0.04 m; the step just taken is dt = 1 ms.
#include <gtest/gtest.h>

#include <cmath>

#include "engine/core/resources.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/system.hpp"
#include "systems/pcisph/pcisph_state.hpp"
#include "systems/timestep/adaptive_dt_system.hpp"

using namespace sph;

namespace {

// The quiet state: every increase condition holds, no decrease or shock condition does.
//   eq. 16: 0.19 sqrt(h / F) = 0.19 sqrt(0.04 / 9.81) = 0.19 * 0.0639 = 0.0121 s > 1e-3 s
//   eq. 17: rho_err_max = 0.02  < 4.5 eta = 0.045
//   eq. 18: rho_err_avg = 0.005 < 0.9 eta = 0.009
//   eq. 19: 0.39 h / v = 0.39 * 0.04 / 0.5 = 0.0312 s > 1e-3 s
//   eq. 20-23: 0.0128 s > dt; 0.02 < 0.055; 0.005 < 0.01; 0.032 s > dt: none holds
//   eq. 25-27: jump 0.02 - 0.02 = 0 < 0.04; 0.02 < 0.1; 0.036 s > dt: none holds
struct AdaptiveWorld {
    World w;
    PcisphController* pc = nullptr;
    AdaptiveWorld() {
        w.physics.h = Real(0.04);
        w.physics.spacing = Real(0.02);  // Ihmsen's h = 2 r0 = 0.04 m (adaptive_controller.hpp)
        pc = &w.resources.add<PcisphController>(res::pcisph_controller.name, Lifetime::Kept);
        pc->pending_dt = 1e-3;
        pc->prev_err_max = 0.02;
        w.step_size.set(1e-3);
        w.step_size.dt_stable = 1e-3;
        w.stats.v_max = 0.5;
        w.stats.a_max = 9.81;
        w.stats.rho_err_avg = 0.005;
        w.stats.rho_err_max = 0.02;
    }
    void run() {
        Scene scene;  // defaults: eta 0.01, dt_max 5e-3
        AdaptiveDtSystem sys(adaptive_params(scene));
        run_system(sys, w);
    }
};

// h is stored as Real: 0.04f = 0.04 (1 - 2.2e-8). The +-0.2 % results do not involve h and are
// a single double multiplication (DOUBLE_EQ, 4 ulp); results of eq. 24 scale with h: 3e-8.
constexpr double kFloatRel = 3e-8;

}  // namespace

TEST(AdaptiveDtSystem, SceneDefaultsGiveThePapersThresholds) {
    Scene scene;
    const AdaptiveParams p = adaptive_params(scene);
    EXPECT_EQ(p.eta_avg, 0.01);
    EXPECT_DOUBLE_EQ(p.eta_max, 0.1);       // sec. 3.3: 10 eta_avg
    EXPECT_DOUBLE_EQ(p.delta_shock, 0.04);  // our default 4 eta_avg, inside (eta_avg, eta_max)
    EXPECT_EQ(p.dt_max, 5e-3);
    EXPECT_EQ(p.change, 0.002);
}

// (a) eq. 16-19 all hold: pending_dt = 1e-3 * 1.002 = 1.002e-3 s; prev_err_max and the tracked
// maxima take this step's values; no rollback.
TEST(AdaptiveDtSystem, QuietStepIncreasesByPointTwoPercent) {
    AdaptiveWorld a;
    a.run();
    EXPECT_DOUBLE_EQ(a.pc->pending_dt, 1.002e-3);
    EXPECT_EQ(a.pc->reason, int(AdaptiveDecision::Increase));
    EXPECT_EQ(a.pc->prev_err_max, 0.02);
    EXPECT_EQ(a.pc->v_max_tracked, 0.5);
    EXPECT_EQ(a.pc->a_max_tracked, 9.81);
    EXPECT_EQ(a.pc->rho_err_avg_max, 0.005);
    EXPECT_EQ(a.w.rollback.request_dt, 0.0);
    EXPECT_TRUE(a.w.rollback.requested_by.empty());
    // Repeated quiet steps compound: 1e-3 * 1.002^2 = 1.004004e-3 s (two double products:
    // 1e-17 s is ~40 ulp of 1e-3 s).
    a.w.step_size.set(a.pc->pending_dt);
    a.w.step_size.dt_stable = a.pc->pending_dt;
    a.run();
    EXPECT_NEAR(a.pc->pending_dt, 1.004004e-3, 1e-17);
}

// (a') Near dt_max the increase is capped: dt = 4.999e-3 s -> min(4.999e-3 * 1.002, 5e-3) = 5e-3 s
// (eq. 16 and 19 still hold: 0.0121 s and 0.0312 s > 5 ms).
TEST(AdaptiveDtSystem, IncreaseIsCappedAtDtMax) {
    AdaptiveWorld a;
    a.w.step_size.set(4.999e-3);
    a.w.step_size.dt_stable = 4.999e-3;
    a.run();
    EXPECT_EQ(a.pc->reason, int(AdaptiveDecision::Increase));
    EXPECT_EQ(a.pc->pending_dt, 5e-3);
}

// (b) A large error decreases the step by 0.2 %: 1e-3 * 0.998 = 0.998e-3 s, through eq. 22
// (rho_err_avg = 0.012 >= eta = 0.01) and, separately, through eq. 21 (rho_err_max = 0.06 >
// 5.5 eta = 0.055, below eta_max = 0.1 and only 0.03 above the last step's 0.03, so no shock).
TEST(AdaptiveDtSystem, LargeErrorDecreasesByPointTwoPercent) {
    {
        AdaptiveWorld a;
        a.w.stats.rho_err_avg = 0.012;
        a.w.stats.rho_err_max = 0.03;
        a.run();
        EXPECT_EQ(a.pc->reason, int(AdaptiveDecision::Decrease));
        EXPECT_DOUBLE_EQ(a.pc->pending_dt, 0.998e-3);
        EXPECT_EQ(a.pc->prev_err_max, 0.03);
        EXPECT_EQ(a.pc->rho_err_avg_max, 0.012);
        EXPECT_EQ(a.w.rollback.request_dt, 0.0);
    }
    {
        AdaptiveWorld a;
        a.pc->prev_err_max = 0.03;
        a.w.stats.rho_err_max = 0.06;
        a.run();
        EXPECT_EQ(a.pc->reason, int(AdaptiveDecision::Decrease));
        EXPECT_DOUBLE_EQ(a.pc->pending_dt, 0.998e-3);
        EXPECT_EQ(a.pc->prev_err_max, 0.06);
        EXPECT_EQ(a.w.rollback.request_dt, 0.0);
    }
}

// (c) A shock (eq. 25-27) requests a rollback and leaves the controller's step and
// prev_err_max as they were (the step is discarded; the engine hands the new step back through
// rollback.resume_dt). The requested step:
//   eq. 26 (rho_err_max = 0.12 > eta_max = 0.1), v = 0.5, F = 9.81: eq. 24 gives
//     min(0.2 sqrt(0.04 / 9.81), 0.25 * 0.04 / 0.5, dt_max) = min(0.0128, 0.02, 0.005) = 5e-3 s,
//     not below dt = 1e-3 s, so the step is halved (our rule): 5e-4 s;
//   eq. 27 (0.45 h / v = 0.45 * 0.04 / 20 = 9e-4 s < 1e-3 s), v = 20 m/s: eq. 24 gives
//     0.25 * 0.04 / 20 = 5e-4 s;
//   eq. 25 (jump 0.055 - 0.01 = 0.045 > 0.04) after a 2 ms step, v = 8 m/s (eq. 27: 0.45 * 0.04
//     / 8 = 2.25e-3 s > 2e-3 s, no): eq. 24 gives 0.25 * 0.04 / 8 = 1.25e-3 s.
TEST(AdaptiveDtSystem, ShockRequestsRollbackAndKeepsPendingDt) {
    struct Case {
        const char* name;
        double dt, v, err_max, prev, request;
        double rel;  // tolerance on the request (see kFloatRel)
    };
    const Case cases[] = {
        {"eq. 26, halved", 1e-3, 0.5, 0.12, 0.02, 5e-4, 1e-15},
        {"eq. 27, eq. 24", 1e-3, 20.0, 0.02, 0.02, 5e-4, kFloatRel},
        {"eq. 25, eq. 24", 2e-3, 8.0, 0.055, 0.01, 1.25e-3, kFloatRel},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        AdaptiveWorld a;
        a.pc->prev_err_max = c.prev;
        a.pc->v_max_tracked = 0.25;
        a.w.step_size.set(c.dt);
        a.w.step_size.dt_stable = c.dt;
        a.w.stats.v_max = c.v;
        a.w.stats.rho_err_max = c.err_max;
        a.run();
        EXPECT_EQ(a.pc->reason, int(AdaptiveDecision::Shock));
        EXPECT_GT(a.w.rollback.request_dt, 0.0);
        EXPECT_NEAR(a.w.rollback.request_dt, c.request, c.rel * c.request);
        EXPECT_EQ(a.w.rollback.requested_by, "adaptive_dt");
        EXPECT_FALSE(a.w.rollback.reason.empty());
        EXPECT_EQ(a.pc->pending_dt, 1e-3);         // unchanged
        EXPECT_EQ(a.pc->prev_err_max, c.prev);     // unchanged: the step is discarded
        EXPECT_EQ(a.pc->v_max_tracked, 0.25);      // a discarded step is not tracked
    }
}

// The first step has no rho_err^max(t - dt) (prev_err_max < 0): eq. 25 cannot fire, however
// large the error is below eta_max. rho_err_max = 0.08 > 5.5 eta: a decrease (eq. 21), 0.998e-3 s.
TEST(AdaptiveDtSystem, FirstStepHasNoJumpCondition) {
    AdaptiveWorld a;
    a.pc->prev_err_max = -1;
    a.w.stats.rho_err_max = 0.08;
    a.run();
    EXPECT_EQ(a.pc->reason, int(AdaptiveDecision::Decrease));
    EXPECT_DOUBLE_EQ(a.pc->pending_dt, 0.998e-3);
    EXPECT_EQ(a.w.rollback.request_dt, 0.0);
    EXPECT_EQ(a.pc->prev_err_max, 0.08);
}

// A last step clipped to the end time (dt = 0.1 ms, dt_stable = 1 ms) is not a decision about
// the flow: the rule is applied to dt_stable (pending = 1.002e-3 s, not 1.002e-4 s), and the
// tracked maxima of eq. 14-15 skip it.
TEST(AdaptiveDtSystem, ClippedLastStepUsesStableStepAndIsNotTracked) {
    AdaptiveWorld a;
    a.w.step_size.set(1e-4);
    a.w.step_size.dt_stable = 1e-3;
    a.w.stats.a_max = 50.0;  // eq. 16: 0.19 sqrt(0.04 / 50) = 5.4e-3 s > 1e-3 s, still quiet
    a.run();
    EXPECT_EQ(a.pc->reason, int(AdaptiveDecision::Increase));
    EXPECT_DOUBLE_EQ(a.pc->pending_dt, 1.002e-3);
    EXPECT_EQ(a.pc->v_max_tracked, 0.0);
    EXPECT_EQ(a.pc->a_max_tracked, 0.0);
    EXPECT_EQ(a.pc->rho_err_avg_max, 0.0);
}
