// The corrected pressure gradient (`fluid.pressure_gradient: corrected`, Bonet & Lok 1999;
// systems/forces/gradient_correction_system.hpp) against O(N^2) references in double precision
// that use no grid and no neighbour list, on a jittered block in a container (so that the moment
// matrices are not the lattice's):
//  * L_i = M_i^-1 with the eigenvalue clamp, M_i = -sum_j V_j grad W_ij x_ij^T (fluid and boundary);
//  * the property the correction exists for: with L_i the SPH gradient of a linear field is exact;
//  * the corrected WCSPH forces, and that they still conserve momentum (F_ij = -F_ji).
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <random>

#include "engine/data/components.hpp"
#include "engine/run/simulation.hpp"
#include "systems/boundary/boundary_volume_system.hpp"
#include "systems/density/density_system.hpp"
#include "systems/forces/forces_kernels.hpp"
#include "systems/forces/forces_system.hpp"
#include "systems/forces/gradient_correction_system.hpp"
#include "systems/neighbours/boundary_neighbours_system.hpp"
#include "systems/neighbours/fluid_grid_system.hpp"
#include "systems/neighbours/fluid_neighbours_system.hpp"
#include "test_scenes.hpp"

using namespace sph;

namespace {

using Mat3d = Eigen::Matrix3d;

/// A jittered fluid block with random velocities, in a container (`with_boundary`) or alone
/// without gravity; density, correction and corrected forces evaluated once.
struct Fixture {
    World w;
    explicit Fixture(bool with_boundary) {
        Scene s = test::tank_scene(Vec3d(0.16, 0.2, 0.1), Vec3d(0.3, 0.3, 0.1));
        s.fluid.viscosity = 0.1;
        s.fluid.pressure_gradient = PressureGradient::Corrected;
        if (!with_boundary) {
            s.boundaries.clear();
            s.simulation.gravity = Vec3d::Zero();
        }
        initialise_world(w, s);
        std::mt19937 rng(5);
        std::uniform_real_distribution<Real> u(-1, 1);
        auto x = w.fluid.store.get(comp::position);
        auto v = w.fluid.store.get(comp::velocity);
        for (std::size_t i = 0; i < x.size(); ++i) {
            x[i] += Vec3(u(rng), u(rng), u(rng)) * (0.3f * w.physics.particle_radius);
            if (with_boundary) x[i] = x[i].cwiseMax(Vec3::Constant(0.002f));
            v[i] = Vec3(u(rng), u(rng), u(rng));
        }
        std::vector<std::unique_ptr<System>> systems;
        if (with_boundary) systems.push_back(std::make_unique<BoundaryVolumeSystem>());
        systems.push_back(std::make_unique<FluidGridSystem>());
        systems.push_back(std::make_unique<FluidNeighbourSystem>());
        if (with_boundary) systems.push_back(std::make_unique<BoundaryNeighbourSystem>());
        systems.push_back(std::make_unique<DensitySystem>(with_boundary));
        systems.push_back(std::make_unique<GradientCorrectionSystem>(with_boundary, false));
        systems.push_back(std::make_unique<ForcesSystem>(with_boundary, false, false, true));
        for (auto& sys : systems) sys->register_components(w);
        for (auto& sys : systems) run_system(*sys, w);
    }
};

/// M_i over all pairs, in double (fluid V_j = m / rho_j, boundary V_b).
Mat3d brute_moment(const World& w, std::size_t i) {
    const auto x = w.fluid.store.get(comp::position);
    const auto rho = w.fluid.store.get(comp::density);
    Mat3d m = Mat3d::Zero();
    for (std::size_t j = 0; j < x.size(); ++j) {
        const Vec3 xij = x[i] - x[j];
        if (j == i || xij.norm() >= w.physics.h) continue;
        m -= (double(w.physics.mass) / rho[j]) * w.kernel.grad(xij, xij.norm()).cast<double>() *
             xij.cast<double>().transpose();
    }
    if (w.boundary.size() > 0) {
        const auto xb = w.boundary.store.get(comp::position);
        const auto vb = w.boundary.store.get(comp::volume);
        for (std::size_t b = 0; b < xb.size(); ++b) {
            const Vec3 xib = x[i] - xb[b];
            if (xib.norm() >= w.physics.h) continue;
            m -= double(vb[b]) * w.kernel.grad(xib, xib.norm()).cast<double>() * xib.cast<double>().transpose();
        }
    }
    return m;
}

}  // namespace

TEST(GradientCorrection, InverseMomentInvertsAndClamps) {
    // A symmetric matrix with eigenvalues 1.3, 0.9, 0.2 in a rotated frame: the first two are
    // inverted, the third is raised to the clamp (0.5), so L has eigenvalues 1/1.3, 1/0.9, 2.
    // Tolerance 1e-5: float eigen-decomposition of a well-conditioned 3x3.
    const Eigen::Matrix3d q = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    const Eigen::Matrix3d m = q * Eigen::Vector3d(1.3, 0.9, 0.2).asDiagonal() * q.transpose();
    const Eigen::Matrix3d expect = q * Eigen::Vector3d(1 / 1.3, 1 / 0.9, 2.0).asDiagonal() * q.transpose();
    const Mat3 l = inverse_moment(m.cast<Real>(), Real(0.5));
    EXPECT_LT((l.cast<double>() - expect).norm(), 1e-5);
    // Without clamping it is the plain inverse.
    const Mat3 full = inverse_moment(m.cast<Real>(), Real(0.1));
    EXPECT_LT((full.cast<double>() * m - Eigen::Matrix3d::Identity()).norm(), 1e-5);
    // Near the identity (an interior particle) the Gershgorin bound clears the clamp and the
    // cofactor inverse is taken instead of the eigen-decomposition: the same matrix.
    Eigen::Matrix3d near = Eigen::Matrix3d::Identity();
    near(0, 1) = near(1, 0) = 0.03;
    near(1, 2) = near(2, 1) = -0.05;
    near(0, 0) = 0.97;
    const Mat3 fast = inverse_moment(near.cast<Real>());
    EXPECT_LT((fast.cast<double>() - near.inverse()).norm(), 1e-5);
}

TEST(GradientCorrection, MatricesMatchBruteForce) {
    Fixture f(true);
    const World& w = f.w;
    const auto l = w.fluid.store.get(comp::gradient_correction);
    ASSERT_GT(l.size(), 300u);
    std::size_t clamped = 0;
    double dev_max = 0;
    for (std::size_t i = 0; i < l.size(); ++i) {
        const Mat3d m = brute_moment(w, i);
        Eigen::SelfAdjointEigenSolver<Mat3d> eig(m);
        Eigen::Vector3d inv = eig.eigenvalues();
        for (int k = 0; k < 3; ++k) {
            if (inv[k] < kMinEigenvalue) ++clamped;
            inv[k] = 1 / std::max(inv[k], double(kMinEigenvalue));
        }
        const Mat3d ref = eig.eigenvectors() * inv.asDiagonal() * eig.eigenvectors().transpose();
        // 1e-4 relative (Frobenius): float sums of ~40 outer products, then a 3x3 inverse.
        const double dev = (l[i].cast<double>() - ref).norm() / ref.norm();
        dev_max = std::max(dev_max, dev);
        EXPECT_LT(dev, 1e-4) << "fluid particle " << i;
    }
    std::printf("gradient correction: %zu particles, max relative deviation %.2e, %zu eigenvalues clamped\n",
                l.size(), dev_max, clamped);
}

TEST(GradientCorrection, CorrectedGradientOfALinearFieldIsExact) {
    // f(x) = 3 + G . x on fluid and boundary particles alike. The corrected difference form
    // sum_j V_j (f_j - f_i) L_i grad W_ij equals G wherever L_i = M_i^-1 (no clamped eigenvalue):
    // that is what the correction buys. Tolerance 1e-5 |G|: float sums (measured 4e-7). The plain SPH gradient
    // (L = I) must be measurably wrong on the same particles, or the test proves nothing.
    Fixture f(true);
    const World& w = f.w;
    const auto x = w.fluid.store.get(comp::position);
    const auto rho = w.fluid.store.get(comp::density);
    const auto l = w.fluid.store.get(comp::gradient_correction);
    const auto xb = w.boundary.store.get(comp::position);
    const auto vb = w.boundary.store.get(comp::volume);
    const Eigen::Vector3d g(2.0, -5.0, 1.5);
    auto field = [&](const Vec3& p) { return 3.0 + g.dot(p.cast<double>()); };
    std::size_t checked = 0;
    double plain_err_max = 0, corrected_err_max = 0;
    for (std::size_t i = 0; i < x.size(); ++i) {
        if (Eigen::SelfAdjointEigenSolver<Mat3d>(brute_moment(w, i)).eigenvalues().minCoeff() < kMinEigenvalue)
            continue;
        Eigen::Vector3d plain = Eigen::Vector3d::Zero();
        for (Index j : w.fluid_neighbours.of(Index(i))) {
            const Vec3 xij = x[i] - x[j];
            plain += (double(w.physics.mass) / rho[j]) * (field(x[j]) - field(x[i])) *
                     w.kernel.grad(xij, xij.norm()).cast<double>();
        }
        for (Index b : w.boundary_neighbours.of(Index(i))) {
            const Vec3 xib = x[i] - xb[b];
            plain += double(vb[b]) * (field(xb[b]) - field(x[i])) * w.kernel.grad(xib, xib.norm()).cast<double>();
        }
        const Eigen::Vector3d corrected = l[i].cast<double>() * plain;
        corrected_err_max = std::max(corrected_err_max, (corrected - g).norm() / g.norm());
        plain_err_max = std::max(plain_err_max, (plain - g).norm() / g.norm());
        EXPECT_NEAR((corrected - g).norm(), 0.0, 1e-5 * g.norm()) << "fluid particle " << i;
        ++checked;
    }
    std::printf("linear field: %zu particles, max relative gradient error %.2e corrected, %.2e plain\n", checked,
                corrected_err_max, plain_err_max);
    EXPECT_GT(checked, 100u);
    EXPECT_GT(plain_err_max, 0.02);
}

TEST(GradientCorrection, CorrectedForcesMatchBruteForce) {
    // He eq. 4 with (L_i + L_j)/2 grad W_ij on fluid pairs and L_i grad W_ib on boundary pairs
    // (Akinci eq. 10, p_b = p_i); viscosity on the plain gradient. Tolerance 1e-4 of the largest
    // acceleration, as for the symmetric form (density_forces_bruteforce_test.cpp).
    Fixture f(true);
    const World& w = f.w;
    const Physics& ph = w.physics;
    const auto x = w.fluid.store.get(comp::position);
    const auto v = w.fluid.store.get(comp::velocity);
    const auto rho = w.fluid.store.get(comp::density);
    const auto p = w.fluid.store.get(comp::pressure);
    const auto l = w.fluid.store.get(comp::gradient_correction);
    const auto acc = w.fluid.store.get(comp::acceleration);
    const auto xb = w.boundary.store.get(comp::position);
    const auto vb = w.boundary.store.get(comp::volume);
    double amax = 0;
    for (const auto& a : acc) amax = std::max(amax, double(a.norm()));
    ASSERT_GT(amax, 10.0);
    for (std::size_t i = 0; i < x.size(); ++i) {
        Eigen::Vector3d a = ph.gravity.cast<double>();
        const double pi = p[i] / (double(rho[i]) * rho[i]);
        for (std::size_t j = 0; j < x.size(); ++j) {
            const Vec3 xij = x[i] - x[j];
            const Real r = xij.norm();
            if (j == i || r >= ph.h) continue;
            const Eigen::Vector3d grad = w.kernel.grad(xij, r).cast<double>();
            const Mat3d lbar = 0.5 * (l[i].cast<double>() + l[j].cast<double>());
            const double visc = monaghan_pi((v[i] - v[j]).dot(xij), xij.squaredNorm(), ph.viscosity, ph.speed_of_sound,
                                            ph.h, rho[i], rho[j]);
            a -= ph.mass * (pi + p[j] / (double(rho[j]) * rho[j])) * (lbar * grad) + ph.mass * visc * grad;
        }
        for (std::size_t b = 0; b < xb.size(); ++b) {
            const Vec3 xib = x[i] - xb[b];
            const Real r = xib.norm();
            if (r >= ph.h) continue;
            const Eigen::Vector3d grad = w.kernel.grad(xib, r).cast<double>();
            const double visc = monaghan_pi(v[i].dot(xib), xib.squaredNorm(), ph.boundary_viscosity, ph.speed_of_sound,
                                            ph.h, rho[i], ph.rest_density);
            a -= ph.rest_density * vb[b] * (2 * pi * (l[i].cast<double>() * grad) + visc * grad);
        }
        EXPECT_NEAR((acc[i].cast<double>() - a).norm(), 0.0, 1e-4 * amax) << "fluid particle " << i;
    }
}

TEST(GradientCorrection, CorrectedForcesConserveMomentum) {
    // No boundary, no gravity: the pair forces cancel, so sum_i m a_i = 0. Tolerance 1e-5 of
    // sum_i m |a_i| (float accumulation over ~40 neighbours per particle).
    Fixture f(false);
    const World& w = f.w;
    const auto acc = w.fluid.store.get(comp::acceleration);
    const auto l = w.fluid.store.get(comp::gradient_correction);
    Eigen::Vector3d total = Eigen::Vector3d::Zero();
    double scale = 0, l_dev = 0;
    for (std::size_t i = 0; i < acc.size(); ++i) {
        total += w.physics.mass * acc[i].cast<double>();
        scale += w.physics.mass * acc[i].cast<double>().norm();
        l_dev = std::max(l_dev, double((l[i] - Mat3::Identity()).norm()));
    }
    std::printf("momentum: |sum m a| = %.3e against sum m |a| = %.3e; max |L - I| = %.3f\n", total.norm(), scale, l_dev);
    EXPECT_LT(total.norm(), 1e-5 * scale);
    EXPECT_GT(l_dev, 0.1);  // the correction is far from the identity here (free surfaces), so it was exercised
}
