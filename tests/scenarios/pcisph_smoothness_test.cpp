// Ihmsen et al. 2010 Fig. 2 / sec. 4.1: on a corner breaking dam of 23k particles, the boundary
// of sec. 3.2 (boundary density and pressure + direct forcing) gives a smoother pressure at the
// floor than direct forcing alone (BTT09 eq. 7-8 style: no boundary density or pressure).
//
// The measure (the paper's "pressure ratio of the particles colliding with the boundary and
// their non-colliding neighbours on top"): for every fluid particle i in the floor layer (centre
// less than one spacing r0 above the floor surface) with positive pressure among its neighbours
// on top (fluid neighbours j with y_j > y_i + r0 / 2), ratio_i = p_i / mean_top(p_j). The
// measure is the largest ratio_i over the floor layer and over the samples (every 10th step
// from t = 0.1 s to 0.2 s: the column is collapsing and the front runs along the floor). Both
// runs use the same constant step, 1 ms, three iterations.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <vector>

#include "engine/data/components.hpp"
#include "systems/methods/recipes.hpp"

using namespace sph;

namespace {

double max_floor_pressure_ratio(BoundaryHandling handling) {
    Scene s = load_scene(SPH_SOURCE_DIR "/scenes/corner_breaking_dam.json");
    s.simulation.scale = 1.2;  // 20,625 -> 23,660 particles (26 x 35 x 26)
    s.simulation.frame_rate = 0;
    s.simulation.stepping.mode = SteppingMode::Constant;
    s.simulation.stepping.dt = 1e-3;
    s.boundary.handling = handling;
    auto sim = make_simulation(s);
    const World& w = sim->world();
    double worst = 0;
    std::vector<double> ratios;
    sim->run_until(0.2, [&](const Simulation& sm) {
        if (sm.time() < 0.1 || sm.steps() % 10 != 0) return;
        const auto x = w.fluid.store.get(comp::position);
        const auto p = w.fluid.store.get(comp::pressure);
        const Real r0 = w.physics.spacing;
        for (std::size_t i = 0; i < x.size(); ++i) {
            if (x[i].y() >= r0) continue;  // floor surface at y = 0
            double sum = 0;
            int n = 0;
            for (Index j : w.fluid_neighbours.of(Index(i)))
                if (x[j].y() > x[i].y() + Real(0.5) * r0) {
                    sum += p[j];
                    ++n;
                }
            if (n == 0 || sum <= 0) continue;
            worst = std::max(worst, double(p[i]) / (sum / n));
            ratios.push_back(double(p[i]) / (sum / n));
        }
    });
    std::sort(ratios.begin(), ratios.end());
    std::printf("%s: %zu fluid particles, floor pressure ratio: max %.3f, 99th percentile %.3f, median %.3f (%zu samples)\n",
                to_string(handling), w.fluid.size(), worst, ratios.empty() ? 0.0 : ratios[ratios.size() * 99 / 100],
                ratios.empty() ? 0.0 : ratios[ratios.size() / 2], ratios.size());
    return worst;
}

}  // namespace

TEST(PcisphSmoothness, FloorPressureRatioLowerWithIhmsenThanDirectForcing) {
    const double ihmsen = max_floor_pressure_ratio(BoundaryHandling::Ihmsen);
    const double direct = max_floor_pressure_ratio(BoundaryHandling::DirectForcing);
    EXPECT_GT(ihmsen, 0.0);
    // Measured (2 threads and 1 thread alike: the run is deterministic): ihmsen 156.0,
    // direct_forcing 823.5, a ratio of 5.3 (docs/results/ihmsen_table1.md still records 52.6 for
    // ihmsen, a ratio of 16). The margin 2 sits near the geometric middle of 1 and 5.3
    // (sqrt(5.3) = 2.3): the test still demands that the boundary of sec. 3.2 at least halves the
    // worst floor pressure ratio, and ihmsen's value may grow 2.6x (to 412) before it fails. A
    // margin of 4 would leave only 1.3x (206) above the measured 156. There is no noise to allow
    // for: the same build gives the same numbers.
    EXPECT_LT(ihmsen, direct / 2);
}
