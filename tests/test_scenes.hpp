#pragma once
// Small scenes built in code for the tests (no scene file involved).
#include <algorithm>
#include <cstdint>
#include <random>
#include <span>
#include <vector>

#include "engine/data/components.hpp"
#include "engine/data/scene.hpp"
#include "engine/data/world.hpp"

namespace sph::test {

/// A fluid block in a closed container, no motion: r = 0.01 m unless given.
inline Scene tank_scene(Vec3d fluid_max, Vec3d box_max, double r = 0.01) {
    Scene s;
    s.name = "test_tank";
    s.fluid.particle_radius = r;
    s.fluid_blocks.push_back(FluidBlock{Aabb{Vec3d::Zero(), fluid_max}, Vec3d::Zero(), /*hydrostatic=*/false});
    BoundaryDesc b;
    b.shape = BoundaryShape::Container;
    b.box = Aabb{Vec3d::Zero(), box_max};
    s.boundaries.push_back(b);
    s.simulation.frame_rate = 0;
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
