// One particle, no boundaries: symplectic Euler must follow its own closed form,
// v_n = n dt g and y_n = y_0 + dt^2 g n (n + 1) / 2 (He et al. Alg. 1 lines 9-10).
#include <gtest/gtest.h>

#include <limits>

#include "engine/data/components.hpp"
#include "systems/methods/recipes.hpp"

using namespace sph;

TEST(FreeFall, FollowsSymplecticEulerClosedForm) {
    Scene s;
    s.name = "free_fall";
    s.fluid.particle_radius = 0.01;
    s.fluid_blocks.push_back(FluidBlock{Aabb{Vec3d::Zero(), Vec3d::Constant(0.02)}, Vec3d::Zero()});
    s.domain = Aabb{Vec3d(-0.1, -2.0, -0.1), Vec3d(0.1, 0.1, 0.1)};
    s.simulation.stepping.mode = SteppingMode::Constant;
    s.simulation.stepping.dt = 1e-3;
    s.simulation.frame_rate = 0;
    auto sim = make_simulation(s);
    ASSERT_EQ(sim->world().fluid.size(), 1u);
    const double g = -9.81, dt = 1e-3, y0 = 0.01;
    const int n = 500;
    // A lone particle's density is m W(0) < rho0, so its pressure is zero and a = g exactly.
    for (int k = 0; k < n; ++k) sim->step();
    const Vec3 x = sim->world().fluid.store.get(comp::position)[0];
    const Vec3 v = sim->world().fluid.store.get(comp::velocity)[0];
    const double v_exact = n * dt * g;
    const double y_exact = y0 + dt * dt * g * n * (n + 1) / 2.0;
    // n additions in Real precision: each rounds by at most eps |value|, so the accumulated
    // error is bounded by n eps max|value|.
    const double eps = std::numeric_limits<Real>::epsilon();
    EXPECT_NEAR(v.y(), v_exact, n * eps * std::abs(v_exact));
    EXPECT_NEAR(x.y(), y_exact, n * eps * 1.3);
    EXPECT_EQ(x.x(), Real(0.01));
    EXPECT_EQ(v.x(), Real(0));
    EXPECT_NEAR(sim->time(), n * dt, 1e-12);
}
