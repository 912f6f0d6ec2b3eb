// scenes/hydrostatic_tank.json: water at rest. After settling, the pressure at depth d must be
// rho0 g d (shared/validation/analytical_references.md, section 1) within 5 %; no particle may
// leave the tank; the maximum density error stays below 3 %.
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

}  // namespace

TEST(HydrostaticTank, PressureMatchesRhoGDepth) {
    const Scene scene = load_scene(SPH_SOURCE_DIR "/scenes/hydrostatic_tank.json");
    auto sim = make_simulation(scene);
    double late_rho_err_max = 0;
    const double settle = scene.simulation.end_time;
    sim->run_until(settle, [&](const Simulation& s) {
        if (s.time() > 0.75 * settle) late_rho_err_max = std::max(late_rho_err_max, s.world().step.rho_err_max);
    });
    const World& w = sim->world();
    const double surface = scene.fluid_blocks[0].box.max.y();  // initial free surface, 0.4 m
    const double rho0 = w.physics.rest_density, g = 9.81;
    for (double d : {0.1, 0.2, 0.3}) {
        const Vec3 point(0.15f, Real(surface - d), 0.15f);
        const double p = pressure_at(w, point);
        const double expect = rho0 * g * d;
        EXPECT_NEAR(p, expect, 0.05 * expect) << "depth " << d << " m";
        std::printf("hydrostatic: depth %.2f m  p = %.1f Pa  rho0 g d = %.1f Pa  error %+.2f %%\n", d, p, expect,
                    100.0 * (p - expect) / expect);
    }
    const auto x = w.fluid.store.get(comp::position);
    const Aabb tank = scene.boundaries[0].box;
    for (std::size_t i = 0; i < x.size(); ++i) ASSERT_TRUE(tank.contains(x[i].cast<double>())) << "particle " << i;
    EXPECT_LT(late_rho_err_max, 0.03);
    std::printf("hydrostatic: max density error over the last quarter %.3f %%\n", 100 * late_rho_err_max);
}
