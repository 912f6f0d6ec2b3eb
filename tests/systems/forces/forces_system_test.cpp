// Each WCSPH system is checked against an O(N^2) reference in double precision that uses no
// grid and no neighbour list: Akinci volumes, summation density + Tait pressure (He eq. 1-2,
// Akinci eq. 6), and forces (He eq. 4 with Monaghan viscosity and Akinci boundary forces).
// The fluid is a jittered block in a container, so sums are not lattice-symmetric. Run at the
// default kernel support (2 spacings, about 30 neighbours) and at fluid.support = 3 (about 110:
// the neighbour lists outgrow their first capacity of 48 and are rebuilt), on the vectorised
// pair loops (simulation.simd, the default) and on the scalar reference loops.
#include <gtest/gtest.h>

#include <random>

#include "engine/data/components.hpp"
#include "engine/run/simulation.hpp"
#include "systems/boundary/boundary_volume_system.hpp"
#include "systems/density/density_kernels.hpp"
#include "systems/density/density_system.hpp"
#include "systems/forces/forces_kernels.hpp"
#include "systems/forces/forces_system.hpp"
#include "systems/neighbours/boundary_neighbours_system.hpp"
#include "systems/neighbours/fluid_grid_system.hpp"
#include "systems/neighbours/fluid_neighbours_system.hpp"
#include "test_scenes.hpp"

using namespace sph;

namespace {

struct Fixture {
    World w;
    Fixture(double support, bool simd) {
        Scene s = test::tank_scene(Vec3d(0.16, 0.2, 0.1), Vec3d(0.3, 0.3, 0.1));
        s.fluid.viscosity = 0.1;
        s.fluid.support = support;
        s.simulation.simd = simd;
        initialise_world(w, s);
        // Jitter and give random velocities so that every term is exercised.
        std::mt19937 rng(11);
        std::uniform_real_distribution<Real> u(-1, 1);
        auto x = w.fluid.store.get(comp::position);
        auto v = w.fluid.store.get(comp::velocity);
        for (std::size_t i = 0; i < x.size(); ++i) {
            x[i] += Vec3(u(rng), u(rng), u(rng)) * (0.3f * w.physics.particle_radius);
            x[i] = x[i].cwiseMax(Vec3::Constant(0.002f));
            v[i] = Vec3(u(rng), u(rng), u(rng));
        }
        BoundaryVolumeSystem vol;
        vol.register_components(w);
        run_system(vol, w);
        DensitySystem dens(true);
        ForcesSystem forces(true);
        dens.register_components(w);
        forces.register_components(w);
        run_system(FluidGridSystem(), w);
        run_system(FluidNeighbourSystem(), w);
        run_system(BoundaryNeighbourSystem(), w);
        run_system(dens, w);
        run_system(forces, w);
    }
};

class BruteForce : public ::testing::TestWithParam<std::tuple<double, bool>> {
protected:
    double support() const { return std::get<0>(GetParam()); }
    bool simd() const { return std::get<1>(GetParam()); }
};

}  // namespace

TEST_P(BruteForce, BoundaryVolumeDensityAndForces) {
    Fixture f(support(), simd());
    const World& w = f.w;
    ASSERT_FLOAT_EQ(w.physics.h, float(support() * 2 * w.physics.particle_radius));
    ASSERT_EQ(w.physics.simd, simd());
    const auto x = w.fluid.store.get(comp::position);
    const auto v = w.fluid.store.get(comp::velocity);
    const auto xb = w.boundary.store.get(comp::position);
    const auto vb = w.boundary.store.get(comp::volume);
    const auto rho = w.fluid.store.get(comp::density);
    const auto p = w.fluid.store.get(comp::pressure);
    const auto acc = w.fluid.store.get(comp::acceleration);
    const CubicSpline& k = w.kernel;
    const Physics& ph = w.physics;
    ASSERT_GT(x.size(), 300u);
    ASSERT_GT(xb.size(), 300u);

    // Akinci eq. 4 scaled by gamma, all pairs. The scaling's contract, checked on the system's
    // output and not on gamma's formula: a particle in the middle of a flat wall (every wall
    // particle within h of it in its own plane) gets exactly the fluid particle volume s^3.
    // Tolerance 1e-5 relative: float sums of ~30 terms.
    const double gamma = boundary_volume_gamma(k, ph.spacing);
    {
        const double s3 = std::pow(double(ph.spacing), 3);
        std::size_t flat = 0;
        for (std::size_t b = 0; b < xb.size(); ++b) {
            bool in_plane[3] = {true, true, true};
            for (std::size_t c = 0; c < xb.size(); ++c)
                if ((xb[b] - xb[c]).norm() < ph.h)
                    for (int a = 0; a < 3; ++a) in_plane[a] = in_plane[a] && std::abs(xb[b][a] - xb[c][a]) < 1e-6f;
            if (!(in_plane[0] || in_plane[1] || in_plane[2])) continue;
            ++flat;
            EXPECT_NEAR(vb[b], s3, 1e-5 * s3) << "boundary particle " << b << " in the middle of a wall";
        }
        ASSERT_GT(flat, 10u) << "the tank must have wall particles farther than h from every edge";
    }
    for (std::size_t b = 0; b < xb.size(); ++b) {
        double sum = 0;
        for (std::size_t c = 0; c < xb.size(); ++c) sum += k.w((xb[b] - xb[c]).norm());
        EXPECT_NEAR(vb[b], gamma / sum, 1e-5 * gamma / sum) << "boundary particle " << b;
    }
    // Density: He eq. 1 + Akinci eq. 6 over all pairs; pressure: He eq. 2.
    // Tolerance 1e-5 relative (float accumulation of ~60 terms of similar size).
    std::vector<double> rho_ref(x.size());
    for (std::size_t i = 0; i < x.size(); ++i) {
        double s = 0;
        for (std::size_t j = 0; j < x.size(); ++j) s += ph.mass * k.w((x[i] - x[j]).norm());
        for (std::size_t b = 0; b < xb.size(); ++b) s += ph.rest_density * vb[b] * k.w((x[i] - xb[b]).norm());
        rho_ref[i] = s;
        EXPECT_NEAR(rho[i], s, 1e-5 * s) << "fluid particle " << i;
        const double ratio = std::max(s, double(ph.rest_density)) / ph.rest_density;
        const double p_ref = ph.tait_b * (std::pow(ratio, 7) - 1);
        // The EOS amplifies the density's relative error 7 times: 1e-4 of B.
        EXPECT_NEAR(p[i], p_ref, 1e-4 * ph.tait_b) << "fluid particle " << i;
    }
    // Forces: tolerance 1e-4 of the largest acceleration (float sums with cancellation).
    double amax = 0;
    for (const auto& a : acc) amax = std::max(amax, double(a.norm()));
    ASSERT_GT(amax, 10.0);
    for (std::size_t i = 0; i < x.size(); ++i) {
        Vec3d a = ph.gravity.cast<double>();
        const double pi = p[i] / (double(rho[i]) * rho[i]);
        for (std::size_t j = 0; j < x.size(); ++j) {
            if (j == i) continue;
            const Vec3 xij = x[i] - x[j];
            const Real r = xij.norm();
            if (r >= ph.h) continue;
            const Vec3d grad = k.grad(xij, r).cast<double>();
            const double visc = monaghan_pi((v[i] - v[j]).dot(xij), xij.squaredNorm(), ph.viscosity, ph.speed_of_sound,
                                            ph.h, rho[i], rho[j]);
            a -= ph.mass * (pi + p[j] / (double(rho[j]) * rho[j]) + visc) * grad;
        }
        for (std::size_t b = 0; b < xb.size(); ++b) {
            const Vec3 xib = x[i] - xb[b];
            const Real r = xib.norm();
            if (r >= ph.h) continue;
            const Vec3d grad = k.grad(xib, r).cast<double>();
            const double visc = monaghan_pi(v[i].dot(xib), xib.squaredNorm(), ph.viscosity, ph.speed_of_sound, ph.h,
                                            rho[i], ph.rest_density);
            a -= ph.rest_density * vb[b] * (2 * pi + visc) * grad;
        }
        EXPECT_NEAR((acc[i].cast<double>() - a).norm(), 0.0, 1e-4 * amax) << "fluid particle " << i;
    }
}

// The mass rule: a particle inside a filled lattice has exactly the rest density.
TEST_P(BruteForce, LatticeMassGivesRestDensityInside) {
    World w;
    Scene s = test::tank_scene(Vec3d(0.2, 0.2, 0.2), Vec3d(0.3, 0.3, 0.3));
    s.fluid.support = support();
    initialise_world(w, s);
    const auto x = w.fluid.store.get(comp::position);
    const Vec3 centre(0.1f, 0.1f, 0.1f);
    std::size_t inner = 0;
    for (std::size_t i = 0; i < x.size(); ++i) {
        if ((x[i] - centre).cwiseAbs().maxCoeff() > 0.1f - w.physics.h - 0.011f) continue;  // needs a full neighbourhood
        double s = 0;
        for (std::size_t j = 0; j < x.size(); ++j) s += w.physics.mass * w.kernel.w((x[i] - x[j]).norm());
        EXPECT_NEAR(s, 1000.0, 1e-3) << "particle " << i;
        ++inner;
    }
    EXPECT_GT(inner, 0u);
}

INSTANTIATE_TEST_SUITE_P(Support, BruteForce, ::testing::Combine(::testing::Values(2.0, 3.0), ::testing::Bool()),
                         [](const auto& info) {
                             return std::string(std::get<0>(info.param) == 2.0 ? "default2" : "wide3") +
                                    (std::get<1>(info.param) ? "_simd" : "_scalar");
                         });
