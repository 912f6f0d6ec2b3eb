// Probes (engine/probes.*) against states whose answer is known in closed form: a lattice
// block at rest (height, front, colour), a uniformly moving block (kinetic energy, momentum,
// potential energy from the block's centre of mass), a linear hydrostatic pressure field
// (interpolated at a point and extrapolated to the floor with Adami et al. 2012 eq. 27, both
// exact for a linear field), plus sampling rates, CSV output and scene-file errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <limits>
#include <numeric>
#include <random>
#include <sstream>

#include "engine/data/components.hpp"
#include "engine/core/errors.hpp"
#include "engine/run/probes.hpp"
#include "engine/run/recorder.hpp"
#include "systems/methods/recipes.hpp"
#include "test_scenes.hpp"

using namespace sph;

namespace {

// A 0.2 x 0.3 x 0.2 m block (r = 0.01 m: 10 x 15 x 10 particles) in a 0.4 x 0.5 x 0.2 m tank,
// densities at rho0, no step taken.
std::unique_ptr<Simulation> block_at_rest() {
    Scene s = test::tank_scene({0.2, 0.3, 0.2}, {0.4, 0.5, 0.2});
    auto sim = make_simulation(s);
    for (auto& rho : sim->world().fluid.store.get(comp::density)) rho = sim->world().physics.rest_density;
    return sim;
}

UniformGrid grid_of(const World& w) {
    UniformGrid g(w.domain, w.physics.h);
    g.build(w.fluid.store.get(comp::position));
    return g;
}

}  // namespace

// Inside a filled lattice at rest sum_j (m/rho0) W = 1 exactly: that is how the mass is chosen
// (engine/simulation.cpp, lattice_mass). Tolerance 1e-5: float positions.
TEST(Probes, ColourIsOneInsideALattice) {
    auto sim = block_at_rest();
    const auto g = grid_of(sim->world());
    EXPECT_NEAR(colour_at(sim->world(), g, {0.11, 0.15, 0.11}), 1.0, 1e-5);
    EXPECT_NEAR(colour_at(sim->world(), g, {0.3, 0.15, 0.1}), 0.0, 1e-12);  // dry, more than h away
}

// The 0.5 level of the colour function at a flat lattice face lies where the continuum the
// particles stand for ends, half a spacing beyond the last centres: at y = 0.3 m (top) and
// x = 0.2 m (side). For a continuous half-space it is exact by the kernel's symmetry; the
// lattice's discreteness moves it by less than a tenth of a spacing (measured 0.4 mm = 0.02
// spacings), so the tolerance is 0.1 spacing = 2 mm.
TEST(Probes, HeightAndColourFrontFindTheBlockFaces) {
    auto sim = block_at_rest();
    const World& w = sim->world();
    const auto g = grid_of(w);
    const double spacing = 0.02;
    const double height = iso_distance(w, g, {0.1, 0.0, 0.1}, {0.1, 0.5, 0.1});
    EXPECT_NEAR(height, 0.3, 0.1 * spacing);
    const double front = iso_distance(w, g, {0.0, 0.05, 0.1}, {0.4, 0.05, 0.1});
    EXPECT_NEAR(front, 0.2, 0.1 * spacing);
    EXPECT_EQ(iso_distance(w, g, {0.3, 0.0, 0.1}, {0.3, 0.5, 0.1}), 0.0);  // dry line
    std::printf("probes: lattice top at %.5f m (0.3), side at %.5f m (0.2)\n", height, front);
}

// Issue 16: a height probe must report the water column, not the splash above it. The block's
// top layer (y = 0.29 m) at the probe line's column is lifted by 0.1 m into a detached sheet
// (0.39 m, an isolated layer of droplets with a 0.08 m dry gap below): the column method still
// reads the column's top, now one layer lower (0.28 m: the lifted particles left the column),
// and the highest wet point reads the sheet (about 0.4 m). Also a line whose start is dry (no
// water within a spacing of `from`) reads 0 with the column method. Tolerance 0.1 spacing, as
// above; the sheet's 0.5 level within 0.25 spacing (a single layer's colour peaks near 0.6).
TEST(Probes, ColumnHeightIgnoresSplashAbove) {
    auto sim = block_at_rest();
    World& w = sim->world();
    auto x = w.fluid.store.get(comp::position);
    int lifted = 0;
    for (auto& p : x)
        if (std::abs(p.y() - 0.29f) < 1e-4f && p.x() < 0.2f && p.z() < 0.2f) {
            p.y() += 0.1f;
            ++lifted;
        }
    ASSERT_EQ(lifted, 100);
    const auto g = grid_of(w);
    const double spacing = 0.02;
    const Vec3d from{0.1, 0.0, 0.1}, to{0.1, 0.5, 0.1};
    EXPECT_NEAR(column_height(w, g, from, to), 0.28, 0.1 * spacing);
    const double highest = iso_distance(w, g, from, to);
    EXPECT_GT(highest, 0.39);
    EXPECT_LT(highest, 0.40 + 0.25 * spacing);
    // Starting 0.1 m above the floor (inside the water) the column reads from there; starting in
    // the dry gap the line has no column at its start: 0, where "highest" still sees the sheet.
    EXPECT_NEAR(column_height(w, g, {0.1, 0.1, 0.1}, to), 0.18, 0.1 * spacing);
    EXPECT_EQ(column_height(w, g, {0.1, 0.32, 0.1}, to), 0.0);
    EXPECT_GT(iso_distance(w, g, {0.1, 0.32, 0.1}, to), 0.0);
    std::printf("probes: column %.5f m (0.28), highest %.5f m\n", column_height(w, g, from, to), highest);
}

// Largest x of a particle centre with >= k neighbours is the last lattice column, 0.19 m; the
// probe reports the face of its cell, + r = 0.2 m. A lone particle thrown ahead (0 neighbours)
// must not count. Exact up to float rounding.
TEST(Probes, FrontByNeighboursIgnoresALoneDroplet) {
    auto sim = block_at_rest();
    World& w = sim->world();
    auto x = w.fluid.store.get(comp::position);
    x[0] = Vec3(0.35f, 0.05f, 0.1f);  // one particle far ahead
    const auto g = grid_of(w);
    EXPECT_NEAR(front_by_neighbours(w, g, {1, 0, 0}, 4) + w.physics.particle_radius, 0.2, 1e-6);
    EXPECT_NEAR(front_by_neighbours(w, g, {1, 0, 0}, 0), 0.35, 1e-6);
}

// Against brute force on a scattered block: every particle jittered, a few thrown ahead along a
// slanted direction, k from 0 to 30; the reference sorts every particle by its projection (ties
// by index) and counts neighbours over all pairs. Exact: the same float projections.
TEST(Probes, FrontByNeighboursEqualsBruteForce) {
    auto sim = block_at_rest();
    World& w = sim->world();
    auto x = w.fluid.store.get(comp::position);
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> jitter(-0.004f, 0.004f);
    for (auto& p : x) p += Vec3(jitter(rng), jitter(rng), jitter(rng));
    for (int k = 0; k < 12; ++k) x[std::size_t(37 * k + 5)] = Vec3(0.21f + 0.012f * float(k), 0.25f, 0.1f);
    x[3] = x[4];  // a tie in every projection
    const auto g = grid_of(w);
    const Real h2 = w.physics.h * w.physics.h;
    for (const Vec3d& dir : {Vec3d(1, 0, 0), Vec3d(0.8, 0.6, 0), Vec3d(-0.6, 0, 0.8)}) {
        const Vec3 d = dir.cast<Real>();
        std::vector<Index> order(x.size());
        std::iota(order.begin(), order.end(), Index(0));
        std::sort(order.begin(), order.end(), [&](Index a, Index b) {
            return x[a].dot(d) > x[b].dot(d) || (x[a].dot(d) == x[b].dot(d) && a < b);
        });
        for (const int k : {0, 1, 4, 12, 30}) {
            double want = -std::numeric_limits<double>::infinity();
            for (const Index i : order) {
                int count = 0;
                for (Index j = 0; j < x.size(); ++j) count += j != i && (x[i] - x[j]).squaredNorm() < h2;
                if (count >= k) {
                    want = double(x[i].dot(d));
                    break;
                }
            }
            EXPECT_EQ(front_by_neighbours(w, g, dir, k), want) << "k = " << k << ", direction " << dir.transpose();
        }
    }
}

// The summary's front (recorder.hpp, front_x) is the same front by neighbours along +x, counted from
// the positions: a state with no neighbour lists (no step taken, as for a sleeping row in
// `individual` or `binned`) still has its front at the last layer's centres, 0.2 - r.
TEST(Probes, SummaryFrontNeedsNoNeighbourLists) {
    auto sim = block_at_rest();
    World& w = sim->world();
    w.fluid.store.get(comp::position)[0] = Vec3(0.35f, 0.05f, 0.1f);  // a lone droplet ahead
    ASSERT_EQ(w.fluid_neighbours.rows(), 0u);
    EXPECT_NEAR(front_x(w), 0.2 - w.physics.particle_radius, 1e-6);
}

// A block moving at v = (1, -2, 0.5) m/s: KE = M |v|^2 / 2, momentum M v, potential energy
// M g y_com with y_com = 0.15 m (the block's centre; the centre of mass also against the mean
// of the positions, 1e-9 m: the same doubles summed in another order), M = N m. Relative tolerance 1e-6
// (float positions and velocities summed in double).
TEST(Probes, FluidTotalsOfAUniformlyMovingBlock) {
    auto sim = block_at_rest();
    World& w = sim->world();
    const Vec3d v(1.0, -2.0, 0.5);
    for (auto& vi : w.fluid.store.get(comp::velocity)) vi = v.cast<Real>();
    auto rho = w.fluid.store.get(comp::density);
    rho[0] = Real(1.05 * w.physics.rest_density);  // one particle 5 % compressed
    const FluidTotals t = fluid_totals(w);
    const double n = double(w.fluid.size()), mass = n * w.physics.mass;
    ASSERT_EQ(n, 1500);
    EXPECT_NEAR(t.kinetic, 0.5 * mass * v.squaredNorm(), 1e-6 * t.kinetic);
    EXPECT_NEAR((t.momentum - mass * v).norm(), 0.0, 1e-6 * mass * v.norm());
    EXPECT_NEAR(t.potential, mass * 9.81 * 0.15, 1e-6 * t.potential);
    EXPECT_NEAR(t.rho_err_max, 0.05, 1e-6);
    EXPECT_NEAR(t.rho_err_avg, 0.05 / n, 1e-8);
    Vec3d centre = Vec3d::Zero();  // brute force, in order
    for (const Vec3& x : w.fluid.store.get(comp::position)) centre += x.cast<double>() / n;
    EXPECT_NEAR((t.centre - centre).norm(), 0.0, 1e-9);
    EXPECT_NEAR(t.centre.y(), 0.15, 1e-6);
}

// The interior density error (Ihmsen sec. 4.1 comparison) against brute force over every
// fluid/boundary pair: the particles with no boundary particle closer than h are averaged.
// Densities follow a pattern with under-dense particles (clamped to zero error) and a 10 %
// compressed wall layer that the measure must leave out. Tolerance 1e-12 relative: the same
// float distances, sums in double in another order.
TEST(Probes, InteriorDensityErrorMatchesBruteForce) {
    auto sim = block_at_rest();
    World& w = sim->world();
    const auto x = w.fluid.store.get(comp::position);
    const auto xb = w.boundary.store.get(comp::position);
    auto rho = w.fluid.store.get(comp::density);
    const double rho0 = w.physics.rest_density;
    const Real h2 = w.physics.h * w.physics.h;
    double sum = 0, max = 0;
    std::size_t n = 0;
    for (std::size_t i = 0; i < x.size(); ++i) {
        bool near_wall = false;
        for (const Vec3& b : xb) near_wall = near_wall || (x[i] - b).squaredNorm() < h2;
        rho[i] = Real(rho0 * (near_wall ? 1.10 : 0.995 + 0.002 * double(i % 7)));
        if (near_wall) continue;
        const double e = std::max(0.0, double(rho[i]) / rho0 - 1.0);
        sum += e, max = std::max(max, e), ++n;
    }
    ASSERT_GT(n, 0u);
    ASSERT_LT(n, x.size());  // the block touches the floor and three walls
    const InteriorDensityError in = interior_density_error(w);
    EXPECT_EQ(in.count, n);
    EXPECT_NEAR(in.rho_err_avg, sum / double(n), 1e-12);
    EXPECT_NEAR(in.rho_err_max, max, 1e-12);
    EXPECT_LT(in.rho_err_max, 0.01);  // the 10 % wall layer is left out
    std::printf("probes: %zu of %zu particles interior, rho_err_avg %.5f %%\n", n, x.size(), 100 * in.rho_err_avg);
}

// Linear hydrostatic field p = rho0 g (H - y), H = 0.3 m, set on the particles. Shepard
// interpolation reproduces a linear field exactly at an interior point of a symmetric lattice
// (the weighted mean of y_j is y), and Adami eq. 27 extrapolates it exactly to the wall: the
// floor's boundary particles sit r = 0.01 m below y = 0, so they read rho0 g (H + r).
// Tolerance 0.1 %: float positions and densities.
TEST(Probes, PressureOfALinearHydrostaticField) {
    auto sim = block_at_rest();
    World& w = sim->world();
    const double rho0 = w.physics.rest_density, g = 9.81, H = 0.3;
    auto x = w.fluid.store.get(comp::position);
    auto p = w.fluid.store.get(comp::pressure);
    for (std::size_t i = 0; i < x.size(); ++i) p[i] = Real(rho0 * g * (H - x[i].y()));
    const auto grid = grid_of(w);
    const double expect_mid = rho0 * g * (H - 0.15);
    EXPECT_NEAR(fluid_pressure_at(w, grid, {0.1, 0.15, 0.1}), expect_mid, 1e-3 * expect_mid);
    int count = 0;
    const double wall = boundary_pressure_at(w, grid, {0.1, 0.0, 0.1}, 0.025, &count);
    const double expect_wall = rho0 * g * (H + 0.01);
    EXPECT_NEAR(wall, expect_wall, 1e-3 * expect_wall);
    EXPECT_GE(count, 4);
    std::printf("probes: interpolated %.2f Pa (%.2f), wall %.2f Pa (%.2f) over %d boundary particles\n",
                fluid_pressure_at(w, grid, {0.1, 0.15, 0.1}), expect_mid, wall, expect_wall, count);
}

// A wall sensor (source "sensor") on the side wall x = 0 in the same linear field: fully wet,
// its disc average is the value at its centre (Adami's extrapolation is exact for a linear
// field, and the disc is symmetric about its centre); straddling the free surface y = H, only
// its lower half is wet and it reads the area average of rho0 g (H - y) over that half,
// rho0 g 4 R / (3 pi) over the half disc times 1/2 for the dry half: rho0 g 2 R / (3 pi).
TEST(Probes, SensorReadsTheAreaAverageOverItsWetFace) {
    auto sim = block_at_rest();
    World& w = sim->world();
    const double rho0 = w.physics.rest_density, g = 9.81, H = 0.3, R = 0.03;
    auto x = w.fluid.store.get(comp::position);
    auto p = w.fluid.store.get(comp::pressure);
    for (std::size_t i = 0; i < x.size(); ++i) p[i] = Real(rho0 * g * (H - x[i].y()));
    const auto grid = grid_of(w);
    double wet = 0;
    const double deep = sensor_pressure_at(w, grid, {0.0, 0.15, 0.1}, {1, 0, 0}, 2 * R, &wet);
    EXPECT_NEAR(deep, rho0 * g * (H - 0.15), 1e-3 * rho0 * g * (H - 0.15));
    EXPECT_DOUBLE_EQ(wet, 1.0);
    const double surface = sensor_pressure_at(w, grid, {0.0, H, 0.1}, {1, 0, 0}, 2 * R, &wet);
    const double expect = rho0 * g * 2 * R / (3 * M_PI);
    std::printf("sensor: %.2f Pa deep (%.2f), %.2f Pa across the surface (%.2f), wet share %.3f\n", deep,
                rho0 * g * (H - 0.15), surface, expect, wet);
    // The wetted edge is where the colour falls through 0.25, near the block's face y = 0.3 (the
    // lattice's top row is at 0.29): measured 2026-12-03 wet share 0.486 (0.5 mm below the face)
    // and 62.04 Pa against 62.45; held to 0.03 (1.4 mm) and 4 %.
    EXPECT_NEAR(wet, 0.5, 0.03);
    EXPECT_NEAR(surface, expect, 0.04 * expect);
}

// Rates: a probe at 100 Hz over 0.1 s of simulated time has 11 samples (t = 0 included), one
// at 20 Hz has 3; the Recorder writes them as CSV with their columns.
TEST(Probes, RatesAndCsvFromARun) {
    const std::string text = R"({"name": "probe_rates",
        "simulation": {"end_time": 0.1, "frame_rate": 0},
        "fluid_blocks": [{"min": [0, 0, 0], "max": [0.2, 0.2, 0.1]}],
        "boundaries": [{"type": "container", "min": [0, 0, 0], "max": [0.4, 0.4, 0.1]}],
        "probes": [{"type": "fluid", "rate": 100},
                   {"type": "front", "name": "tip", "rate": 20},
                   {"type": "height", "from": [0.05, 0, 0.05], "to": [0.05, 0.4, 0.05], "rate": 20},
                   {"type": "pressure", "point": [0.1, 0.05, 0.05], "rate": 20},
                   {"type": "pressure", "source": "boundary", "point": [0.1, 0, 0.05], "rate": 20}]})";
    const Scene scene = parse_scene(text, "probe_rates.json");
    auto sim = make_simulation(scene);
    const auto dir = std::filesystem::temp_directory_path() / "sph_probes_test";
    std::filesystem::remove_all(dir);
    Recorder rec(dir, *sim);
    rec.begin(*sim);
    sim->run_until(0.1, [&](const Simulation& s) { rec.after_step(s); });
    const nlohmann::json summary = rec.finish(*sim, 1.0, 1);
    auto lines = [&](const char* name) {
        std::ifstream f(dir / "probes" / name);
        std::string line, header;
        std::getline(f, header);
        int n = 0;
        while (std::getline(f, line)) ++n;
        return std::make_pair(header, n);
    };
    EXPECT_EQ(lines("fluid_0.csv"), std::make_pair(std::string("t,kinetic,potential,momentum_x,momentum_y,momentum_z,"
                                                               "rho_err_avg,rho_err_max,rho_err_avg_interior,"
                                                               "rho_err_max_interior,interior_count,centre_x,centre_y,centre_z"), 11));
    EXPECT_EQ(lines("tip.csv"), std::make_pair(std::string("t,front,x_centre"), 3));
    EXPECT_EQ(lines("height_2.csv").second, 3);
    EXPECT_EQ(lines("pressure_3.csv").first, "t,p,colour");
    EXPECT_EQ(lines("pressure_4.csv").first, "t,p,wall_particles");
    // Sample k of a 20 Hz probe is taken at the end of the first step that reaches k / 20 s:
    // t_k in [k / 20, k / 20 + the run's largest step).
    const double dt_max = summary.at("max_dt_s").get<double>();
    ASSERT_GT(dt_max, 0.0);
    std::ifstream tip(dir / "probes" / "tip.csv");
    std::string line;
    std::getline(tip, line);
    for (int k = 0; std::getline(tip, line); ++k) {
        const double t = std::stod(line.substr(0, line.find(',')));
        EXPECT_GE(t, k / 20.0 - 1e-12) << "sample " << k;
        EXPECT_LT(t, k / 20.0 + dt_max) << "sample " << k;
    }
}

TEST(Probes, SceneErrorsNameThePathAndWhatWasExpected) {
    const auto load = [](const std::string& probes) {
        const std::string text = R"({"name": "x", "fluid_blocks": [{"min": [0,0,0], "max": [0.1,0.1,0.1]}],
            "probes": )" + probes + "}";
        try {
            parse_scene(text, "x.json");
        } catch (const SceneError& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    EXPECT_EQ(load(R"([{"type": "presure"}])"),
              "x.json: /probes/0/type: found \"presure\", expected one of \"pressure\", \"height\", \"front\", \"fluid\"");
    EXPECT_EQ(load(R"([{"type": "height", "from": [0,0,0]}])"),
              "x.json: /probes/0/to: found nothing, expected an array of 3 numbers (metres)");
    EXPECT_EQ(load(R"([{"type": "fluid", "rate": 0}])"),
              "x.json: /probes/0/rate: found 0, expected a number > 0 (samples per simulated second)");
    EXPECT_EQ(load(R"([{"type": "fluid", "point": [0,0,0]}])"),
              "x.json: /probes/0/point: found an unknown key \"point\", expected one of \"type\", \"name\", \"rate\", "
              "\"experiment\" for a \"fluid\" probe");
    EXPECT_EQ(load(R"([{"type": "fluid", "name": "a"}, {"type": "fluid", "name": "a"}])"),
              "x.json: /probes/1/name: found \"a\", expected a name no other probe has (it names probes/<name>.csv)");
    EXPECT_EQ(load(R"({"type": "fluid"})"), "x.json: /probes: found {\"type\":\"fluid\"}, expected an array of probes");
}
