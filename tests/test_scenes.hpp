#pragma once
// Small scenes built in code for the tests (no scene file involved).
#include <algorithm>
#include <cstdint>
#include <optional>
#include <random>
#include <span>
#include <vector>

#include "engine/data/components.hpp"
#include "engine/data/scene.hpp"
#include "engine/data/world.hpp"

namespace sph::test {

/// True in the sanitizer builds of tools/test.sh (stages 2 and 3: GCC defines these macros with
/// -fsanitize=address or thread), where a whole run takes 10-15x its Release time. The longest
/// whole-run tests run a shorter stretch of the same scene there (each states its lengths and
/// why its assertions still hold): the sanitizers check the code a step runs, which the first
/// steps already run, and stage 1 runs every test at full length.
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
inline constexpr bool kSanitized = true;
#else
inline constexpr bool kSanitized = false;
#endif

/// He et al.'s physics (summation density, Monaghan alpha 0.1, no laminar viscosity, mirrored
/// walls), which the system and stepping tests built on these scenes were written and measured
/// against; the engine's own defaults (continuity, alpha 0.01, water's nu) are a scene's when it
/// sets none (SceneDefaults tests).
inline void he_physics(Scene& s) {
    s.fluid.density = DensityForm::Summation;
    s.fluid.viscosity = 0.1;
    s.fluid.kinematic_viscosity = 0.0;
}

/// A box obstacle, moving with `motion` if given.
inline BoundaryDesc box_obstacle(const Aabb& box, std::optional<Motion> motion = {}) {
    BoundaryDesc b;
    b.shape = BoundaryShape::Box;
    b.box = box;
    b.motion = std::move(motion);
    return b;
}

/// A fluid block in a closed container, no motion, He et al.'s physics: r = 0.01 m unless given.
inline Scene tank_scene(Vec3d fluid_max, Vec3d box_max, double r = 0.01) {
    Scene s;
    s.name = "test_tank";
    he_physics(s);
    s.fluid.particle_radius = r;
    s.fluid_blocks.push_back(FluidBlock{Aabb{Vec3d::Zero(), fluid_max}, Vec3d::Zero(), /*hydrostatic=*/false});
    BoundaryDesc b;
    b.shape = BoundaryShape::Container;
    b.box = Aabb{Vec3d::Zero(), box_max};
    s.boundaries.push_back(b);
    s.simulation.frame_rate = 0;
    return s;
}

/// A 0.4 x 0.12 x 0.12 m pool at r = 5 mm (He et al.'s physics) in `binned` without the acoustic
/// condition, with a 4 x 16 x 4 cm box pushed through it at 0.5 m/s along x.
inline Scene pool_with_pushed_box() {
    Scene s = tank_scene(Vec3d(0.4, 0.12, 0.12), Vec3d(0.4, 0.25, 0.12), 0.005);
    s.simulation.stepping.mode = SteppingMode::Binned;
    s.simulation.stepping.acoustic = false;
    s.boundaries.push_back(box_obstacle(Aabb{Vec3d(0.10, 0.04, 0.03), Vec3d(0.14, 0.20, 0.07)}, linear_motion(Vec3d(0.5, 0, 0))));
    return s;
}

/// pool_with_pushed_box with the pool's water around the box only (five blocks), as the loader
/// requires of a scene (a fluid block clear of every box obstacle) and so validate_scene does.
inline Scene pool_around_pushed_box() {
    Scene s = pool_with_pushed_box();
    s.fluid_blocks.clear();
    for (const Aabb& block : {Aabb{Vec3d(0, 0, 0), Vec3d(0.10, 0.12, 0.12)}, Aabb{Vec3d(0.14, 0, 0), Vec3d(0.4, 0.12, 0.12)},
                              Aabb{Vec3d(0.10, 0, 0), Vec3d(0.14, 0.12, 0.03)}, Aabb{Vec3d(0.10, 0, 0.07), Vec3d(0.14, 0.12, 0.12)},
                              Aabb{Vec3d(0.10, 0, 0.03), Vec3d(0.14, 0.04, 0.07)}})
        s.fluid_blocks.push_back(FluidBlock{block, Vec3d::Zero(), true});
    return s;
}

/// Moves every fluid particle by up to `fraction` r per axis (uniform, seeded), keeping it 2 mm
/// inside the walls of a container at the origin.
inline void jitter(World& w, std::uint32_t seed, Real fraction) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<Real> u(-1, 1);
    for (auto& p : w.fluid.store.get(comp::position)) {
        p += Vec3(u(rng), u(rng), u(rng)) * (fraction * w.physics.particle_radius);
        p = p.cwiseMax(Vec3::Constant(0.002f));
    }
}

/// The entries of a list, sorted (to compare as sets).
inline std::vector<Index> sorted_copy(std::span<const Index> s) {
    std::vector<Index> v(s.begin(), s.end());
    std::sort(v.begin(), v.end());
    return v;
}

}  // namespace sph::test
