// Semi-implicit (symplectic) Euler, He et al. Alg. 1 lines 9-10
// (systems/integrate/symplectic_euler_system.hpp):
//   v(t + dt) = v(t) + dt a(t)
//   x(t + dt) = x(t) + dt v(t + dt)      (the new velocity, not the old one)
// against that closed form in double, for particles with distinct a, v, x, with the step read
// from res::dt (the quantised, possibly clipped dt, not dt_stable).
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/system.hpp"
#include "systems/integrate/symplectic_euler_system.hpp"

using namespace sph;

namespace {

struct State {
    std::vector<Vec3> x, v, a;
};

World make_world(const State& s, double dt) {
    World w;
    auto& st = w.fluid.store;
    st.add(comp::position);
    st.add(comp::velocity);
    st.add(comp::acceleration);
    st.resize(s.x.size());
    std::copy(s.x.begin(), s.x.end(), st.get(comp::position).begin());
    std::copy(s.v.begin(), s.v.end(), st.get(comp::velocity).begin());
    std::copy(s.a.begin(), s.a.end(), st.get(comp::acceleration).begin());
    w.step_size.set(dt);
    return w;
}

}  // namespace

// Three particles worked out by hand, dt = 0.01 s (exactly 10^10 ticks):
//   0: x = (0, 0, 0),      v = (1, 0, 0),     a = (0, -10, 0)
//      v' = (1, -0.1, 0),  x' = (0.01, -0.001, 0)
//      (explicit Euler would give x' = (0.01, 0, 0): the y of x' tells them apart)
//   1: x = (0.5, 1, -0.2), v = (0, 0, 0),     a = (2, 4, -6)
//      v' = (0.02, 0.04, -0.06), x' = (0.5002, 1.0004, -0.2006)
//   2: x = (0.1, 0.2, 0.3), v = (-3, 2, 0.5), a = (0, 0, 0)
//      v' = v,             x' = (0.07, 0.22, 0.305)
// Tolerance 1e-6 absolute: float arithmetic, two roundings of values <= 1 (6e-8 each).
TEST(SymplecticEuler, HandWorkedParticles) {
    State s;
    s.x = {Vec3(0, 0, 0), Vec3(0.5f, 1, -0.2f), Vec3(0.1f, 0.2f, 0.3f)};
    s.v = {Vec3(1, 0, 0), Vec3(0, 0, 0), Vec3(-3, 2, 0.5f)};
    s.a = {Vec3(0, -10, 0), Vec3(2, 4, -6), Vec3(0, 0, 0)};
    World w = make_world(s, 0.01);
    run_system(SymplecticEulerSystem(), w);
    const auto x = w.fluid.store.get(comp::position);
    const auto v = w.fluid.store.get(comp::velocity);
    const Vec3d want_v[] = {{1, -0.1, 0}, {0.02, 0.04, -0.06}, {-3, 2, 0.5}};
    const Vec3d want_x[] = {{0.01, -0.001, 0}, {0.5002, 1.0004, -0.2006}, {0.07, 0.22, 0.305}};
    for (int i = 0; i < 3; ++i) {
        EXPECT_NEAR((v[i].cast<double>() - want_v[i]).norm(), 0.0, 1e-6) << "particle " << i;
        EXPECT_NEAR((x[i].cast<double>() - want_x[i]).norm(), 0.0, 1e-6) << "particle " << i;
    }
    // The acceleration is read, not written.
    EXPECT_EQ(w.fluid.store.get(comp::acceleration)[0], Vec3(0, -10, 0));
}

// 10,000 particles with random x, v, a (more than one parallel block of 4096), dt = 1.7e-3 s,
// against the closed form in double from the same float inputs. Tolerance 1e-6 (1 + |x'|):
// the float result carries two roundings of values of order 1 (|x| <= 1.7 m, |v| <= 3.5 m/s,
// |dt a| <= 0.06 m/s), 1.2e-7 relative, while the explicit-Euler error dt^2 |a| reaches
// 1e-4 m (|a| <= 20 sqrt(3) m/s^2), 40 times the tolerance.
TEST(SymplecticEuler, MatchesClosedFormOnManyParticles) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<Real> u(-1, 1);
    State s;
    const std::size_t n = 10'000;
    for (std::size_t i = 0; i < n; ++i) {
        s.x.emplace_back(u(rng), u(rng), u(rng));
        s.v.push_back(2 * Vec3(u(rng), u(rng), u(rng)));
        s.a.push_back(20 * Vec3(u(rng), u(rng), u(rng)));
    }
    const double dt = 1.7e-3;
    World w = make_world(s, dt);
    // dt_stable differs from the step taken (a clipped last step): the integrator must use dt.
    w.step_size.dt_stable = 10 * dt;
    const double step = w.step_size.dt;
    ASSERT_NEAR(step, dt, 1e-12);
    run_system(SymplecticEulerSystem(), w);
    const auto x = w.fluid.store.get(comp::position);
    const auto v = w.fluid.store.get(comp::velocity);
    double worst_explicit_gap = 0;
    for (std::size_t i = 0; i < n; ++i) {
        const Vec3d v1 = s.v[i].cast<double>() + step * s.a[i].cast<double>();
        const Vec3d x1 = s.x[i].cast<double>() + step * v1;
        const Vec3d x_explicit = s.x[i].cast<double>() + step * s.v[i].cast<double>();
        worst_explicit_gap = std::max(worst_explicit_gap, (x1 - x_explicit).norm());
        ASSERT_NEAR((v[i].cast<double>() - v1).norm(), 0.0, 1e-6 * (1 + v1.norm())) << "particle " << i;
        ASSERT_NEAR((x[i].cast<double>() - x1).norm(), 0.0, 1e-6 * (1 + x1.norm())) << "particle " << i;
    }
    // The test can tell the two schemes apart: the largest gap is well above the tolerance.
    EXPECT_GT(worst_explicit_gap, 2e-5);
}

// Two steps in a row under constant a: v_n = v0 + n dt a, x_n = x0 + dt sum_k v_k
// = x0 + n dt v0 + n (n + 1) / 2 dt^2 a. With x0 = 0, v0 = (0, 1, 0), a = (0, -10, 0),
// dt = 0.01 s and n = 2: v_2 = (0, 0.8, 0), x_2 = (0, 0.02 - 0.003, 0) = (0, 0.017, 0).
TEST(SymplecticEuler, TwoStepsFollowTheDiscreteSum) {
    State s;
    s.x = {Vec3(0, 0, 0)};
    s.v = {Vec3(0, 1, 0)};
    s.a = {Vec3(0, -10, 0)};
    World w = make_world(s, 0.01);
    run_system(SymplecticEulerSystem(), w);
    run_system(SymplecticEulerSystem(), w);
    EXPECT_NEAR(w.fluid.store.get(comp::velocity)[0].y(), 0.8, 1e-6);
    EXPECT_NEAR(w.fluid.store.get(comp::position)[0].y(), 0.017, 1e-6);
    EXPECT_EQ(w.fluid.store.get(comp::position)[0].x(), 0.0f);
}
