// Every system of individual time stepping (He et al. Alg. 2) against an O(N^2) brute-force
// reference in double precision, with 100 %, 50 %, 10 % and 0 % of the fluid active
// (SWIFT's testActivePair pattern). The fluid is a jittered block with random velocities in
// a container; one full step is taken first so that every particle has lists, densities,
// accelerations and a base state, then a chosen subset is made due and one more step is run
// system by system, checking each against its reference and checking that it left the
// inactive particles alone. Tolerances per field are stated where they are asserted.
#include <gtest/gtest.h>

#include <limits>

#include <algorithm>
#include <map>
#include <random>
#include <set>

#include "engine/data/components.hpp"
#include "engine/run/simulation.hpp"
#include "systems/density/density_kernels.hpp"
#include "systems/forces/forces_kernels.hpp"
#include "systems/methods/recipes.hpp"
#include "systems/methods/wcsph.hpp"
#include "systems/timestep/global_dt_system.hpp"
#include "test_scenes.hpp"

using namespace sph;

namespace {

struct Harness {
    World w;
    Recipe recipe;
    std::map<std::string, System*> by_name;

    Harness(std::uint32_t seed, bool simd) {
        // 800 rows: at 50 % active, dt_propagation's 512-row tasks split (the thread sanitizer's stage
        // sees its per-worker arrays and the halo's collection run concurrently).
        Scene s = test::tank_scene(Vec3d(0.16, 0.2, 0.2), Vec3d(0.3, 0.3, 0.2));
        s.simulation.simd = simd;
        s.fluid.viscosity = 0.1;
        s.simulation.stepping.mode = SteppingMode::Individual;
        s.simulation.stepping.lambda_v = 0.05;
        s.simulation.stepping.lambda_f = 0.025;
        s.simulation.stepping.acoustic = false;
        initialise_world(w, s);
        recipe = make_wcsph_recipe(s);
        for (auto& sys : recipe.setup) sys->register_components(w);
        for (auto& sys : recipe.step) sys->register_components(w), by_name[sys->name()] = sys.get();
        for (auto& sys : recipe.setup) run_system(*sys, w);
        std::mt19937 rng(seed);
        std::uniform_real_distribution<Real> u(-1, 1);
        auto x = w.fluid.store.get(comp::position);
        auto v = w.fluid.store.get(comp::velocity);
        for (std::size_t i = 0; i < x.size(); ++i) {
            x[i] += Vec3(u(rng), u(rng), u(rng)) * (0.3f * w.physics.particle_radius);
            x[i] = x[i].cwiseMax(Vec3::Constant(0.002f));
            v[i] = Vec3(u(rng), u(rng), u(rng));
        }
    }
    void run(const std::string& name) {
        ASSERT_TRUE(by_name.count(name)) << name;
        run_system(*by_name[name], w);
    }
    void run_all() {
        for (auto& sys : recipe.step) run_system(*sys, w);
    }
};

std::vector<Index> brute_neighbours(std::span<const Vec3> x, std::span<const Vec3> y, Index i, Real h, bool self) {
    std::vector<Index> out;
    for (std::size_t j = 0; j < y.size(); ++j)
        if ((x[i] - y[j]).squaredNorm() < h * h && !(self && j == i)) out.push_back(Index(j));
    return out;
}

std::vector<Index> sorted(std::span<const Index> s) {
    std::vector<Index> v(s.begin(), s.end());
    std::sort(v.begin(), v.end());
    return v;
}

void check_fraction(double fraction, bool simd) {
    SCOPED_TRACE("active fraction " + std::to_string(fraction) + (simd ? ", vectorised loops" : ", scalar loops"));
    Harness H(7, simd);
    World& w = H.w;
    const std::size_t n = w.fluid.size();
    ASSERT_GT(n, 300u);
    // Step 0: every particle is due (t_last = 0, dt = 0), so all get lists and forces.
    w.step_size.set(1e-4);
    H.run_all();
    ASSERT_EQ(w.counter_value("active"), n);
    w.clock.t_ticks += w.step_size.dt_ticks;
    w.clock.t = to_seconds(w.clock.t_ticks);
    ++w.clock.step;

    // Make a chosen subset due now: dt_i = t for them (tie: active), 10 t for the others.
    std::mt19937 rng(3);
    std::vector<Index> perm(n);
    for (Index i = 0; i < n; ++i) perm[i] = i;
    std::shuffle(perm.begin(), perm.end(), rng);
    const std::size_t n_active = std::size_t(std::llround(fraction * double(n)));
    std::vector<std::uint8_t> want(n, 0);
    for (std::size_t k = 0; k < n_active; ++k) want[perm[k]] = 1;
    auto dt = w.fluid.store.get(comp::dt);
    for (Index i = 0; i < n; ++i) dt[i] = want[i] ? w.clock.t : 10 * w.clock.t;
    auto v = w.fluid.store.get(comp::velocity);
    for (Index i = 0; i < n; ++i) v[i] += Vec3(0.1f, -0.2f, 0.05f);  // so v differs from the base state

    // --- select_active: exact.
    H.run("select_active");
    const auto active = w.fluid.store.get(comp::active);
    std::vector<Index> want_set;
    for (Index i = 0; i < n; ++i) {
        ASSERT_EQ(active[i], want[i]) << "particle " << i;
        if (want[i]) want_set.push_back(i);
    }
    EXPECT_EQ(w.active_set, want_set);

    // --- neighbour search: active lists equal brute force (as sets); inactive lists untouched.
    const NeighbourLists fl_before = w.fluid_neighbours, bl_before = w.boundary_neighbours;
    H.run("fluid_grid");
    H.run("fluid_neighbours");
    H.run("boundary_neighbours");
    const auto x = w.fluid.store.get(comp::position);
    const auto xb = w.boundary.store.get(comp::position);
    const Real h = w.physics.h;
    std::uint64_t boundary_entries = 0;
    for (Index i = 0; i < n; ++i) {
        if (want[i]) {
            EXPECT_EQ(sorted(w.fluid_neighbours.of(i)), brute_neighbours(x, x, i, h, true)) << "particle " << i;
            EXPECT_EQ(sorted(w.boundary_neighbours.of(i)), brute_neighbours(x, xb, i, h, false)) << "particle " << i;
            boundary_entries += w.boundary_neighbours.size_of(Index(i));
        } else {
            EXPECT_TRUE(std::ranges::equal(w.fluid_neighbours.of(i), fl_before.of(i))) << "particle " << i;
            EXPECT_TRUE(std::ranges::equal(w.boundary_neighbours.of(i), bl_before.of(i))) << "particle " << i;
        }
    }
    EXPECT_EQ(w.counter_value("neighbour_searches"), n_active);
    EXPECT_EQ(w.counter_value("boundary_contributions"), boundary_entries);

    // --- density: active ones equal the O(N^2) sum (1e-5 relative: float sums of ~60 terms);
    // the others keep their values exactly (they carry the interpolated density).
    const std::vector<Real> rho_before(w.fluid.store.get(comp::density).begin(), w.fluid.store.get(comp::density).end());
    H.run("density");
    const auto rho = w.fluid.store.get(comp::density);
    const auto p = w.fluid.store.get(comp::pressure);
    const auto vol = w.boundary.store.get(comp::volume);
    const CubicSpline& k = w.kernel;
    const Physics& ph = w.physics;
    for (Index i = 0; i < n; ++i) {
        if (!want[i]) {
            EXPECT_EQ(rho[i], rho_before[i]) << "particle " << i;
            continue;
        }
        double s = 0;
        for (std::size_t j = 0; j < n; ++j) s += ph.mass * k.w((x[i] - x[j]).norm());
        for (std::size_t b = 0; b < xb.size(); ++b) s += ph.rest_density * vol[b] * k.w((x[i] - xb[b]).norm());
        EXPECT_NEAR(rho[i], s, 1e-5 * s) << "particle " << i;
        EXPECT_EQ(w.fluid.store.get(comp::density_last)[i], rho[i]);
    }

    // --- forces, drho/dt (He eq. 5), dt_raw (line 13), t_last (line 14): active ones against
    // the O(N^2) reference (1e-4 of the largest acceleration / rate: float sums with
    // cancellation); dt_raw to 1e-5 relative; inactive ones untouched.
    const auto acc = w.fluid.store.get(comp::acceleration);
    const std::vector<Vec3> acc_before(acc.begin(), acc.end());
    H.run("forces");
    const auto drho = w.fluid.store.get(comp::drho_dt);
    const auto dt_raw = w.fluid.store.get(comp::dt_raw);
    const auto t_last = w.fluid.store.get(comp::t_last);
    double amax = 0, dmax = 0;
    for (Index i : want_set) amax = std::max(amax, double(acc[i].norm())), dmax = std::max(dmax, double(std::abs(drho[i])));
    for (Index i = 0; i < n; ++i) {
        if (!want[i]) {
            EXPECT_EQ(acc[i], acc_before[i]) << "particle " << i;
            EXPECT_EQ(t_last[i], 0) << "particle " << i;
            continue;
        }
        EXPECT_EQ(t_last[i], w.clock.t_ticks);
        Vec3d a = ph.gravity.cast<double>();
        double d = 0;
        const double pi = p[i] / (double(rho[i]) * rho[i]);
        for (std::size_t j = 0; j < n; ++j) {
            const Vec3 xij = x[i] - x[j];
            const Real r = xij.norm();
            if (j == i || r >= h) continue;
            const Vec3d grad = k.grad(xij, r).cast<double>();
            const double visc = monaghan_pi((v[i] - v[j]).dot(xij), xij.squaredNorm(), ph.viscosity,
                                            ph.speed_of_sound, h, rho[i], rho[j]);
            a -= ph.mass * (pi + p[j] / (double(rho[j]) * rho[j]) + visc) * grad;
            d += ph.mass * (v[i] - v[j]).cast<double>().dot(grad);
        }
        for (std::size_t b = 0; b < xb.size(); ++b) {
            const Vec3 xib = x[i] - xb[b];
            const Real r = xib.norm();
            if (r >= h) continue;
            const Vec3d grad = k.grad(xib, r).cast<double>();
            const double visc = monaghan_pi(v[i].dot(xib), xib.squaredNorm(), ph.viscosity, ph.speed_of_sound, h,
                                            rho[i], ph.rest_density);
            a -= ph.rest_density * vol[b] * (2 * pi + visc) * grad;
            d += ph.rest_density * vol[b] * v[i].cast<double>().dot(grad);
        }
        EXPECT_NEAR((acc[i].cast<double>() - a).norm(), 0.0, 1e-4 * amax) << "particle " << i;
        EXPECT_NEAR(drho[i], d, 1e-4 * dmax) << "particle " << i;
        // He Alg. 2 line 13: dt_raw is the same function as the global step (eq. 6-8), so
        // global_time_step is the oracle here (it is pinned by hand in global_dt_system_test.cpp).
        const double raw = global_time_step(w.scene.simulation.stepping, h, ph.speed_of_sound, v[i].norm(), acc[i].norm());
        EXPECT_NEAR(dt_raw[i], raw, 1e-5 * raw) << "particle " << i;
    }
    EXPECT_EQ(w.counter_value("force_evaluations"), n_active);

    // --- dt propagation (line 16), exact (a minimum of stored values). The halo: the inactive
    // particles within h of an active one (brute force), ascending. For the active and the
    // halo, dt is the minimum of dt_raw over itself, its list, and the active particles that
    // have it in their fresh lists; every other particle keeps its dt.
    const std::vector<double> dt_before(dt.begin(), dt.end());
    H.run("dt_propagation");
    std::set<Index> halo_ref;
    for (Index i : want_set)
        for (Index j : brute_neighbours(x, x, i, h, true))
            if (!want[j]) halo_ref.insert(j);
    EXPECT_EQ(w.halo_set, std::vector<Index>(halo_ref.begin(), halo_ref.end()));
    for (Index i = 0; i < n; ++i) {
        if (!want[i] && !halo_ref.count(i)) {
            EXPECT_EQ(dt[i], dt_before[i]) << "particle " << i;
            continue;
        }
        double m = dt_raw[i];
        for (Index j : w.fluid_neighbours.of(i)) m = std::min(m, dt_raw[j]);
        for (Index a : want_set)
            if ((x[a] - x[i]).squaredNorm() < h * h && a != i) m = std::min(m, dt_raw[a]);
        EXPECT_EQ(dt[i], m) << "particle " << i;
    }
    EXPECT_EQ(w.counter_value("propagation_updates"), n_active + halo_ref.size());

    // --- global dt (line 17): the minimum over all particles, in whole ticks. Under the
    // `deadline` activation rule (select_active_system.hpp) the step also stops at the earliest
    // deadline t_last + Delta t_i of an inactive particle still ahead, but never below the
    // last stable step; recomputed here by a plain loop.
    const Tick floor_ticks = std::max<Tick>(1, to_ticks(w.step_size.dt_stable));
    Tick next = std::numeric_limits<Tick>::max();
    for (Index i = 0; i < n; ++i) {
        const Tick due = t_last[i] + to_ticks(dt[i]);
        if (!active[i] && due > w.clock.t_ticks) next = std::min(next, due);
    }
    H.run("individual_dt");
    const double dt_min = std::min(*std::min_element(dt.begin(), dt.end()), w.scene.simulation.stepping.dt_max);
    Tick expected = to_ticks(dt_min);
    if (next != std::numeric_limits<Tick>::max()) expected = std::min(expected, std::max(next - w.clock.t_ticks, floor_ticks));
    EXPECT_EQ(w.step_size.dt_ticks, expected);
    // With none active the step is set by the sleeping particles alone: the cap must bind there.
    if (fraction == 0.0) {
        EXPECT_LT(expected, to_ticks(dt_min)) << "the deadline cap is not exercised";
    }

    // --- asynchronous integration (lines 18-21 and 9): every particle from its base state,
    // Delta = t + Delta t_sim - t_last, against double arithmetic (1e-6 relative: one float
    // rounding per operation on values of order 1).
    const std::vector<Vec3> x_prev(x.begin(), x.end()), v_prev(v.begin(), v.end());
    const auto x0 = w.fluid.store.get(comp::position_last);
    const auto v0 = w.fluid.store.get(comp::velocity_last);
    const std::vector<Vec3> x0_prev(x0.begin(), x0.end()), v0_prev(v0.begin(), v0.end());
    const std::vector<Real> rho_last(w.fluid.store.get(comp::density_last).begin(),
                                     w.fluid.store.get(comp::density_last).end());
    H.run("async_integrate");
    const Tick t_end = w.clock.t_ticks + w.step_size.dt_ticks;
    for (Index i = 0; i < n; ++i) {
        const Vec3d bx = (want[i] ? x_prev[i] : x0_prev[i]).cast<double>();
        const Vec3d bv = (want[i] ? v_prev[i] : v0_prev[i]).cast<double>();
        const double delta = to_seconds(t_end - t_last[i]);
        const Vec3d vn = bv + delta * acc[i].cast<double>();
        const Vec3d xn = bx + delta * vn;
        EXPECT_NEAR((v[i].cast<double>() - vn).norm(), 0.0, 1e-6 * (1 + vn.norm())) << "particle " << i;
        EXPECT_NEAR((x[i].cast<double>() - xn).norm(), 0.0, 1e-6 * (1 + xn.norm())) << "particle " << i;
        const double rn = rho_last[i] + delta * drho[i];
        EXPECT_NEAR(rho[i], rn, 1e-6 * rn) << "particle " << i;
        if (want[i]) {
            EXPECT_EQ(x0[i], x_prev[i]) << "base state of active particle " << i;
        }
    }
}

}  // namespace

// Each on the vectorised pair loops (simulation.simd) and on the scalar reference loops.
TEST(IndividualSystems, AllActiveMatchesBruteForce) { for (bool simd : {true, false}) check_fraction(1.0, simd); }
TEST(IndividualSystems, HalfActiveMatchesBruteForce) { for (bool simd : {true, false}) check_fraction(0.5, simd); }
TEST(IndividualSystems, TenPercentActiveMatchesBruteForce) { for (bool simd : {true, false}) check_fraction(0.1, simd); }
TEST(IndividualSystems, NoneActiveMatchesBruteForce) { for (bool simd : {true, false}) check_fraction(0.0, simd); }
