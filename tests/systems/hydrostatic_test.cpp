// scenes/hydrostatic_tank.json: water at rest. After settling, the pressure at depth d must be
// rho0 g d (shared/validation/analytical_references.md, section 1) within 5 %; no particle may
// leave the tank; the maximum density error stays below 3 %. Why 5 % and not less: the
// symmetric SPH pressure gradient with the cubic spline at h = 2 spacings is biased by a few
// per cent on a disordered particle set, and the tank still sloshes slightly after 2 s.
#include <gtest/gtest.h>

#include "engine/components.hpp"
#include "systems/methods/wcsph.hpp"

using namespace sph;

namespace {

// Shepard-normalised SPH interpolation of the pressure at a point (kernel-weighted average
// of nearby particles' pressures; normalising removes the kernel-truncation bias).
double pressure_at(const World& w, const Vec3& point) {
    const auto x = w.fluid.store.get(comp::position);
    const auto p = w.fluid.store.get(comp::pressure);
    const auto rho = w.fluid.store.get(comp::density);
    double num = 0, den = 0;
    for (std::size_t j = 0; j < x.size(); ++j) {
        const double wj = w.kernel.w((point - x[j]).norm()) * w.physics.mass / rho[j];
        num += wj * p[j];
        den += wj;
    }
    return den > 0 ? num / den : 0.0;
}

double colour_at(const World& w, const Vec3& point) {
    const auto x = w.fluid.store.get(comp::position);
    const auto rho = w.fluid.store.get(comp::density);
    double c = 0;
    for (std::size_t j = 0; j < x.size(); ++j) c += w.kernel.w((point - x[j]).norm()) * w.physics.mass / rho[j];
    return c;
}

}  // namespace

double free_surface(const World& w) {
    for (double y = 0.3; y < 0.5; y += 2e-4)
        if (colour_at(w, Vec3(0.15f, Real(y), 0.15f)) < 0.5) return y;
    return 0.5;
}

// After 2 s of settling, the pressure at depths 0.1, 0.2 and 0.3 m below the free surface is
// averaged over the last third of the run (50 samples): the tank keeps a slow slosh of a
// few per cent that a single snapshot would alias. The free surface is where the
// kernel-interpolated colour function sum_j (m/rho_j) W falls to 0.5 on the centre line: the
// lattice relaxes and the column rises by a few millimetres, so depth is measured from where
// the surface is, not where it began.
TEST(HydrostaticTank, PressureMatchesRhoGDepth) {
    const Scene scene = load_scene(SPH_SOURCE_DIR "/scenes/hydrostatic_tank.json");
    auto sim = make_simulation(scene);
    const double end = scene.simulation.end_time, window = end / 3.0;
    const std::vector<double> depths{0.1, 0.2, 0.3};
    std::vector<double> sum(depths.size(), 0.0);
    int samples = 0;
    double late_rho_err_max = 0, surface_sum = 0, next = end - window;
    sim->run_until(end, [&](const Simulation& s) {
        if (s.time() < end - window) return;
        late_rho_err_max = std::max(late_rho_err_max, s.world().step.rho_err_max);
        if (s.time() + 1e-9 < next) return;
        next += window / 50.0;
        const double surface = free_surface(s.world());
        surface_sum += surface;
        for (std::size_t k = 0; k < depths.size(); ++k)
            sum[k] += pressure_at(s.world(), Vec3(0.15f, Real(surface - depths[k]), 0.15f));
        ++samples;
    });
    ASSERT_GE(samples, 40);
    const World& w = sim->world();
    const double rho0 = w.physics.rest_density, g = 9.81;
    std::printf("hydrostatic: free surface at y = %.4f m on average (0.4 m at the start), %d samples\n",
                surface_sum / samples, samples);
    for (std::size_t k = 0; k < depths.size(); ++k) {
        const double p = sum[k] / samples, expect = rho0 * g * depths[k];
        EXPECT_NEAR(p, expect, 0.05 * expect) << "depth " << depths[k] << " m";
        std::printf("hydrostatic: depth %.2f m  p = %.1f Pa  rho0 g d = %.1f Pa  error %+.2f %%\n", depths[k], p, expect,
                    100.0 * (p - expect) / expect);
    }
    const auto x = w.fluid.store.get(comp::position);
    const Aabb tank = scene.boundaries[0].box;
    for (std::size_t i = 0; i < x.size(); ++i) ASSERT_TRUE(tank.contains(x[i].cast<double>())) << "particle " << i;
    EXPECT_LT(late_rho_err_max, 0.03);
    std::printf("hydrostatic: max density error over the last third %.3f %%\n", 100 * late_rho_err_max);
}
