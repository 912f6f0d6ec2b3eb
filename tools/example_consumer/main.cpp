// Builds a scene in code, steps it, reads components and writes a frame.
#include <cstdio>

#include "engine/data/components.hpp"
#include "engine/run/io.hpp"
#include "systems/methods/recipes.hpp"

int main() {
    sph::Scene scene;
    scene.name = "consumer";
    scene.fluid.particle_radius = 0.01;
    scene.fluid_blocks.push_back({sph::Aabb{sph::Vec3d(0, 0, 0), sph::Vec3d(0.1, 0.2, 0.1)}});
    scene.boundaries.push_back({sph::BoundaryShape::Container, sph::Aabb{sph::Vec3d(0, 0, 0), sph::Vec3d(0.3, 0.3, 0.1)}});
    auto sim = sph::make_simulation(scene);
    sim->run_until(0.1);
    const auto x = sim->world().fluid.store.get(sph::comp::position);
    double front = 0;
    for (const auto& p : x) front = std::max(front, double(p.x()));
    sph::write_vtu("consumer_frame.vtu", sim->world(), {"velocity", "density"});
    std::printf("%zu particles, %lld steps, t = %.3f s, front x = %.3f m\n", x.size(),
                static_cast<long long>(sim->steps()), sim->time(), front);
    return front > 0.1 ? 0 : 1;  // the column must have started to spread
}
