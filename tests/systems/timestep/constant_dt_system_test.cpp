// `constant` stepping (He et al. Alg. 1 with a fixed step; systems/timestep/constant_dt_system.hpp):
// ConstantDtSystem gives the scene's dt every step, quantised down to whole ticks
// (1 tick = 1e-12 s, engine/data/world.hpp), at least one tick, and clips the last step so that
// the run ends exactly on clock.t_stop. Every expected tick count is worked out by hand in the
// comment beside it; ticks are integers, so every comparison is exact.
#include <gtest/gtest.h>

#include <vector>

#include "engine/data/world.hpp"
#include "engine/graph/system.hpp"
#include "systems/methods/recipes.hpp"
#include "systems/methods/wcsph.hpp"
#include "systems/timestep/constant_dt_system.hpp"
#include "test_scenes.hpp"

using namespace sph;

namespace {

// Runs the system once per step, advancing the clock as Simulation does (t += dt in ticks),
// until t_stop is reached; returns the tick count of every step.
std::vector<Tick> steps_until(double dt, double t_stop, Tick t0 = 0) {
    World w;
    w.clock.t_ticks = t0;
    w.clock.t = to_seconds(t0);
    w.clock.t_stop = t_stop;
    ConstantDtSystem sys(dt);
    std::vector<Tick> out;
    const Tick end = to_ticks(t_stop + 0.5e-12);
    while (w.clock.t_ticks < end && out.size() < 1000) {
        run_system(sys, w);
        EXPECT_EQ(w.step_size.dt_stable, dt) << "dt_stable is the scene's dt, unclipped";
        EXPECT_EQ(w.step_size.dt, to_seconds(w.step_size.dt_ticks));
        out.push_back(w.step_size.dt_ticks);
        w.clock.t_ticks += w.step_size.dt_ticks;
        w.clock.t = to_seconds(w.clock.t_ticks);
        ++w.clock.step;
    }
    EXPECT_EQ(w.clock.t_ticks, end) << "the run must end exactly on t_stop";
    return out;
}

}  // namespace

// 4e-4 s = 400,000,000 ticks exactly, every step, whatever the state of the clock.
TEST(ConstantDtSystem, GivesTheScenesDtEveryStep) {
    World w;
    ConstantDtSystem sys(4e-4);
    for (int k = 0; k < 5; ++k) {
        w.clock.t_ticks = Tick(k) * 400'000'000;
        w.clock.t = to_seconds(w.clock.t_ticks);
        w.clock.step = k;
        run_system(sys, w);
        EXPECT_EQ(w.step_size.dt_ticks, 400'000'000) << "step " << k;
        // In seconds dt = ticks * 1e-12, one rounding (4e8 * 1e-12 is 1 ulp off 4e-4): DOUBLE_EQ.
        EXPECT_DOUBLE_EQ(w.step_size.dt, 4e-4) << "step " << k;
        EXPECT_EQ(w.step_size.dt_stable, 4e-4) << "step " << k;
    }
}

// A dt that is not a whole number of ticks is rounded down (a step never grows by
// quantisation): 2.5e-4 s + 0.7 tick -> 250,000,000 ticks; 1e-4 s - 0.4 tick -> 99,999,999 ticks.
// Below one tick it is one tick (a zero step would never advance).
TEST(ConstantDtSystem, QuantisesDownToWholeTicks) {
    struct Case {
        double dt;
        Tick ticks;
    };
    for (const Case c : {Case{2.5e-4 + 0.7e-12, 250'000'000}, Case{1e-4 - 0.4e-12, 99'999'999}, Case{0.3e-12, 1},
                         Case{3e-12, 3}}) {
        World w;
        run_system(ConstantDtSystem(c.dt), w);
        EXPECT_EQ(w.step_size.dt_ticks, c.ticks) << "dt " << c.dt;
        EXPECT_EQ(w.step_size.dt, double(c.ticks) * 1e-12) << "dt " << c.dt;
        EXPECT_EQ(w.step_size.dt_stable, c.dt) << "dt " << c.dt;
    }
}

// The last step is clipped so that the run ends exactly on t_stop:
//   dt = 3e-4 s to t_stop = 1e-3 s: 3 x 300,000,000 ticks, then 1e-3 - 9e-4 = 100,000,000 ticks;
//   dt = 4e-4 s to t_stop = 1e-3 s: 2 x 400,000,000 ticks, then 200,000,000 ticks;
//   dt = 2.5e-4 s to t_stop = 1e-3 s: exactly 4 steps, none clipped;
//   dt = 1e-3 s from t = 0.25 ms to t_stop = 0.3 ms: one step of 50,000,000 ticks.
TEST(ConstantDtSystem, LastStepEndsExactlyAtTStop) {
    EXPECT_EQ(steps_until(3e-4, 1e-3), (std::vector<Tick>{300'000'000, 300'000'000, 300'000'000, 100'000'000}));
    EXPECT_EQ(steps_until(4e-4, 1e-3), (std::vector<Tick>{400'000'000, 400'000'000, 200'000'000}));
    EXPECT_EQ(steps_until(2.5e-4, 1e-3), (std::vector<Tick>(4, 250'000'000)));
    EXPECT_EQ(steps_until(1e-3, 3e-4, 250'000'000), (std::vector<Tick>{50'000'000}));
}

// The same through a whole `constant` run (no fluid, so the step is the only thing that
// happens): 0.1 s at 3e-4 s is 333 steps of 300,000,000 ticks (99,900,000,000) and one of
// 100,000,000 ticks; the run ends at 10^11 ticks exactly.
TEST(ConstantDtSystem, RunEndsExactlyAtEndTime) {
    Scene s = test::tank_scene(Vec3d(0.02, 0.02, 0.02), Vec3d(0.2, 0.2, 0.2));
    s.fluid_blocks.clear();
    s.simulation.stepping.mode = SteppingMode::Constant;
    s.simulation.stepping.dt = 3e-4;
    // No fluid, so only the clock is tested: past make_simulation, whose validate_scene refuses a
    // scene that simulates nothing.
    auto sim = std::make_unique<Simulation>(s, make_wcsph_recipe(s));
    std::vector<Tick> ticks;
    sim->run_until(0.1, [&](const Simulation& sm) { ticks.push_back(sm.world().step_size.dt_ticks); });
    ASSERT_EQ(ticks.size(), 334u);
    for (std::size_t k = 0; k < 333; ++k) ASSERT_EQ(ticks[k], 300'000'000) << "step " << k;
    EXPECT_EQ(ticks[333], 100'000'000);
    EXPECT_EQ(sim->world().clock.t_ticks, 100'000'000'000);
    // In seconds: 10^11 * 1e-12 is one double ulp (1.4e-17 s) below 0.1, hence the 1e-15 s.
    EXPECT_NEAR(sim->time(), 0.1, 1e-15);
}
