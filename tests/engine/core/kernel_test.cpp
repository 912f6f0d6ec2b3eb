// Property tests of the cubic spline (Monaghan 1992) in engine/kernel.hpp.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "engine/core/kernel.hpp"

using namespace sph;

namespace {
constexpr double kH = 0.04;
}

// Normalisation: int W dV = 4 pi int_0^h r^2 W(r) dr = 1. Midpoint rule with 20,000 radial
// intervals has a quadrature error far below 1e-6, and W is evaluated in float (a few ulp,
// about 5e-7 relative per term), so 1e-5 measures the kernel's own normalisation constant: a
// wrong sigma (8 / (pi h^3)) or a piece off by a factor misses it by far more.
TEST(CubicSpline, IntegratesToOne) {
    const CubicSpline k{Real(kH)};
    const int n = 20000;
    double sum = 0;
    for (int i = 0; i < n; ++i) {
        const double r = (i + 0.5) * kH / n;
        sum += 4 * std::numbers::pi * r * r * k.w(Real(r)) * (kH / n);
    }
    EXPECT_NEAR(sum, 1.0, 1e-5);
}

// The same on a 3-D lattice of spacing h/2 (the engine's sampling): the discrete sum is the
// quantity the particle mass is built from, and must be within 5 % of the integral.
TEST(CubicSpline, LatticeSumNearOne) {
    const CubicSpline k{Real(kH)};
    const double s = kH / 2;
    double sum = 0;
    for (int z = -3; z <= 3; ++z)
        for (int y = -3; y <= 3; ++y)
            for (int x = -3; x <= 3; ++x) sum += k.w(Real(s * std::sqrt(double(x * x + y * y + z * z))));
    EXPECT_NEAR(sum * s * s * s, 1.0, 0.05);
}

TEST(CubicSpline, NonNegativeCompactAndMonotone) {
    const CubicSpline k{Real(kH)};
    Real prev = k.w(0);
    for (int i = 1; i <= 1000; ++i) {
        const Real r = Real(kH * i / 1000.0);
        const Real w = k.w(r);
        EXPECT_GE(w, 0) << "r = " << r;
        EXPECT_LE(w, prev) << "r = " << r;
        prev = w;
    }
    EXPECT_EQ(k.w(Real(kH)), 0);
    EXPECT_EQ(k.w(Real(1.5 * kH)), 0);
    const Vec3 far(Real(kH), 0, 0);
    EXPECT_EQ(k.grad(far, Real(kH)).norm(), 0);
    // W(0) = 8 / (pi h^3)
    EXPECT_NEAR(k.w(0), 8.0 / (std::numbers::pi * kH * kH * kH), 1e-3 * k.w(0));
}

// grad W equals the central finite difference of W along random directions (to 1e-3 of
// its largest value; the step h*1e-3 keeps the truncation error ~1e-8 while float round-off in W stays ~1e-4
// of the difference, hence double-precision evaluation of the difference quotient).
TEST(CubicSpline, GradientMatchesFiniteDifference) {
    const CubicSpline k{Real(kH)};
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-1, 1);
    for (int t = 0; t < 200; ++t) {
        Vec3d x(u(rng), u(rng), u(rng));
        x *= 0.99 * kH / std::sqrt(3.0);
        const double r = x.norm();
        if (r < 1e-3 * kH) continue;
        const Vec3 g = k.grad(x.cast<Real>(), Real(r));
        const double eps = kH * 1e-3;
        const double dwdr = (double(k.w(Real(r + eps))) - double(k.w(Real(r - eps)))) / (2 * eps);
        const Vec3d expect = dwdr * x / r;
        // Tolerance: 1e-3 of the largest |dW/dr| = 2 W(0) / h (at q = 1/3).
        EXPECT_NEAR((g.cast<double>() - expect).norm(), 0.0, 1e-3 * 2.0 * k.w(0) / kH)
            << "x = " << x.transpose();
    }
}

// Sum of gradients over a full symmetric lattice around a particle is zero (each pair
// cancels exactly), and grad W is antisymmetric; at r = 0 it is zero, not NaN.
TEST(CubicSpline, GradientSumIsZeroAndNoNaNAtOrigin) {
    const CubicSpline k{Real(kH)};
    const double s = kH / 2;
    Vec3d sum = Vec3d::Zero();
    double scale = 0;
    for (int z = -3; z <= 3; ++z)
        for (int y = -3; y <= 3; ++y)
            for (int x = -3; x <= 3; ++x) {
                const Vec3 d = (s * Vec3d(x, y, z)).cast<Real>();
                const Vec3 g = k.grad(d, d.norm());
                sum += g.cast<double>();
                scale += g.norm();
                const Vec3 gm = k.grad(-d, d.norm());
                EXPECT_EQ((g + gm).norm(), 0);
            }
    EXPECT_LT(sum.norm(), 1e-6 * scale);
    const Vec3 g0 = k.grad(Vec3::Zero(), 0);
    EXPECT_TRUE(g0.allFinite());
    EXPECT_EQ(g0.norm(), 0);
}
