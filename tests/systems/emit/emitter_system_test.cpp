// Emitters (scene `emitters`): a stream poured into a box. Each step, every newly inserted
// particle must be at least 0.95 r0 from every other fluid particle and every boundary particle
// (never inside another particle or a boundary: brute force over all pairs), the count may not
// exceed rate x time (+ one layer's rounding: the budget is whole particles) nor max_particles.
#include <gtest/gtest.h>

#include "engine/data/components.hpp"
#include "systems/methods/recipes.hpp"

using namespace sph;

TEST(Emitter, NeverInsertsInsideParticlesOrBoundaries) {
    const std::string text = R"({"name": "pour", "simulation": {"method": "pcisph", "end_time": 0.3, "frame_rate": 0},
        "fluid": {"particle_radius": 0.01, "viscosity": 0},
        "emitters": [{"position": [0.15, 0.25, 0.15], "velocity": [0, -2, 0], "radius": 0.05, "rate": 2000, "max_particles": 500}],
        "boundaries": [{"type": "container", "min": [0, 0, 0], "max": [0.3, 0.3, 0.3]}]})";
    const Scene scene = parse_scene(text, "pour.json");
    auto sim = make_simulation(scene);
    const World& w = sim->world();
    const double r0 = w.physics.spacing, min_d = 0.95 * r0 * (1 - 1e-6);
    // Positions of every particle after the previous step, by id (the spatial sort permutes).
    std::vector<Vec3> prev;
    std::uint32_t next_id = 0;
    std::size_t checked = 0;
    double closest = 1e9;
    sim->run_until(0.3, [&](const Simulation& s) {
        const auto x = w.fluid.store.get(comp::position);
        const auto id = w.fluid.store.get(comp::id);
        const auto xb = w.boundary.store.get(comp::position);
        EXPECT_LE(double(x.size()), 2000.0 * s.time() + 25.0);  // rate x t, plus at most one disc
        EXPECT_LE(x.size(), 500u);
        if (!s.last().rolled_back) {
            // Where each new particle was inserted: on the disc (y = 0.25) at the lattice point
            // its (x, z) rounds to (it moved less than r0/2 sideways in one step).
            std::vector<Vec3> inserted;
            for (std::size_t i = 0; i < x.size(); ++i)
                if (id[i] >= next_id)
                    inserted.emplace_back(Real(0.15 + r0 * std::round((x[i].x() - 0.15) / r0)), Real(0.25),
                                          Real(0.15 + r0 * std::round((x[i].z() - 0.15) / r0)));
            for (std::size_t a = 0; a < inserted.size(); ++a) {
                for (std::uint32_t j = 0; j < next_id; ++j) closest = std::min(closest, double((inserted[a] - prev[j]).norm()));
                for (std::size_t c = 0; c < a; ++c) closest = std::min(closest, double((inserted[a] - inserted[c]).norm()));
                for (const auto& q : xb) closest = std::min(closest, double((inserted[a] - q).norm()));
                ++checked;
            }
        }
        std::uint32_t max_id = 0;
        for (auto i : id) max_id = std::max(max_id, i + 1);
        next_id = max_id;
        prev.assign(next_id, Vec3::Zero());
        for (std::size_t i = 0; i < x.size(); ++i) prev[id[i]] = x[i];
    });
    std::printf("emitter: %zu insertions checked, closest distance at insertion %.4f m (r0 = %.3f m)\n", checked,
                closest, r0);
    EXPECT_GE(closest, min_d);
    EXPECT_EQ(w.fluid.size(), 500u) << "the emitter stopped early";
    EXPECT_GE(checked, 500u);  // a rollback re-inserts a few
}
