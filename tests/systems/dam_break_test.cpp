// scenes/dam_break.json at its default size reaches 1 s with no NaN (the engine throws a
// SimulationError on any non-finite value) and no leak: every particle stays inside the box.
#include <gtest/gtest.h>

#include "engine/components.hpp"
#include "systems/methods/wcsph.hpp"

using namespace sph;

TEST(DamBreak, ReachesOneSecondWithoutNaNOrLeak) {
    const Scene scene = load_scene(SPH_SOURCE_DIR "/scenes/dam_break.json");
    auto sim = make_simulation(scene);
    const Aabb box = scene.boundaries[0].box;
    double max_err = 0;
    std::uint64_t collisions = 0;
    ASSERT_NO_THROW(sim->run_until(1.0, [&](const Simulation& s) {
        max_err = std::max(max_err, s.world().step.rho_err_max);
        collisions += s.world().step.collisions;
    }));
    // The Akinci particle boundary alone holds the fluid: the collision safety net never acts.
    EXPECT_EQ(collisions, 0u);
    EXPECT_NEAR(sim->time(), 1.0, 1e-6);
    const auto x = sim->world().fluid.store.get(comp::position);
    std::size_t outside = 0;
    for (const auto& p : x)
        if (!box.contains(p.cast<double>())) ++outside;
    EXPECT_EQ(outside, 0u);
    // The front must have run along the floor: the column started 0.4 m wide.
    double front = 0;
    for (const auto& p : x) front = std::max(front, double(p.x()));
    EXPECT_GT(front, 1.0);
    std::printf("dam_break: %lld steps, max density error %.2f %%, front x = %.3f m\n",
                static_cast<long long>(sim->steps()), 100 * max_err, front);
}
