// PCISPH with Ihmsen et al. 2010 boundary handling: the prototype delta (eq. 4-5), compression
// resolved by the iterations, direct forcing against a fast particle (eq. 9-12), the rest
// density of the boundary particles (eq. 13), and the shock rollback (eq. 24-27).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <numbers>

#include "engine/data/components.hpp"
#include "systems/pcisph/pcisph_components.hpp"
#include "engine/core/errors.hpp"
#include "systems/methods/recipes.hpp"
#include "systems/pcisph/pcisph_kernels.hpp"
#include "systems/pcisph/pcisph_state.hpp"
#include "systems/timestep/adaptive_controller.hpp"
#include "test_scenes.hpp"

using namespace sph;

namespace {

Scene pcisph_scene(Scene s, SteppingMode mode) {
    s.simulation.method = Method::Pcisph;
    s.simulation.stepping.mode = mode;
    s.fluid.viscosity = 0;
    return s;
}

// Ground truth for eq. 4 written out from Monaghan's cubic spline, in double and independent
// of engine/kernel.hpp: |grad W| = |dW/dq| / h with W = sigma (6 (q^3 - q^2) + 1) for q <= 1/2
// and 2 sigma (1 - q)^3 for q <= 1, sigma = 8 / (pi h^3).
double analytic_prototype_sum(double h, double s) {
    const double sigma = 8.0 / (std::numbers::pi * h * h * h);
    double sum_sq = 0;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int k = -3; k <= 3; ++k)
        for (int j = -3; j <= 3; ++j)
            for (int i = -3; i <= 3; ++i) {
                const Eigen::Vector3d x = s * Eigen::Vector3d(i, j, k);
                const double r = x.norm(), q = r / h;
                if (r == 0 || q >= 1) continue;
                const double dwdq = q <= 0.5 ? sigma * (18 * q * q - 12 * q) : -6 * sigma * (1 - q) * (1 - q);
                const Eigen::Vector3d g = -x / r * dwdq / h;  // x_ij = x_i - x_j = -x
                sum += g;
                sum_sq += g.squaredNorm();
            }
    return sum.squaredNorm() + sum_sq;
}

}  // namespace

// delta of eq. 4-5 equals the prototype sum written out independently, for the first step and
// after the adaptive controller changed dt (delta is recomputed: delta dt^2 is constant).
// Tolerance 1e-5 relative: the engine sums float gradients (7 significant digits) over the
// 56 lattice neighbours inside h = 2 r0.
TEST(PcisphPrototype, DeltaEqualsAnalyticPrototypeSum) {
    Scene s = pcisph_scene(test::tank_scene(Vec3d(0.2, 0.2, 0.2), Vec3d(0.3, 0.3, 0.3)), SteppingMode::Adaptive);
    auto sim = make_simulation(s);
    const auto& w = sim->world();
    const double h = w.physics.h, r0 = w.physics.spacing;
    const double S = analytic_prototype_sum(h, r0);
    // The filled lattice is symmetric: sum_j grad W_ij vanishes and only sum |grad W|^2 remains.
    EXPECT_NEAR(pcisph_prototype_sum(w.kernel, r0) / S, 1.0, 1e-5);
    const double m = w.physics.mass, rho0 = w.physics.rest_density;
    auto expected_delta = [&](double dt) { return 1.0 / (2.0 * std::pow(m * dt / rho0, 2) * S); };
    double first_dt = 0;
    int changes = 0;
    for (int k = 0; k < 20; ++k) {
        sim->step();
        const double dt = w.resources.get<PcisphDelta>(res::pcisph_delta.name).delta_dt;
        EXPECT_EQ(dt, w.step_size.dt);
        EXPECT_NEAR(w.resources.get<PcisphDelta>(res::pcisph_delta.name).delta / expected_delta(dt), 1.0, 1e-5) << "step " << k;
        if (k == 0) first_dt = dt;
        if (dt != first_dt) ++changes;
    }
    EXPECT_GT(changes, 0) << "the controller never changed dt: the recomputation is untested";
}

// A block compressed by 3 % (lattice spacing 0.99 r0: rho = rho0 / 0.99^3 inside), no gravity,
// no boundary. The Solenthaler-Pajarola loop must converge (max predicted error <= eta before
// max_iterations), and a brute-force summation on the positions the step ends at must show
// every particle within eta = 0.5 % of rho0 (compressions; the free surface is thinner).
TEST(PcisphCompression, CompressedBlockReachesEta) {
    Scene s;
    s.name = "compressed";
    s.fluid.particle_radius = 0.01;
    s.simulation.gravity = Vec3d::Zero();
    s.simulation.frame_rate = 0;
    s.simulation.method = Method::Pcisph;
    s.simulation.stepping.mode = SteppingMode::Constant;
    s.simulation.stepping.dt = 2e-3;
    s.fluid.viscosity = 0;
    s.pcisph.loop = PcisphLoop::UntilConverged;
    s.pcisph.eta = 0.005;
    s.pcisph.max_iterations = 200;
    s.domain = Aabb{Vec3d::Constant(-0.5), Vec3d::Constant(0.5)};
    s.fluid_blocks.push_back(FluidBlock{Aabb{Vec3d::Zero(), Vec3d::Constant(0.2)}, Vec3d::Zero(), false});
    auto sim = make_simulation(s);
    World& w = sim->world();
    auto x = w.fluid.store.get(comp::position);
    for (auto& p : x) p = (Vec3::Constant(0.1f) + Real(0.99) * (p - Vec3::Constant(0.1f))).eval();
    auto brute_max_err = [&]() {
        const auto xs = w.fluid.store.get(comp::position);
        double worst = 0;
        for (std::size_t i = 0; i < xs.size(); ++i) {
            double rho = 0;
            for (std::size_t j = 0; j < xs.size(); ++j) rho += w.physics.mass * w.kernel.w((xs[i] - xs[j]).norm());
            worst = std::max(worst, rho / w.physics.rest_density - 1.0);
        }
        return worst;
    };
    const double before = brute_max_err();
    ASSERT_GT(before, 0.025);  // the set-up is compressed by ~3 %
    sim->step();
    EXPECT_LT(w.resources.get<PcisphErrors>(res::pcisph_errors.name).iterations, 200) << "the loop did not converge";
    EXPECT_LE(w.resources.get<PcisphErrors>(res::pcisph_errors.name).pred_err_max, 0.005);
    const double after = brute_max_err();
    std::printf("compression: max rho_err %.4f before, %.5f after %d iterations (predicted %.5f)\n", before, after,
                w.resources.get<PcisphErrors>(res::pcisph_errors.name).iterations, w.resources.get<PcisphErrors>(res::pcisph_errors.name).pred_err_max);
    EXPECT_LE(after, 0.005) << "before " << before << ", iterations " << w.resources.get<PcisphErrors>(res::pcisph_errors.name).iterations;
}

// A slab of fluid fired at 20 m/s into a container wall (no gravity). With the Ihmsen boundary
// and direct forcing alone, no particle centre may end a step beyond the wall surface, and the
// analytic safety net behind it must never act. Run in `adaptive` (initial dt = 0.25 h / v0)
// and in `constant` with dt = 0.4 h / v0, the longest step eq. 23 lets the controller keep.
TEST(PcisphPenetration, FastSlabNeverEndsInsideTheWall) {
    for (const SteppingMode mode : {SteppingMode::Adaptive, SteppingMode::Constant}) {
        Scene s = pcisph_scene(test::tank_scene(Vec3d(0.1, 0.1, 0.1), Vec3d(0.5, 0.3, 0.3)), mode);
        s.fluid_blocks[0].box = Aabb{Vec3d(0.3, 0.1, 0.1), Vec3d(0.36, 0.16, 0.16)};
        s.fluid_blocks[0].velocity = Vec3d(20.0, 0, 0);
        s.simulation.gravity = Vec3d::Zero();
        s.simulation.stepping.dt = 0.4 * 0.04 / 20.0;
        auto sim = make_simulation(s);
        double deepest = -1;  // largest x - wall, m (negative: short of the wall)
        std::uint64_t net = 0;
        sim->run_until(0.03, [&](const Simulation& sm) {
            for (const auto& p : sm.world().fluid.store.get(comp::position)) deepest = std::max(deepest, double(p.x()) - 0.5);
            net += sm.world().counter_value("collisions");
        });
        SCOPED_TRACE(to_string(mode));
        std::printf("penetration (%s): deepest centre %.4f m from the wall surface, %lld steps\n", to_string(mode),
                    deepest, static_cast<long long>(sim->steps()));
        EXPECT_LT(deepest, 0.0);
        EXPECT_EQ(net, 0u) << "the analytic safety net had to act";
        // The slab reached the wall (it is not a test of nothing): within two radii of it.
        EXPECT_GT(deepest, -0.02);
    }
}

// Boundary density (eq. 13 with the fluid term mirrored) under fluid at rest on a flat wall:
// the floor particles under the middle of a resting block have rho_b within 3 % of rho0 (the
// boundary plane is sampled with Akinci's volumes, the fluid with the lattice mass, so the two
// sums agree only to the kernel's lattice-sum error), and p_b = 0 at rest.
TEST(PcisphBoundary, RestDensityOnFlatWall) {
    Scene s = pcisph_scene(test::tank_scene(Vec3d(0.3, 0.1, 0.3), Vec3d(0.3, 0.3, 0.3)), SteppingMode::Constant);
    s.simulation.gravity = Vec3d::Zero();
    s.simulation.stepping.dt = 1e-3;
    auto sim = make_simulation(s);
    sim->step();
    const World& w = sim->world();
    const auto xb = w.boundary.store.get(comp::position);
    const auto rho = w.boundary.store.get(comp::density);
    int checked = 0;
    for (Index b : w.resources.get<BoundaryActive>(res::boundary_active.name).set) {
        const Vec3 p = xb[b];
        if (p.y() > 0 || p.x() < 0.1 || p.x() > 0.2 || p.z() < 0.1 || p.z() > 0.2) continue;
        EXPECT_NEAR(rho[b] / w.physics.rest_density, 1.0, 0.03) << "boundary particle at " << p.transpose();
        if (checked == 0) std::printf("floor boundary particle rho_b / rho0 = %.4f\n", rho[b] / w.physics.rest_density);
        ++checked;
    }
    EXPECT_GT(checked, 10);
}

// Shock rollback: after a few steps, one particle's velocity is set so that eq. 27 holds. The
// step detects the shock, restores the state saved two steps back bit for bit (every fluid and
// boundary column), and the next step takes the dt of eq. 24 computed from the shock step's
// v_max and F_max.
TEST(PcisphShock, RollbackRestoresStateBitForBitAndResumesWithEq24) {
    Scene s = pcisph_scene(test::tank_scene(Vec3d(0.2, 0.2, 0.1), Vec3d(0.3, 0.3, 0.1)), SteppingMode::Adaptive);
    auto sim = make_simulation(s);
    World& w = sim->world();
    for (int k = 0; k < 5; ++k) sim->step();
    ASSERT_EQ(w.clock.rollbacks, 0u);
    // Copy of every column at the start of the step before the shock step.
    auto copy = [](const ComponentStore& st) {
        ComponentStore::Snapshot snap;
        st.save(snap);
        return snap;
    };
    const auto fluid_before = copy(w.fluid.store);
    const auto boundary_before = copy(w.boundary.store);
    const Tick t_before = w.clock.t_ticks;
    sim->step();  // kept
    const double dt_kept = w.step_size.dt;
    // Forced shock: one particle at 0.5 h / dt (eq. 27 needs > 0.45 h / dt).
    w.fluid.store.get(comp::velocity)[0] = Vec3(Real(0.5 * w.physics.h / dt_kept), 0, 0);
    sim->step();
    ASSERT_EQ(w.clock.rollbacks, 1u);
    EXPECT_TRUE(sim->last().rolled_back);
    EXPECT_EQ(w.clock.t_ticks, t_before);
    const double v = w.stats.v_max, f = w.stats.a_max;  // the shock step's statistics
    const double eq24 = std::min({0.2 * std::sqrt(w.physics.h / f), 0.25 * w.physics.h / v, s.simulation.stepping.dt_max});
    {  // the same columns, the same sizes
        ComponentStore::Snapshot now;
        w.fluid.store.save(now);
        ASSERT_EQ(now.size, fluid_before.size);
        ASSERT_EQ(now.columns.size(), fluid_before.columns.size());
    }
    // Bitwise comparison of the columns that matter, typed.
    auto eq_vec = [](std::span<const Vec3> a, const ComponentStore::Snapshot& snap, const char* name) {
        const auto& col = static_cast<const Column<Vec3>&>(*snap.columns.at(name)).data;
        ASSERT_EQ(a.size(), col.size());
        EXPECT_EQ(std::memcmp(a.data(), col.data(), a.size_bytes()), 0) << name;
    };
    auto eq_real = [](std::span<const Real> a, const ComponentStore::Snapshot& snap, const char* name) {
        const auto& col = static_cast<const Column<Real>&>(*snap.columns.at(name)).data;
        ASSERT_EQ(a.size(), col.size());
        EXPECT_EQ(std::memcmp(a.data(), col.data(), a.size_bytes()), 0) << name;
    };
    eq_vec(w.fluid.store.get(comp::position), fluid_before, "position");
    eq_vec(w.fluid.store.get(comp::velocity), fluid_before, "velocity");
    eq_vec(w.fluid.store.get(comp::acceleration), fluid_before, "acceleration");
    eq_vec(w.fluid.store.get(comp::pressure_acceleration), fluid_before, "pressure_acceleration");
    eq_vec(w.fluid.store.get(comp::predicted_position), fluid_before, "predicted_position");
    eq_real(w.fluid.store.get(comp::density), fluid_before, "density");
    eq_real(w.fluid.store.get(comp::pressure), fluid_before, "pressure");
    {
        const auto id = w.fluid.store.get(comp::id);
        const auto& col = static_cast<const Column<std::uint32_t>&>(*fluid_before.columns.at("id")).data;
        EXPECT_EQ(std::memcmp(id.data(), col.data(), id.size_bytes()), 0);
    }
    eq_real(w.boundary.store.get(comp::density), boundary_before, "density");
    eq_real(w.boundary.store.get(comp::pressure), boundary_before, "pressure");
    eq_vec(w.boundary.store.get(comp::position), boundary_before, "position");
    // Resumes with eq. 24.
    sim->step();
    EXPECT_FALSE(sim->last().rolled_back);
    EXPECT_EQ(w.step_size.dt, to_seconds(to_ticks(eq24))) << "eq. 24 gives " << eq24;
    EXPECT_LT(w.step_size.dt, dt_kept);
}

// A shock whose eq. 24 step is below dt_min stops the run with a SimulationError naming the
// controller, instead of rolling back forever.
TEST(PcisphShock, ResumeBelowDtMinStopsTheRun) {
    Scene s = pcisph_scene(test::tank_scene(Vec3d(0.2, 0.2, 0.1), Vec3d(0.3, 0.3, 0.1)), SteppingMode::Adaptive);
    auto sim = make_simulation(s);
    World& w = sim->world();
    for (int k = 0; k < 3; ++k) sim->step();
    const double dt = w.step_size.dt;
    w.scene.simulation.stepping.dt_min = 0.9 * dt;  // eq. 24 gives 0.25 h / v = 0.5 dt below
    w.fluid.store.get(comp::velocity)[0] = Vec3(Real(0.5 * w.physics.h / dt), 0, 0);
    try {
        sim->step();
        FAIL() << "no error";
    } catch (const SimulationError& e) {
        EXPECT_EQ(e.system(), "adaptive_dt");
        EXPECT_NE(std::string(e.what()).find("below dt_min"), std::string::npos) << e.what();
    }
}
