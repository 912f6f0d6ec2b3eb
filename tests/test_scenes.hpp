#pragma once
// Small scenes built in code for the tests (no scene file involved).
#include "engine/data/scene.hpp"

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

}  // namespace sph::test
