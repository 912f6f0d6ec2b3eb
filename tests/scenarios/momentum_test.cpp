// Two blobs collide in free space without gravity: the symmetric pressure force and the
// pairwise Monaghan viscosity (He et al. eq. 4) cancel pair by pair, so total momentum is
// conserved up to float round-off. Tolerance: relative 1e-5 of sum_i m |v_i| (issue figure).
#include <gtest/gtest.h>

#include "engine/data/components.hpp"
#include "systems/methods/recipes.hpp"

using namespace sph;

namespace {
Vec3d momentum(const Simulation& sim, double* scale = nullptr) {
    const auto v = sim.world().fluid.store.get(comp::velocity);
    Vec3d p = Vec3d::Zero();
    double s = 0;
    for (const auto& vi : v) {
        p += vi.cast<double>();
        s += vi.cast<double>().norm();
    }
    if (scale) *scale = s * sim.world().physics.mass;
    return p * sim.world().physics.mass;
}
}  // namespace

TEST(Momentum, TwoBlobsCollidingConserveMomentum) {
    Scene s;
    s.name = "blobs";
    s.fluid.particle_radius = 0.01;
    s.fluid.viscosity = 0.05;
    s.simulation.gravity = Vec3d::Zero();
    s.simulation.frame_rate = 0;
    s.fluid_blocks.push_back(FluidBlock{Aabb{Vec3d(0, 0, 0), Vec3d(0.12, 0.12, 0.12)}, Vec3d(2.0, 0, 0)});
    s.fluid_blocks.push_back(FluidBlock{Aabb{Vec3d(0.15, 0.03, 0.02), Vec3d(0.27, 0.15, 0.14)}, Vec3d(-1.0, 0.5, 0)});
    s.domain = Aabb{Vec3d(-1, -1, -1), Vec3d(1.3, 1, 1)};
    auto sim = make_simulation(s);
    double scale = 0;
    const Vec3d p0 = momentum(*sim, &scale);
    double max_rho_err = 0;
    sim->run_until(0.12, [&](const Simulation& sm) { max_rho_err = std::max(max_rho_err, sm.world().stats.rho_err_max); });
    const Vec3d p1 = momentum(*sim);
    // The blobs did collide: densities rose above rest by a visible amount.
    EXPECT_GT(max_rho_err, 1e-3);
    EXPECT_LT((p1 - p0).norm(), 1e-5 * scale) << "p0 = " << p0.transpose() << ", p1 = " << p1.transpose();
}
