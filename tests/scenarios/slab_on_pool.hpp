#pragma once
// The wake-up scenario shared by the per-particle stepping tests (individual_stepping_test.cpp,
// binned_stepping_test.cpp): a slab falls 0.15 m onto a resting pool, run without the collision
// safety net (and what follows it in the recipe), so the particle boundary alone must hold.
#include <algorithm>

#include "engine/data/components.hpp"
#include "systems/methods/recipes.hpp"
#include "systems/methods/wcsph.hpp"
#include "test_scenes.hpp"

namespace sph::test {

/// A 0.3 x 0.12 x 0.08 m resting pool (the first block) and a 0.1 x 0.06 m slab above it.
inline Scene slab_on_pool_scene() {
    Scene s = tank_scene(Vec3d(0.3, 0.12, 0.08), Vec3d(0.3, 0.4, 0.08));
    s.fluid_blocks[0].hydrostatic = true;
    s.fluid_blocks.push_back(FluidBlock{Aabb{Vec3d(0.1, 0.27, 0.0), Vec3d(0.2, 0.33, 0.08)}, Vec3d::Zero(), false});
    return s;
}

struct SlabOnPool {
    double max_err = 0;             ///< max over steps of the maximum density error
    double splash = 0;              ///< highest pool particle after the slab lands (t > 0.2 s), m
    double penetration = 0;         ///< deepest particle centre beyond the container, m
    double pool_active_before = 0;  ///< average active share of the pool for 0.10 < t < 0.17 s
};

/// Runs `sc` (made from slab_on_pool_scene) to 0.45 s without the net.
inline SlabOnPool run_slab_on_pool(const Scene& sc) {
    const std::uint32_t n_pool = std::uint32_t(lattice_dims(sc.fluid_blocks[0].box, 2 * sc.fluid.particle_radius).prod());
    Recipe recipe = make_wcsph_recipe(sc);
    while (recipe.step.back()->name() != "boundary_collision") recipe.step.pop_back();
    recipe.step.pop_back();
    Simulation sim(sc, std::move(recipe));
    const Aabb box = sc.boundaries[0].box;
    SlabOnPool r;
    int before = 0;
    sim.run_until(0.45, [&](const Simulation& sm) {
        const World& w = sm.world();
        const auto x = w.fluid.store.get(comp::position);
        const auto id = w.fluid.store.get(comp::id);
        const double t = sm.time();
        r.max_err = std::max(r.max_err, w.stats.rho_err_max);
        for (std::size_t i = 0; i < x.size(); ++i) {
            for (int a = 0; a < 3; ++a)
                r.penetration = std::max({r.penetration, box.min[a] - x[i][a], x[i][a] - box.max[a]});
            // The splash: pool particles (the first block: ids below its lattice count).
            if (t > 0.2 && id[i] < n_pool) r.splash = std::max(r.splash, double(x[i].y()));
        }
        if (!w.active_set.empty() && t > 0.10 && t < 0.17) {  // the last part of the fall
            std::size_t pool_active = 0;
            for (Index i : w.active_set) pool_active += id[i] < n_pool;
            r.pool_active_before += double(pool_active) / n_pool;
            ++before;
        }
    });
    if (before) r.pool_active_before /= before;
    return r;
}

}  // namespace sph::test
