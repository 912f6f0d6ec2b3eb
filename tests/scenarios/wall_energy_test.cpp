// A resting tank must not gain energy. With the continuity density and no dissipation at all
// (delta = 0, alpha = 0, nu = 0) the scheme's fluid pairs conserve E = sum_i m (|v_i|^2 / 2 - g . x_i
// + e(rho_i)), e(rho) = int_rho0^rho p / rho'^2 drho' the Tait internal energy, up to the time
// integration's error; what the walls do to E is what this measures. With pressure mirroring
// (p_b = p_i) the wall force is not the gradient of any energy, and the tank runs away; with the
// extrapolated wall pressure (Adami, Hu & Adams 2012 eq. 27) it keeps its energy.
// Tank 0.5 x 0.3 x 0.1 m of water at r = 1 cm (1,875 particles), hydrostatic start, 0.4 s.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "engine/data/components.hpp"
#include "engine/run/simulation.hpp"
#include "systems/methods/recipes.hpp"

using namespace sph;

namespace {

double energy(const World& w) {
    const Physics& ph = w.physics;
    const double m = ph.mass, B = ph.tait_b, r0 = ph.rest_density;
    const Vec3d g = ph.gravity.cast<double>();
    const auto x = w.fluid.store.get(comp::position);
    const auto v = w.fluid.store.get(comp::velocity);
    const auto rho = w.fluid.store.get(comp::density);
    double e = 0;
    for (std::size_t i = 0; i < x.size(); ++i) {
        const double r = rho[i];
        e += m * (0.5 * v[i].cast<double>().squaredNorm() - g.dot(x[i].cast<double>()) +
                  B * ((std::pow(r, 6) - std::pow(r0, 6)) / (6 * std::pow(r0, 7)) + 1 / r - 1 / r0));
    }
    return e;
}

struct Gain {
    double energy = 0, kinetic = 0;  ///< J: E(end) - E(first step); the kinetic energy at the end
};

Gain run_tank(WallPressure walls) {
    Scene s;
    s.name = "resting_tank";
    s.fluid.particle_radius = 0.01;
    s.fluid.viscosity = 0;
    s.fluid.boundary_viscosity = 0;
    s.fluid.density = DensityForm::Continuity;
    s.fluid.density_diffusion = 0.0;
    s.fluid.wall_pressure = walls;
    s.fluid_blocks.push_back(FluidBlock{Aabb{Vec3d::Zero(), Vec3d(0.5, 0.3, 0.1)}, Vec3d::Zero(), true});
    BoundaryDesc b;
    b.shape = BoundaryShape::Container;
    b.box = Aabb{Vec3d::Zero(), Vec3d(0.5, 0.6, 0.1)};
    s.boundaries.push_back(b);
    s.simulation.gravity = Vec3d(0, -9.81, 0);
    s.simulation.frame_rate = 0;
    s.simulation.end_time = 0.4;
    auto sim = make_simulation(s);
    double e0 = 0;
    bool first = true;
    sim->run_until(s.simulation.end_time, [&](const Simulation& sm) {
        if (first) e0 = energy(sm.world()), first = false;
    });
    Gain out;
    out.energy = energy(sim->world()) - e0;
    for (const Vec3& v : sim->world().fluid.store.get(comp::velocity))
        out.kinetic += 0.5 * double(sim->world().physics.mass) * double(v.squaredNorm());
    std::printf("%s walls: energy gained in 0.4 s %+.4f J, kinetic energy at the end %.4f J\n", to_string(walls),
                out.energy, out.kinetic);
    return out;
}

}  // namespace

// Measured 2026-12-04 (density floored at 0.99 rho0; docs/results/validation.md, "Wall pressure"):
// extrapolated +0.049 J, mirrored +26.0 J (537x as much; its kinetic energy at the end 10.0 J
// against 0.042 J); since droplets take the summation density, +0.041 J and +25.4 J (627x).
// With the floor at rho0 itself (2026-12-03): -0.039 J and +10.6 J.
// Bounds: the extrapolated walls' change within 0.2 J (4x the measured; the fluid's own
// integration error), the mirrored walls' gain at least 5 J and 50x the extrapolated walls'.
TEST(WallEnergy, ExtrapolatedWallsKeepARestingTanksEnergy) {
    const Gain extrapolated = run_tank(WallPressure::Extrapolated);
    const Gain mirrored = run_tank(WallPressure::Mirrored);
    std::printf("mirrored gained %.0fx the extrapolated walls' energy\n", mirrored.energy / std::abs(extrapolated.energy));
    EXPECT_LT(std::abs(extrapolated.energy), 0.2);
    EXPECT_GT(mirrored.energy, 5.0);
    EXPECT_GT(mirrored.energy, 50 * std::abs(extrapolated.energy));
}

// A droplet alone (no fluid neighbour) thrown at 12 m/s along x between the end walls of a 0.3 m
// box, no gravity, continuity density (the defaults: delta 0.1, alpha 0.01, extrapolated walls),
// 0.2 s. Its continuity density, integrated over its own steps, came out of every wall contact
// denser than it went in, and the extra pressure threw it back faster: 12 -> 35 m/s in every
// mode, densest 1.28 rho0 (measured 2026-12-04, before rows without fluid neighbours took the
// summation density). Now its density is the summation density max(m W(0) + rho0 sum_b V_b
// W_ib, rho0). A brute-force sum over every wall particle peaks at 0.80 rho0 (804.8 kg/m^3
// measured) where the droplet meets the wall, so that density is rho0 throughout: asserted to
// 1e-4 relative, with the sum's peak between 0.6 and 1.0 rho0 (above 0.6: the droplet did reach
// the wall; below 1: the clamp, not the sum, decides, as the test assumes). Its speed never
// exceeds the speed it was thrown with (bound 1e-5 relative: the rounding of a kick). The
// collision net stops it at its first wall contact (an inelastic contact: it ends at rest).
TEST(WallEnergy, ADropletThrownAtAWallGainsNoSpeed) {
    for (const SteppingMode mode : {SteppingMode::Global, SteppingMode::Binned, SteppingMode::Individual}) {
        Scene s;
        s.name = "droplet";
        s.fluid.particle_radius = 0.01;
        s.fluid.density = DensityForm::Continuity;
        s.fluid_blocks.push_back(FluidBlock{Aabb{Vec3d(0.09, 0.09, 0.09), Vec3d(0.11, 0.11, 0.11)}, Vec3d(12, 0, 0), false});
        BoundaryDesc b;
        b.shape = BoundaryShape::Container;
        b.box = Aabb{Vec3d::Zero(), Vec3d(0.3, 0.2, 0.2)};
        s.boundaries.push_back(b);
        s.simulation.gravity = Vec3d::Zero();
        s.simulation.frame_rate = 0;
        s.simulation.end_time = 0.2;
        s.simulation.stepping.mode = mode;
        auto sim = make_simulation(s);
        ASSERT_EQ(sim->world().fluid.size(), 1u);
        double v_max = 0, rho_err = 0, rho_max = 0, sum_max = 0;
        std::uint64_t catches = 0, droplet_contacts = 0;
        sim->run_until(s.simulation.end_time, [&](const Simulation& sm) {
            const World& w = sm.world();
            catches += w.counter_value("collisions");
            droplet_contacts += w.counter_value("droplet_contacts");
            const Physics& ph = w.physics;
            const Vec3 xi = w.fluid.store.get(comp::position)[0];
            const auto xb = w.boundary.store.get(comp::position);
            const auto vb = w.boundary.store.get(comp::volume);
            double sum = double(ph.mass) * double(w.kernel.w(0));
            for (std::size_t k = 0; k < xb.size(); ++k)
                sum += double(ph.rest_density) * double(vb[k]) * double(w.kernel.w((xi - xb[k]).norm()));
            const double rho = w.fluid.store.get(comp::density)[0];
            rho_err = std::max(rho_err, std::abs(rho - std::max(sum, double(ph.rest_density))) / double(ph.rest_density));
            rho_max = std::max(rho_max, rho);
            sum_max = std::max(sum_max, sum);
            v_max = std::max(v_max, double(w.fluid.store.get(comp::velocity)[0].norm()));
        });
        std::printf("%s: fastest %.4f m/s, densest %.2f kg/m^3 (largest sum %.1f), largest error against the sum %.2e\n",
                    to_string(mode), v_max, rho_max, sum_max, rho_err);
        EXPECT_LT(v_max, 12 * (1 + 1e-5)) << to_string(mode);
        EXPECT_LT(rho_err, 1e-4) << to_string(mode);
        EXPECT_GT(sum_max, 0.6 * s.fluid.rest_density) << to_string(mode);
        EXPECT_LT(sum_max, 1.0 * s.fluid.rest_density) << to_string(mode);
        // The net is the lone particle's contact (it has no pressure): each catch is a droplet's.
        EXPECT_GE(catches, 1u) << to_string(mode);
        EXPECT_EQ(droplet_contacts, catches) << to_string(mode);
    }
}
