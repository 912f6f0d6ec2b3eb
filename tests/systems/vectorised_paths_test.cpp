// The vectorised pair loops (simulation.simd: Highway, dispatched to AVX-512/AVX2 at run time)
// against the scalar reference loops on identical inputs: the same neighbour lists, then
// density and pressure (He eq. 1-2, Akinci eq. 6), then accelerations and drho/dt (He eq. 4-5,
// Monaghan viscosity, Akinci boundary terms) with a moving body, so that the relative boundary
// velocity v_i - v_b is exercised. Individual stepping's first step (every particle due) runs
// every term, drho/dt included. The differences are float reassociation only (the vector loops
// sum lanes in another order): tolerances below are stated where asserted.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>

#include "simd_test_targets.hpp"  // before any other Highway header (the engine's target list)

#include "engine/core/simd.hpp"
#include "engine/data/components.hpp"
#include "engine/run/simulation.hpp"
#include "systems/methods/recipes.hpp"
#include "systems/methods/wcsph.hpp"
#include "systems/pcisph/pcisph_components.hpp"
#include "systems/pcisph/pcisph_density_system.hpp"
#include "systems/pcisph/pcisph_pressure_force_system.hpp"
#include "test_scenes.hpp"

using namespace sph;

namespace {

struct Harness {
    World w;
    Recipe recipe;
    std::map<std::string, System*> by_name;

    explicit Harness(SteppingMode mode, double nu = 0, bool corrected = false) {
        Scene s = test::tank_scene(Vec3d(0.3, 0.16, 0.1), Vec3d(0.4, 0.3, 0.1));
        s.fluid.viscosity = 0.1;
        if (corrected) s.fluid.pressure_gradient = PressureGradient::Corrected;
        s.fluid.kinematic_viscosity = nu;  // the laminar term (Morris et al. 1997), also against the walls
        s.simulation.stepping.mode = mode;
        // A paddle inside the fluid, moving through it at 0.5 m/s.
        BoundaryDesc paddle;
        paddle.shape = BoundaryShape::Box;
        paddle.box = Aabb{Vec3d(0.12, 0.02, 0.0), Vec3d(0.16, 0.25, 0.1)};
        Motion m;
        m.type = MotionType::Linear;
        m.velocity = Vec3d(0.5, 0, 0);
        paddle.motion = m;
        s.boundaries.push_back(paddle);
        initialise_world(w, s);
        recipe = make_wcsph_recipe(s);
        for (auto& sys : recipe.setup) sys->register_components(w);
        for (auto& sys : recipe.step) sys->register_components(w), by_name[sys->name()] = sys.get();
        for (auto& sys : recipe.setup) run_system(*sys, w);
        test::jitter(w, 5, 0.3f);
        std::mt19937 rng(9);
        std::uniform_real_distribution<Real> u(-1, 1);
        for (auto& v : w.fluid.store.get(comp::velocity)) v = Vec3(u(rng), u(rng), u(rng));
        w.step_size.set(1e-4);
    }
    void run(const std::string& name) {
        ASSERT_TRUE(by_name.count(name)) << name;
        run_system(*by_name[name], w);
    }
};

template <class T>
std::vector<T> copy(std::span<const T> s) {
    return {s.begin(), s.end()};
}

void compare_paths(SteppingMode mode, double nu = 0, bool corrected = false) {
    Harness H(mode, nu, corrected);
    World& w = H.w;
    const bool individual = mode == SteppingMode::Individual;
    ASSERT_TRUE(w.physics.simd);
    // Everything before the pair loops, once: lists, active set (all due at t = 0), motion.
    for (auto& sys : H.recipe.step) {
        if (sys->name() == "density") break;
        run_system(*sys, w);
    }
    ASSERT_GT(w.fluid_neighbours.rows(), 0u);
    ASSERT_GT(w.boundary.store.get(comp::velocity).size(), 0u);

    // Density and pressure: the same inputs, both paths.
    H.run("density");
    const auto rho_simd = copy<Real>(w.fluid.store.get(comp::density));
    const auto p_simd = copy<Real>(w.fluid.store.get(comp::pressure));
    w.physics.simd = false;
    H.run("density");
    const auto rho = w.fluid.store.get(comp::density);
    const auto p = w.fluid.store.get(comp::pressure);
    const std::size_t n = rho.size();
    ASSERT_GT(n, 500u);
    // The pressure difference is measured against the EOS's sensitivity: dp = 7 B (rho/rho0)^7
    // drho/rho, so a density difference e gives at most 7 B (rho/rho0)^7 e.
    const double rho0 = w.physics.rest_density, B = w.physics.tait_b;
    double rho_dev = 0, p_dev = 0, p_max = 0;
    for (std::size_t i = 0; i < n; ++i) {
        rho_dev = std::max(rho_dev, std::abs(double(rho_simd[i]) - rho[i]) / rho[i]);
        const double sensitivity = 7 * B * std::pow(std::max(double(rho[i]), rho0) / rho0, 7);
        p_dev = std::max(p_dev, std::abs(double(p_simd[i]) - p[i]) / sensitivity);
        p_max = std::max(p_max, double(p[i]));
    }
    std::printf("density: largest relative difference %.3g; pressure: %.3g of 7 B (rho/rho0)^7\n", rho_dev, p_dev);
    // ~30 fluid + up to ~40 boundary terms summed in float, in another order: a few ulp.
    EXPECT_LT(rho_dev, 2e-6) << "largest relative density difference";
    // Through the EOS: the density bound, plus the float rounding of p itself (~1e-7 relative).
    EXPECT_LT(p_dev, 2.5e-6) << "largest pressure difference over 7 B (rho/rho0)^7";
    EXPECT_GT(p_max, 0.0);

    // Forces (and drho/dt in individual stepping) on the scalar path's density, both paths
    // (with the correction matrices L_i of that density, Bonet & Lok 1999).
    if (corrected) {
        w.physics.simd = true;
        H.run("gradient_correction");
        const auto L_simd = copy<Mat3>(w.fluid.store.get(comp::gradient_correction));
        w.physics.simd = false;
        H.run("gradient_correction");
        const auto L = w.fluid.store.get(comp::gradient_correction);
        double off_identity = 0, l_dev = 0;
        for (std::size_t i = 0; i < n; ++i) {
            off_identity = std::max(off_identity, double((L[i] - Mat3::Identity()).norm()));
            l_dev = std::max(l_dev, double((L_simd[i] - L[i]).norm() / L[i].norm()));
        }
        ASSERT_GT(off_identity, 0.1) << "the jittered block's L_i should differ from the identity";
        std::printf("gradient correction: largest relative difference of L_i %.3g\n", l_dev);
        // M_i sums ~70 float terms in another order and mirrors its symmetric half; L_i = M_i^-1
        // with eigenvalues clamped at 0.5 amplifies that by at most the condition number (<= 4
        // once clamped): a few ulp times 4.
        EXPECT_LT(l_dev, 5e-6) << "largest relative difference of L_i";
    }
    w.physics.simd = true;
    H.run("forces");
    const auto acc_simd = copy<Vec3>(w.fluid.store.get(comp::acceleration));
    std::vector<Real> drho_simd;
    if (individual) drho_simd = copy<Real>(w.fluid.store.get(comp::drho_dt));
    w.physics.simd = false;
    H.run("forces");
    const auto acc = w.fluid.store.get(comp::acceleration);
    double a_max = 0, a_dev = 0;
    for (std::size_t i = 0; i < n; ++i) {
        a_max = std::max(a_max, double((acc[i] - w.physics.gravity).norm()));
        a_dev = std::max(a_dev, double((acc_simd[i] - acc[i]).norm()));
    }
    ASSERT_GT(a_max, 10.0);
    std::printf("acceleration: largest difference %.3g of the largest |a - g| (%.4g m/s^2)\n", a_dev / a_max, a_max);
    // Sums of ~70 terms with cancellation: 3e-6 of the largest (measured 3.2e-7).
    EXPECT_LT(a_dev, 3e-6 * a_max) << "largest acceleration difference; largest |a - g| " << a_max;
    if (individual) {
        const auto drho = w.fluid.store.get(comp::drho_dt);
        double d_max = 0, d_dev = 0;
        for (std::size_t i = 0; i < n; ++i) {
            d_max = std::max(d_max, double(std::abs(drho[i])));
            d_dev = std::max(d_dev, double(std::abs(drho_simd[i] - drho[i])));
        }
        ASSERT_GT(d_max, 1.0);
        std::printf("drho/dt: largest difference %.3g of the largest (%.4g kg/m^3/s)\n", d_dev / d_max, d_max);
        EXPECT_LT(d_dev, 3e-6 * d_max) << "largest drho/dt difference; largest |drho/dt| " << d_max;
    }
}

}  // namespace

TEST(VectorisedPaths, DispatchesToAVectorTarget) {
    // This machine kind has AVX-512; any x86-64 since 2013 has AVX2. The portable fallback
    // would pass every other test while giving up the speed, so it is named here.
    const std::string target = simd_target();
    EXPECT_TRUE(target == "AVX3" || target == "AVX2") << "dispatched to " << target;
}

// Each comparison below runs once per vectorised target this CPU runs (test::for_each_simd_target),
// so that a machine with AVX-512 also checks the AVX2 code (its row loads in place of gathers).
TEST(VectorisedPaths, GlobalSteppingMatchesScalarWithMovingBody) {
    test::for_each_simd_target([] { compare_paths(SteppingMode::Global); });
}
TEST(VectorisedPaths, IndividualSteppingMatchesScalarWithMovingBody) {
    test::for_each_simd_target([] { compare_paths(SteppingMode::Individual); });
}
// nu = 50 m^2/s (an arithmetic check, not a fluid): with |v_ij| ~ 1 m/s the laminar term,
// ~ nu |v| / h^2 ~ 3e4 m/s^2, is as large as the jittered block's pressure term, so a wrong
// coefficient or sign in either path shows in the same bound.
TEST(VectorisedPaths, LaminarViscosityMatchesScalar) {
    test::for_each_simd_target([] { compare_paths(SteppingMode::Global, 50.0); });
}
// The corrected pressure gradient (Bonet & Lok 1999): the L_j half gathered per pair and the
// L_i half applied once per row, against the scalar loop's (L_i + L_j)/2 grad W_ij per pair;
// individual stepping also checks drho/dt, which keeps the uncorrected gradient (He eq. 5).
TEST(VectorisedPaths, CorrectedGradientMatchesScalar) {
    test::for_each_simd_target([] {
        compare_paths(SteppingMode::Global, 0, true);
        compare_paths(SteppingMode::Individual, 0, true);
    });
}

// PCISPH's pair loops (Ihmsen et al. 2010 eq. 13 predicted density, eq. 6 pressure acceleration
// with the boundary's density and pressure) on a flowing column 40 steps in, on the same inputs.
namespace {
void pcisph_paths() {
    Scene s = test::tank_scene(Vec3d(0.2, 0.25, 0.1), Vec3d(0.5, 0.3, 0.1));
    s.simulation.method = Method::Pcisph;
    s.simulation.stepping.mode = SteppingMode::Adaptive;
    auto sim = make_simulation(s);
    for (int k = 0; k < 40; ++k) sim->step();
    World& w = sim->world();
    ASSERT_TRUE(w.physics.simd);
    const std::size_t n = w.fluid.size();
    ASSERT_GT(n, 500u);
    PcisphDensitySystem density(true);
    PcisphPressureForceSystem pressure(true);
    // The density pass also adds delta (rho* - rho0) to p: both paths start from the same p.
    const auto p0 = copy<Real>(w.fluid.store.get(comp::pressure));
    run_system(density, w);
    const auto rho_simd = copy<Real>(w.fluid.store.get(comp::density));
    std::copy(p0.begin(), p0.end(), w.fluid.store.get(comp::pressure).begin());
    w.physics.simd = false;
    run_system(density, w);
    const auto rho = w.fluid.store.get(comp::density);
    double rho_dev = 0;
    for (std::size_t i = 0; i < n; ++i) rho_dev = std::max(rho_dev, std::abs(double(rho_simd[i]) - rho[i]) / rho[i]);
    std::printf("pcisph density: largest relative difference %.3g\n", rho_dev);
    EXPECT_LT(rho_dev, 2e-6);  // as for WCSPH's density: a few ulp of float sums

    w.physics.simd = true;
    run_system(pressure, w);
    const auto a_simd = copy<Vec3>(w.fluid.store.get(comp::pressure_acceleration));
    w.physics.simd = false;
    run_system(pressure, w);
    const auto a = w.fluid.store.get(comp::pressure_acceleration);
    double a_max = 0, a_dev = 0;
    for (std::size_t i = 0; i < n; ++i) {
        a_max = std::max(a_max, double(a[i].norm()));
        a_dev = std::max(a_dev, double((a_simd[i] - a[i]).norm()));
    }
    ASSERT_GT(a_max, 1.0);
    std::printf("pcisph pressure acceleration: largest difference %.3g of the largest (%.4g m/s^2)\n", a_dev / a_max,
                a_max);
    EXPECT_LT(a_dev, 3e-6 * a_max);
}
}  // namespace

TEST(VectorisedPaths, PcisphDensityAndPressureForceMatchScalar) { test::for_each_simd_target(pcisph_paths); }
