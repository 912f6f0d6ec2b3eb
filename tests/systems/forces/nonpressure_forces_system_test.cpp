// NonpressureForcesSystem (Becker & Teschner 2007 eq. 10-11 viscosity, eq. 13 cohesion, and the
// boundary viscosity with psi_b = rho0 V_b) against an O(N^2) double-precision reference on a
// jittered block with random velocities next to a container wall. Tolerance: 1e-4 of the
// largest |a| (float sums over ~30-60 neighbours; the reference is in double).
#include <gtest/gtest.h>

#include <random>

#include "engine/data/components.hpp"
#include "systems/pcisph/pcisph_components.hpp"
#include "systems/forces/nonpressure_forces_system.hpp"
#include "systems/methods/recipes.hpp"
#include "systems/neighbours/boundary_neighbours_system.hpp"
#include "systems/neighbours/fluid_grid_system.hpp"
#include "systems/neighbours/fluid_neighbours_system.hpp"
#include "test_scenes.hpp"

using namespace sph;

TEST(NonpressureForces, EqualsBruteForce) {
    Scene s = test::tank_scene(Vec3d(0.12, 0.12, 0.12), Vec3d(0.3, 0.3, 0.3));
    s.simulation.method = Method::Pcisph;
    s.simulation.stepping.mode = SteppingMode::Constant;
    s.fluid.viscosity = 0.1;
    s.fluid.boundary_viscosity = 0.3;  // the walls' own alpha (fluid.boundary_viscosity), not the fluid's
    s.fluid.surface_tension = 0.5;
    auto sim = make_simulation(s);
    World& w = sim->world();
    std::mt19937 rng(7);
    std::uniform_real_distribution<Real> u(-1, 1);
    auto x = w.fluid.store.get(comp::position);
    auto v = w.fluid.store.get(comp::velocity);
    for (std::size_t i = 0; i < x.size(); ++i) {
        x[i] += Vec3(u(rng), u(rng), u(rng)) * Real(0.003);
        v[i] = Vec3(u(rng), u(rng), u(rng));
    }
    run_system(FluidGridSystem(), w);
    run_system(FluidNeighbourSystem(), w);
    run_system(BoundaryNeighbourSystem(), w);
    NonpressureForcesSystem sys(true, false, s.fluid.surface_tension);
    // Both paths: the scalar reference loop, then the vectorised one (simulation.simd).
    w.physics.simd = false;
    run_system(sys, w);
    const auto a_scalar = w.fluid.store.get(comp::nonpressure_acceleration);
    const std::vector<Vec3> scalar(a_scalar.begin(), a_scalar.end());
    w.physics.simd = true;
    run_system(sys, w);
    const auto a = w.fluid.store.get(comp::nonpressure_acceleration);
    const auto xb = w.boundary.store.get(comp::position);
    const auto vol = w.boundary.store.get(comp::volume);
    const double h = w.physics.h, m = w.physics.mass, rho0 = w.physics.rest_density, kappa = 0.5;
    const double c = w.physics.speed_of_sound;
    const double sigma = 8.0 / (3.14159265358979323846 * h * h * h);
    auto W = [&](double r) {
        const double q = r / h;
        if (q >= 1) return 0.0;
        return q <= 0.5 ? sigma * (6 * (q * q * q - q * q) + 1) : 2 * sigma * (1 - q) * (1 - q) * (1 - q);
    };
    auto gradW = [&](const Eigen::Vector3d& d) -> Eigen::Vector3d {
        const double r = d.norm(), q = r / h;
        if (q >= 1 || r < 1e-12) return Eigen::Vector3d::Zero();
        const double dwdq = q <= 0.5 ? sigma * (18 * q * q - 12 * q) : -6 * sigma * (1 - q) * (1 - q);
        return d / r * dwdq / h;
    };
    auto pi = [&](const Eigen::Vector3d& vij, const Eigen::Vector3d& xij, double alpha = 0.1) {
        const double vx = vij.dot(xij);
        if (vx >= 0) return 0.0;
        return -(2 * alpha * h * c / (2 * rho0)) * vx / (xij.squaredNorm() + 0.01 * h * h);
    };
    double amax = 0, err = 0;
    std::vector<Eigen::Vector3d> ref(x.size(), Eigen::Vector3d::Zero());
    for (std::size_t i = 0; i < x.size(); ++i) {
        const Eigen::Vector3d xi = x[i].cast<double>(), vi = v[i].cast<double>();
        for (std::size_t j = 0; j < x.size(); ++j) {
            if (i == j) continue;
            const Eigen::Vector3d xij = xi - x[j].cast<double>();
            if (xij.norm() >= h) continue;
            ref[i] -= m * pi(vi - v[j].cast<double>(), xij) * gradW(xij);
            ref[i] -= kappa * W(xij.norm()) * xij;
        }
        for (std::size_t b = 0; b < xb.size(); ++b) {
            const Eigen::Vector3d xib = xi - xb[b].cast<double>();
            if (xib.norm() >= h) continue;
            ref[i] -= rho0 * vol[b] * pi(vi, xib, 0.3) * gradW(xib);
        }
        amax = std::max(amax, ref[i].norm());
    }
    double err_scalar = 0;
    for (std::size_t i = 0; i < x.size(); ++i) {
        err = std::max(err, (a[i].cast<double>() - ref[i]).norm());
        err_scalar = std::max(err_scalar, (scalar[i].cast<double>() - ref[i]).norm());
    }
    ASSERT_GT(amax, 1.0);  // the forces are not trivially zero
    EXPECT_LE(err, 1e-4 * amax) << "vectorised; largest |a| " << amax;
    EXPECT_LE(err_scalar, 1e-4 * amax) << "scalar; largest |a| " << amax;
}
