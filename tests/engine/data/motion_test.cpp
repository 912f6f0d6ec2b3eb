/// @file motion_test.cpp
/// @brief Kinematic motions (engine/motion.hpp): each type's displacement and velocity against
/// the closed form written out independently here, and the velocity against a central finite
/// difference of the displacement; path ends (stop / loop); circle geometry; scene keys.
///
/// Tolerances. Closed form: both sides evaluate the same double expressions in a different
/// order, so they agree to a few ulp of values of order 1: 1e-12 m and 1e-12 m/s. Finite
/// difference (d(t + e) - d(t - e)) / 2e with e = 1e-6 s: truncation error <= e^2/6 max|d'''|
/// (at most 2e-11 m/s for the fastest motion here, A w^3 = 99 m/s^3) plus round-off
/// <= 2 eps |d| / 2e = 2.2e-10 m/s for |d| <= 1 m, so 1e-8 m/s is a safe bound that still fails
/// on any wrong factor (every velocity here is >= 0.3 m/s).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include <Eigen/Geometry>

#include "engine/core/errors.hpp"
#include "engine/data/motion.hpp"
#include "engine/data/scene.hpp"

using namespace sph;

namespace {

constexpr double k_exact = 1e-12;
constexpr double k_fd = 1e-8;
constexpr double k_eps = 1e-6;

Vec3d finite_difference(const Motion& m, double t) {
    return (displacement(m, t + k_eps) - displacement(m, t - k_eps)) / (2 * k_eps);
}

void expect_near(const Vec3d& a, const Vec3d& b, double tol, const std::string& what) {
    EXPECT_LE((a - b).norm(), tol) << what << ": got " << a.transpose() << ", expected " << b.transpose();
}

}  // namespace

TEST(Motion, LinearIsVelocityTimesTime) {
    const Vec3d u(0.5, -0.25, 0.125);
    const Motion m = linear_motion(u);
    for (double t : {0.0, 0.013, 0.7, 3.2}) {
        expect_near(displacement(m, t), u * t, k_exact, "d");
        expect_near(velocity(m, t), u, k_exact, "v");
        if (t > 0) expect_near(finite_difference(m, t), u, k_fd, "fd");
    }
    EXPECT_DOUBLE_EQ(speed_bound(m, 1.0), u.norm());
}

TEST(Motion, SinusoidalFollowsAmplitudeSinAxis) {
    // Axis (0, 3, 4) is normalised to (0, 0.6, 0.8).
    const double a = 0.05, period = 0.5, phase = 0.3, w = 2 * std::numbers::pi / period;
    const Motion m = sinusoidal_motion(Vec3d(0, 3, 4), a, period, phase);
    const Vec3d axis(0, 0.6, 0.8);
    expect_near(m.axis, axis, k_exact, "axis");
    double vmax = 0;
    for (double t : {0.0, 0.01, 0.123, 0.25, 0.4, 1.77}) {
        expect_near(displacement(m, t), a * std::sin(w * t + phase) * axis, k_exact, "d");
        expect_near(velocity(m, t), a * w * std::cos(w * t + phase) * axis, k_exact, "v");
        if (t > 0) expect_near(finite_difference(m, t), velocity(m, t), k_fd, "fd");
        vmax = std::max(vmax, velocity(m, t).norm());
    }
    // One period later it is back: d(t + T) = d(t).
    expect_near(displacement(m, 0.123 + period), displacement(m, 0.123), k_exact, "periodic");
    EXPECT_NEAR(speed_bound(m, 0.0), a * w, k_exact);
    EXPECT_LE(vmax, speed_bound(m, 0.0));
}

TEST(Motion, PathStopsAtTheLastPoint) {
    // Segments of 0.3 m along x then 0.4 m along y at 0.5 m/s: at the end after 1.4 s.
    const Motion m = path_motion({Vec3d(1, 1, 1), Vec3d(1.3, 1, 1), Vec3d(1.3, 1.4, 1)}, 0.5, false);
    struct Case {
        double t;
        Vec3d d, v;
    };
    for (const Case& c : {Case{0.0, {0, 0, 0}, {0.5, 0, 0}}, Case{0.3, {0.15, 0, 0}, {0.5, 0, 0}},
                          Case{1.0, {0.3, 0.2, 0}, {0, 0.5, 0}}, Case{1.39, {0.3, 0.395, 0}, {0, 0.5, 0}},
                          Case{2.0, {0.3, 0.4, 0}, {0, 0, 0}}, Case{50.0, {0.3, 0.4, 0}, {0, 0, 0}}}) {
        expect_near(displacement(m, c.t), c.d, k_exact, "d at t = " + std::to_string(c.t));
        expect_near(velocity(m, c.t), c.v, k_exact, "v at t = " + std::to_string(c.t));
        if (c.t > 0 && std::abs(c.t - 0.6) > 1e-3 && std::abs(c.t - 1.4) > 1e-3)  // away from vertices
            expect_near(finite_difference(m, c.t), c.v, k_fd, "fd at t = " + std::to_string(c.t));
    }
    EXPECT_EQ(speed_bound(m, 1.0), 0.5);
    EXPECT_EQ(speed_bound(m, 1.5), 0.0);  // stopped: it can no longer reach anything
}

TEST(Motion, LoopingPathClosesAndRepeats) {
    // Closing segment (0.3, 0.4, 0) -> (0, 0, 0) of 0.5 m: total 1.2 m, a lap every 2.4 s.
    const Motion m = path_motion({Vec3d(0, 0, 0), Vec3d(0.3, 0, 0), Vec3d(0.3, 0.4, 0)}, 0.5, true);
    // t = 2.0 s: s = 1.0 m, 0.3 m into the closing segment (0.6 of it).
    expect_near(displacement(m, 2.0), Vec3d(0.12, 0.16, 0), k_exact, "d on the closing segment");
    expect_near(velocity(m, 2.0), Vec3d(-0.3, -0.4, 0), k_exact, "v on the closing segment");
    expect_near(finite_difference(m, 2.0), Vec3d(-0.3, -0.4, 0), k_fd, "fd on the closing segment");
    for (double t : {0.1, 0.9, 2.0})
        expect_near(displacement(m, t + 2.4 * 3), displacement(m, t), 1e-12, "lap periodicity");
    EXPECT_EQ(speed_bound(m, 100.0), 0.5);
}

TEST(Motion, CircleTranslatesRoundItsCentre) {
    // Body centre at (0.7, 0.1, 0.5), circle centre (0.5, 0.3, 0.5), axis +y (given unnormalised):
    // u = +x, w = axis x u = -z; counter-clockwise seen from +y.
    const double radius = 0.2, speed = 0.8, omega = speed / radius;
    const Vec3d c(0.5, 0.3, 0.5), start(0.7, 0.1, 0.5);
    const Motion m = circle_motion(c, radius, Vec3d(0, 2, 0), speed, start);
    expect_near(m.start, Vec3d(1, 0, 0), k_exact, "start direction");
    for (double t : {0.0, 0.05, 0.4, 1.0, 2.9}) {
        const Vec3d d = displacement(m, t), v = velocity(m, t);
        const Vec3d expected_d = radius * Vec3d(std::cos(omega * t) - 1, 0, -std::sin(omega * t));
        const Vec3d expected_v = speed * Vec3d(-std::sin(omega * t), 0, -std::cos(omega * t));
        expect_near(d, expected_d, k_exact, "d");
        expect_near(v, expected_v, k_exact, "v");
        if (t > 0) expect_near(finite_difference(m, t), v, k_fd, "fd");
        // The body centre stays on the circle (in its plane) and moves at `speed`.
        const Vec3d p = start + d - c;
        EXPECT_NEAR(std::hypot(p.x(), p.z()), radius, k_exact);
        EXPECT_NEAR(p.y(), -0.2, k_exact);
        EXPECT_NEAR(v.norm(), speed, k_exact);
    }
    // A quarter turn (t = pi/2 / omega) takes the centre from +x to -z of the circle centre.
    expect_near(start + displacement(m, std::numbers::pi / 2 / omega), Vec3d(0.5, 0.1, 0.3), k_exact, "quarter");
    const auto [lo, hi] = displacement_bounds(m, 10.0);
    expect_near(lo, Vec3d(-0.4, 0, -0.2), k_exact, "bounds lo");
    expect_near(hi, Vec3d(0, 0, 0.2), k_exact, "bounds hi");
}

TEST(Motion, SceneKeysParseIntoMotions) {
    const char* const text = R"({
      "name": "motions",
      "fluid_blocks": [{"min": [0, 0, 0], "max": [0.2, 0.2, 0.2]}],
      "boundaries": [
        {"type": "container", "min": [0, 0, 0], "max": [2, 1, 1]},
        {"type": "box", "min": [0.5, 0, 0], "max": [0.6, 0.5, 0.1], "motion": {"type": "linear", "velocity": [0.1, 0, 0]}},
        {"type": "sphere", "center": [1, 0.5, 0.5], "radius": 0.1,
         "motion": {"type": "sinusoidal", "axis": [0, 0, 2], "amplitude": 0.05, "period": 0.5}},
        {"type": "box", "min": [1.2, 0, 0.2], "max": [1.3, 0.5, 0.3],
         "motion": {"type": "path", "points": [[0, 0, 0], [0.2, 0, 0], [0.2, 0, 0.2]], "speed": 0.3, "loop": true}},
        {"type": "box", "min": [0.66, 0.1, 0.46], "max": [0.74, 0.65, 0.54],
         "motion": {"type": "circle", "center": [0.5, 0.375, 0.5], "radius": 0.2, "axis": [0, 1, 0], "speed": 0.8}}
      ]
    })";
    const Scene s = parse_scene(text, "m.json");
    ASSERT_EQ(s.boundaries.size(), 5u);
    EXPECT_FALSE(s.boundaries[0].motion.has_value());
    EXPECT_TRUE(has_moving_boundaries(s));
    ASSERT_TRUE(s.boundaries[1].motion && s.boundaries[2].motion && s.boundaries[3].motion && s.boundaries[4].motion);
    EXPECT_EQ(s.boundaries[1].motion->type, MotionType::Linear);
    EXPECT_EQ(s.boundaries[1].motion->velocity, Vec3d(0.1, 0, 0));
    EXPECT_EQ(s.boundaries[2].motion->type, MotionType::Sinusoidal);
    EXPECT_EQ(s.boundaries[2].motion->axis, Vec3d(0, 0, 1));  // normalised
    EXPECT_EQ(s.boundaries[2].motion->phase, 0.0);             // default
    EXPECT_EQ(s.boundaries[3].motion->type, MotionType::Path);
    EXPECT_EQ(s.boundaries[3].motion->points.size(), 3u);
    EXPECT_TRUE(s.boundaries[3].motion->loop);
    EXPECT_EQ(s.boundaries[4].motion->type, MotionType::Circle);
    EXPECT_NEAR((s.boundaries[4].motion->start - Vec3d(1, 0, 0)).norm(), 0.0, k_exact);
    EXPECT_FALSE(has_moving_boundaries(parse_scene(R"({"name": "s", "fluid_blocks": [{"min": [0, 0, 0], "max": [1, 1, 1]}]})", "s.json")));
}
