// scenes/dam_break.json at its default size reaches 1 s with no NaN (the engine throws a
// SimulationError on any non-finite value) and no leak through the particle boundary.
//
// The run leaves out the collision safety net (boundary_collision, the last system of the
// WCSPH recipe) so that the Akinci particle boundary alone must hold the fluid: the test
// measures how far any particle centre ever gets past the declared wall surface. The wall's
// boundary samples sit one particle radius r behind that surface (engine/sampling.cpp), so a
// penetration of r or more means a particle reached the sample layer, i.e. leaked. Measured
// on 2026-11-23: 4.1 mm = 0.41 r at t = 0.54 s (the impact on the far wall).
#include <gtest/gtest.h>

#include "engine/data/components.hpp"
#include "systems/methods/recipes.hpp"
#include "systems/methods/wcsph.hpp"

using namespace sph;

TEST(DamBreak, ParticleBoundaryAloneHoldsForOneSecond) {
    const Scene scene = load_scene(SPH_SOURCE_DIR "/scenes/dam_break.json");
    Recipe recipe = make_wcsph_recipe(scene);
    ASSERT_EQ(recipe.step.back()->name(), "boundary_collision");
    recipe.step.pop_back();
    Simulation sim(scene, std::move(recipe));
    const Aabb box = scene.boundaries[0].box;
    const double r = scene.fluid.particle_radius;
    double max_err = 0, max_penetration = 0, t_penetration = 0;
    ASSERT_NO_THROW(sim.run_until(1.0, [&](const Simulation& s) {
        max_err = std::max(max_err, s.world().stats.rho_err_max);
        for (const auto& p : s.world().fluid.store.get(comp::position))
            for (int a = 0; a < 3; ++a) {
                const double pen = std::max(box.min[a] - double(p[a]), double(p[a]) - box.max[a]);
                if (pen > max_penetration) max_penetration = pen, t_penetration = s.time();
            }
    }));
    EXPECT_NEAR(sim.time(), 1.0, 1e-6);
    EXPECT_LT(max_penetration, r) << "a particle reached the boundary sample layer at t = " << t_penetration;
    // The front must have run along the floor: the column started 0.4 m wide.
    double front = 0;
    for (const auto& p : sim.world().fluid.store.get(comp::position)) front = std::max(front, double(p.x()));
    EXPECT_GT(front, 1.0);
    // Weakly compressible at the default c_s (about 1 % at rest); the impact peaks higher.
    EXPECT_LT(max_err, 0.15);
    std::printf("dam_break without the safety net: %lld steps, max density error %.2f %%, deepest "
                "penetration %.2f mm (%.2f r) at t = %.3f s, front x = %.3f m\n",
                static_cast<long long>(sim.steps()), 100 * max_err, 1e3 * max_penetration,
                max_penetration / r, t_penetration, front);
}
