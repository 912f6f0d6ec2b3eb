#pragma once
// Fixtures shared by the benchmarks: built outside the timed loop.
#include <cmath>
#include <memory>
#include <random>

#include "engine/data/components.hpp"
#include "engine/run/simulation.hpp"

namespace sph::bench {

/// A cube of n (rounded to a cube number) fluid particles of radius 0.01 m on a jittered lattice,
/// no boundaries, no gravity: the per-system benchmarks' particle cloud.
inline std::unique_ptr<World> lattice_world(std::size_t n) {
    const int side = static_cast<int>(std::lround(std::cbrt(double(n))));
    const double r = 0.01, edge = side * 2 * r;
    Scene s;
    s.name = "lattice";
    s.fluid.particle_radius = r;
    s.simulation.gravity = Vec3d::Zero();
    s.fluid_blocks.push_back(FluidBlock{Aabb{Vec3d::Zero(), Vec3d::Constant(edge)}, Vec3d::Zero()});
    s.domain = Aabb{Vec3d::Constant(-0.1), Vec3d::Constant(edge + 0.1)};
    auto w = std::make_unique<World>();
    initialise_world(*w, s);
    std::mt19937 rng(3);
    std::uniform_real_distribution<Real> u(-0.2f, 0.2f);
    for (auto& x : w->fluid.store.get(comp::position)) x += Vec3(u(rng), u(rng), u(rng)) * Real(r);
    for (auto& v : w->fluid.store.get(comp::velocity)) v = Vec3(u(rng), u(rng), u(rng));
    return w;
}

}  // namespace sph::bench
