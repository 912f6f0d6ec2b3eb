// The continuity density (`fluid.density: continuity`, systems/density/density_system.hpp) and
// the laminar viscosity (`fluid.kinematic_viscosity`, Morris et al. 1997):
//  * drho_i/dt (He eq. 5 plus the delta-SPH diffusion with Fourtakas et al.'s hydrostatic part
//    removed) against an O(N^2) double-precision evaluation of the same formula that uses no grid
//    and no neighbour list, on a jittered block in a container with random velocities and
//    densities; and the density advanced by exactly (t - t_0) drho/dt;
//  * the properties the terms exist for, against analytic values on the lattice interior:
//    the diffusion of rho0 (1 + A |x - c|^2) is delta h_s c_s lap(rho) = delta h_s c_s 6 rho0 A;
//    a hydrostatic column diffuses nothing, also at the free surface where the support is cut
//    (without the hydrostatic term it would); a uniform expansion v = B (x - c) gives -3 B rho;
//    the laminar acceleration of the shear flow v = (A y^2, 0, 0) is nu lap(v) = (2 nu A, 0, 0).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "engine/data/components.hpp"
#include "engine/run/simulation.hpp"
#include "systems/boundary/boundary_volume_system.hpp"
#include "systems/density/density_system.hpp"
#include "systems/forces/forces_system.hpp"
#include "systems/neighbours/boundary_neighbours_system.hpp"
#include "systems/neighbours/fluid_grid_system.hpp"
#include "systems/neighbours/fluid_neighbours_system.hpp"
#include "test_scenes.hpp"

using namespace sph;

namespace {

constexpr double kDt = 1e-4;  // the interval the density is advanced over, s

/// A fluid block (in a container when `with_boundary`), its lists built, densities started
/// (the first evaluation sums them); the caller then sets rho and v and calls advance().
struct Fixture {
    World w;
    std::vector<std::unique_ptr<System>> systems;
    bool boundary;

    Fixture(bool with_boundary, Vec3d gravity, bool jittered, double nu = 0, bool simd = true) : boundary(with_boundary) {
        Scene s = test::tank_scene(Vec3d(0.2, 0.2, 0.2), Vec3d(0.3, 0.3, 0.3));
        s.simulation.simd = simd;  // the vectorised rates or the scalar reference
        if (!with_boundary) s.boundaries.clear();
        s.simulation.gravity = gravity;
        s.fluid.viscosity = 0;
        s.fluid.boundary_viscosity = with_boundary ? 0.1 : 0.0;
        s.fluid.kinematic_viscosity = nu;
        s.fluid.density = DensityForm::Continuity;
        initialise_world(w, s);
        if (with_boundary) systems.push_back(std::make_unique<BoundaryVolumeSystem>());
        systems.push_back(std::make_unique<FluidGridSystem>());
        systems.push_back(std::make_unique<FluidNeighbourSystem>());
        if (with_boundary) systems.push_back(std::make_unique<BoundaryNeighbourSystem>());
        systems.push_back(std::make_unique<DensitySystem>(with_boundary, false, true));
        systems.push_back(std::make_unique<ForcesSystem>(with_boundary, false, false, false, SteppingParams{}, true));
        for (auto& sys : systems) sys->register_components(w);
        if (jittered) test::jitter(w, 11, 0.3f);
        for (auto& sys : systems)
            if (sys->name() != "forces") run_system(*sys, w);  // t = 0: the densities are summed
    }
    /// The density system one interval later (drho/dt from the rho and v set by the caller).
    void advance() {
        w.clock.t_ticks = to_ticks(kDt);
        w.clock.t = to_seconds(w.clock.t_ticks);
        for (auto& sys : systems)
            if (sys->name() == "density") run_system(*sys, w);
    }
    void forces() {
        for (auto& sys : systems)
            if (sys->name() == "forces") run_system(*sys, w);
    }
    /// Rows whose whole support lies in the fluid block, 2 h from its faces.
    bool interior(std::size_t i) const {
        const Vec3 x = w.fluid.store.get(comp::position)[i];
        const Real m = 1.01f * w.physics.h;
        return (x.array() > m).all() && (x.array() < Real(0.2) - m).all();
    }
};

/// drho_i/dt by the formula of density_kernels.hpp over all pairs, in double, from the
/// densities `rho` (those before the advance).
double brute_rate(const World& w, std::span<const Real> rho, std::size_t i, bool hydrostatic_term = true) {
    const auto x = w.fluid.store.get(comp::position);
    const auto v = w.fluid.store.get(comp::velocity);
    const Physics& ph = w.physics;
    const double m = ph.mass, c = ph.speed_of_sound, h = ph.h, rho0 = ph.rest_density;
    const double delta_hc = double(ph.density_diffusion) * h * c, eps = 0.01 * h * h;
    const Eigen::Vector3d g_h = (rho0 / (c * c)) * ph.gravity.cast<double>();
    double div = 0, diffused = 0;
    for (std::size_t j = 0; j < x.size(); ++j) {
        const Eigen::Vector3d xij = (x[i] - x[j]).cast<double>();
        const double r = xij.norm();
        if (j == i || r >= h) continue;
        const Eigen::Vector3d grad = w.kernel.grad(Vec3(xij.cast<Real>()), Real(r)).cast<double>();
        div += m * (v[i] - v[j]).cast<double>().dot(grad);
        const double rho_h = hydrostatic_term ? g_h.dot(xij) : 0.0;
        diffused += m / rho[j] * (double(rho[i]) - rho[j] - rho_h) * xij.dot(grad) / (r * r + eps);
    }
    if (w.boundary.size() > 0) {
        const auto xb = w.boundary.store.get(comp::position);
        const auto vb = w.boundary.store.get(comp::volume);
        for (std::size_t b = 0; b < xb.size(); ++b) {
            const Vec3 xib = x[i] - xb[b];
            if (xib.norm() >= ph.h) continue;
            div += rho0 * vb[b] * v[i].cast<double>().dot(w.kernel.grad(xib, xib.norm()).cast<double>());
        }
    }
    return div + delta_hc * diffused;
}

}  // namespace

class ContinuityRatePath : public ::testing::TestWithParam<bool> {};

TEST_P(ContinuityRatePath, RateMatchesBruteForceAndAdvancesTheDensity) {
    Fixture f(true, Vec3d(0, -9.81, 0), true, 0, GetParam());
    ASSERT_EQ(f.w.physics.simd, GetParam());
    World& w = f.w;
    std::mt19937 rng(3);
    std::uniform_real_distribution<Real> u(-1, 1);
    auto rho = w.fluid.store.get(comp::density);
    for (auto& r : rho) r = w.physics.rest_density * (1 + 0.01f * u(rng));
    for (auto& v : w.fluid.store.get(comp::velocity)) v = Vec3(u(rng), u(rng), u(rng));
    const std::vector<Real> before(rho.begin(), rho.end());
    f.advance();
    const auto drho = w.fluid.store.get(comp::drho_dt);
    double dev = 0, scale = 0, step_dev = 0;
    for (std::size_t i = 0; i < rho.size(); ++i) {
        const double want = brute_rate(w, before, i);
        scale = std::max(scale, std::abs(want));
        dev = std::max(dev, std::abs(double(drho[i]) - want));
        const double advanced = std::max(double(before[i]) + kDt * double(drho[i]), 0.99 * w.physics.rest_density);
        step_dev = std::max(step_dev, std::abs(double(rho[i]) - advanced));
    }
    ASSERT_GT(scale, 1e3);  // |v| ~ 1 m/s across h = 4 cm: ~ rho0 |v| / h
    // ~30 fluid and ~40 boundary terms summed in float with cancellation: 1e-5 of the largest.
    EXPECT_LT(dev, 1e-5 * scale) << "largest |drho/dt| " << scale;
    // max(rho + dt drho/dt, 0.99 rho0) in float (the floor of continuity_density_floor): the rounding of rho (6e-5 kg/m^3 at 1000) is the bound.
    EXPECT_LT(step_dev, 1.2e-4);
}

INSTANTIATE_TEST_SUITE_P(BothLoops, ContinuityRatePath, ::testing::Bool(),
                         [](const auto& info) { return info.param ? "Vectorised" : "Scalar"; });

TEST(ContinuityDensity, DiffusionOfAQuadraticDensityIsItsLaplacian) {
    Fixture f(false, Vec3d::Zero(), false);
    World& w = f.w;
    const auto x = w.fluid.store.get(comp::position);
    auto rho = w.fluid.store.get(comp::density);
    const Vec3 c(0.1f, 0.1f, 0.1f);
    const double rho0 = w.physics.rest_density, A = 2.0;  // 1/m^2: rho varies by 2 % over 0.1 m
    for (std::size_t i = 0; i < x.size(); ++i) rho[i] = Real(rho0 * (1 + A * (x[i] - c).squaredNorm()));
    f.advance();
    const double want = w.physics.density_diffusion * 0.5 * w.physics.h * w.physics.speed_of_sound * 6 * rho0 * A;
    const auto drho = w.fluid.store.get(comp::drho_dt);
    double worst = 0;
    int n = 0;
    for (std::size_t i = 0; i < x.size(); ++i)
        if (f.interior(i)) worst = std::max(worst, std::abs(double(drho[i]) / want - 1)), ++n;
    ASSERT_GT(n, 50);
    std::printf("diffusion of a quadratic density: worst relative error %.4f over %d rows\n", worst, n);
    // Brookshaw's Laplacian on the cubic lattice: the gradient moment is 2 % off there (the
    // expansion test below), and 0.01 h^2 in the denominator lowers the nearest pairs' weight by
    // up to 4 %; measured 2026-12-03: 4.35 %. Held to 6 %.
    EXPECT_LT(worst, 0.06);
}

TEST(ContinuityDensity, AHydrostaticColumnDiffusesNothingEvenAtTheSurface) {
    Fixture f(false, Vec3d(0, -9.81, 0), false);
    World& w = f.w;
    const auto x = w.fluid.store.get(comp::position);
    auto rho = w.fluid.store.get(comp::density);
    const double rho0 = w.physics.rest_density, c = w.physics.speed_of_sound;
    // rho = rho0 (1 + g (H - y) / c^2): the linearised Tait density of the column's pressure.
    for (std::size_t i = 0; i < x.size(); ++i) rho[i] = Real(rho0 * (1 + 9.81 * (0.2 - x[i].y()) / (c * c)));
    const std::vector<Real> before(rho.begin(), rho.end());
    f.advance();
    const auto drho = w.fluid.store.get(comp::drho_dt);
    double worst = 0, without = 0;
    for (std::size_t i = 0; i < x.size(); ++i) {
        worst = std::max(worst, double(std::abs(drho[i])));
        without = std::max(without, std::abs(brute_rate(w, before, i, false)));
    }
    std::printf("hydrostatic column: largest |drho/dt| %.3g; Molteni & Colagrossi's form gives %.3g\n", worst, without);
    // Without the hydrostatic term the cut support at the surface and the bottom diffuses the
    // gradient away; with it every pair cancels up to the float rounding of rho_i - rho_j.
    ASSERT_GT(without, 1.0);
    EXPECT_LT(worst, 1e-3 * without);
}

TEST(ContinuityDensity, UniformExpansionLowersTheDensityAtThreeBRho) {
    Fixture f(false, Vec3d::Zero(), false);
    World& w = f.w;
    const auto x = w.fluid.store.get(comp::position);
    auto v = w.fluid.store.get(comp::velocity);
    const auto rho = w.fluid.store.get(comp::density);
    const Vec3 c(0.1f, 0.1f, 0.1f);
    const Real B = 2;  // 1/s
    for (std::size_t i = 0; i < x.size(); ++i) v[i] = B * (x[i] - c);
    std::vector<Real> rho_before(rho.begin(), rho.end());
    f.advance();
    const auto drho = w.fluid.store.get(comp::drho_dt);
    double worst = 0;
    for (std::size_t i = 0; i < x.size(); ++i)
        if (f.interior(i)) worst = std::max(worst, std::abs(double(drho[i]) / (-3.0 * B * rho_before[i]) - 1));
    std::printf("uniform expansion: worst relative error %.4g\n", worst);
    // sum_j m x_ij x_ij^T W'/r is -rho I in the continuum; on the cubic lattice, whose mass makes
    // the kernel sum exact, the gradient moment is 2.0 % off (measured 2026-12-03: 0.0201, the
    // same for every interior row). Held to 2.5 %.
    EXPECT_LT(worst, 0.025);
}

TEST(LaminarViscosity, ShearFlowAccelerationIsNuTimesTheLaplacian) {
    const double nu = 1e-2;  // m^2/s: large, so that the term dominates float rounding
    Fixture f(false, Vec3d::Zero(), false, nu);
    World& w = f.w;
    const auto x = w.fluid.store.get(comp::position);
    auto v = w.fluid.store.get(comp::velocity);
    auto rho = w.fluid.store.get(comp::density);
    const double A = 50;  // 1/(m s): v_x = A (y - 0.1)^2
    for (std::size_t i = 0; i < x.size(); ++i) {
        v[i] = Vec3(Real(A * std::pow(x[i].y() - 0.1, 2)), 0, 0);
        rho[i] = w.physics.rest_density;  // uniform: no pressure force in the interior
    }
    f.advance();
    f.forces();
    const auto a = w.fluid.store.get(comp::acceleration);
    double worst = 0, cross = 0;
    int n = 0;
    for (std::size_t i = 0; i < x.size(); ++i)
        if (f.interior(i)) {
            worst = std::max(worst, std::abs(double(a[i].x()) / (2 * nu * A) - 1));
            cross = std::max(cross, double(std::hypot(a[i].y(), a[i].z())) / (2 * nu * A));
            ++n;
        }
    ASSERT_GT(n, 50);
    std::printf("laminar shear: worst relative error %.4f, largest cross term %.3g\n", worst, cross);
    // The same operator as the density's Laplacian, on a field whose Taylor series ends at the
    // second order (measured 2026-12-03: 0.84 %); held to the same 6 %.
    EXPECT_LT(worst, 0.06);
    EXPECT_LT(cross, 0.01);
}
