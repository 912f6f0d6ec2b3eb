// scene_to_json and validate_scene (engine/data/scene_writer.cpp): a scene written out loads back
// into an equal Scene, field for field (Scene::operator==, exact doubles: nlohmann writes the
// shortest text that reads back to the same double), for every shipped scene, the valid corpus
// and a scene built in code with every boundary shape, motion, probe kind and optional key; and
// a scene built in code that breaks a loader rule is refused with the loader's message, naming
// the key by its scene-file path.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "engine/core/errors.hpp"
#include "engine/data/scene.hpp"
#include "test_scenes.hpp"

using namespace sph;

namespace {

/// Writes `s`, reads it back and expects the same Scene, but for what the text does not hold: the
/// file it was loaded from and the OBJ file a mesh was read from (written inline); on a
/// difference, prints both as JSON.
void expect_round_trip(Scene s, const std::string& what) {
    const nlohmann::json j = scene_to_json(s);
    Scene back = parse_scene(j.dump(), what);
    back.source = s.source;
    for (BoundaryDesc& b : s.boundaries) b.file.clear();
    const bool equal = back == s;
    EXPECT_TRUE(equal) << what << ": written\n" << j.dump() << "\nread back as\n" << scene_to_json(back).dump();
}

std::string refusal(const Scene& s) {
    try {
        validate_scene(s);
    } catch (const SceneError& e) {
        return e.what();
    }
    return "accepted";
}

}  // namespace

TEST(SceneWriter, EveryShippedAndValidSceneLoadsBackEqual) {
    int n = 0;
    for (const char* dir : {SPH_SOURCE_DIR "/scenes", SPH_SOURCE_DIR "/tests/data/valid"})
        for (const auto& entry : std::filesystem::directory_iterator(dir)) {
            if (entry.path().extension() != ".json") continue;
            const Scene s = load_scene(entry.path());
            expect_round_trip(s, entry.path().string());
            EXPECT_NO_THROW(validate_scene(s)) << entry.path();
            ++n;
        }
    EXPECT_GE(n, 13);  // 12 shipped scenes and the valid corpus
}

// Every shape (a mesh inline), every motion, every probe kind, the optional keys set, a PCISPH
// scene with an emitter and a DFSPH one: what the shipped scenes may not hold.
TEST(SceneWriter, ASceneWithEveryKindOfEntryLoadsBackEqual) {
    Scene s = test::tank_scene(Vec3d(0.3, 0.2, 0.3), Vec3d(1.0, 1.0, 1.0));
    s.name = "everything";
    s.domain = Aabb{Vec3d::Constant(-0.1), Vec3d::Constant(1.1)};
    s.simulation.stepping.mode = SteppingMode::Individual;
    s.simulation.stepping.lambda_v = 0.07;
    s.simulation.stepping.activation = Activation::Paper;
    s.simulation.end_time = 0.37;
    s.simulation.sort_interval = 0;
    s.simulation.gravity = Vec3d(0.1, -9.7, 0.3);
    s.fluid.speed_of_sound = 31.5;
    s.fluid.boundary_viscosity = 0.02;
    s.fluid.density = DensityForm::Continuity;
    s.fluid.density_diffusion = 0.13;
    s.fluid.kinematic_viscosity = 1e-6;
    s.fluid.wall_pressure = WallPressure::Mirrored;
    s.fluid.pressure_gradient = PressureGradient::Corrected;
    s.fluid_blocks.front().velocity = Vec3d(0.5, 0, -0.25);
    s.fluid_blocks.push_back(FluidBlock{Aabb{Vec3d(0.5, 0, 0), Vec3d(0.7, 0.1, 0.2)}, Vec3d::Zero(), true});
    // An axis off the coordinate axes: normalised by sinusoidal_motion, and read back unchanged
    // (sph::unit keeps a unit vector as it is; normalising (1, 0, 1) twice moved it an ulp).
    s.boundaries.push_back(test::box_obstacle(Aabb{Vec3d(0.4, 0.3, 0.4), Vec3d(0.5, 0.4, 0.5)},
                                              sinusoidal_motion(Vec3d(1, 0, 1), 0.05, 0.8, 0.3)));
    s.boundaries.push_back(test::box_obstacle(Aabb{Vec3d(0.05, 0.5, 0.05), Vec3d(0.1, 0.6, 0.1)},
                                              linear_motion(Vec3d(0.1, 0, 0.05))));
    BoundaryDesc sphere;
    sphere.shape = BoundaryShape::Sphere;
    sphere.center = Vec3d(0.8, 0.6, 0.8);
    sphere.radius = 0.05;
    sphere.motion = path_motion({Vec3d(0.8, 0.6, 0.8), Vec3d(0.8, 0.7, 0.7), Vec3d(0.7, 0.7, 0.7)}, 0.2, true);
    s.boundaries.push_back(sphere);
    // A cylinder (its box derived as the loader derives it) carried round a circle about a tilted
    // axis, starting at its reference point.
    BoundaryDesc cylinder = cylinder_boundary(Vec3d(0.2, 0.5, 0.7), Vec3d(0, 1, 0), 0.04, 0.2);
    cylinder.motion = circle_motion(Vec3d(0.3, 0.6, 0.7), 0.1, Vec3d(0, 1, 0.001), 0.3, reference_point(cylinder));
    s.boundaries.push_back(cylinder);
    // One triangle, counter-clockwise seen from above.
    s.boundaries.push_back(mesh_boundary({Vec3d(0.6, 0.8, 0.1), Vec3d(0.7, 0.8, 0.1), Vec3d(0.6, 0.8, 0.2)}, {{0, 2, 1}}));
    for (ProbeDesc d : {ProbeDesc{}, ProbeDesc{}, ProbeDesc{}, ProbeDesc{}, ProbeDesc{}, ProbeDesc{}, ProbeDesc{}}) {
        d.name = "p" + std::to_string(s.probes.size());
        s.probes.push_back(d);
    }
    s.probes[0].type = ProbeType::Pressure, s.probes[0].point = Vec3d(0.1, 0.1, 0.1), s.probes[0].rate = 250;
    s.probes[1].type = ProbeType::Pressure, s.probes[1].source = PressureSource::Boundary;
    s.probes[1].point = Vec3d(0, 0.05, 0.1), s.probes[1].radius = 0.03;
    s.probes[2].type = ProbeType::Pressure, s.probes[2].source = PressureSource::Sensor;
    s.probes[2].point = Vec3d(1, 0.05, 0.1), s.probes[2].diameter = 0.009, s.probes[2].normal = Vec3d(-1, 0, 0);
    s.probes[3].type = ProbeType::Height, s.probes[3].from = Vec3d(0.1, 0, 0.1), s.probes[3].to = Vec3d(0.1, 1, 0.1);
    s.probes[3].height_method = HeightMethod::Highest;
    s.probes[4].type = ProbeType::Front, s.probes[4].direction = Vec3d(0, 0, 1), s.probes[4].min_neighbours = 6;
    s.probes[4].experiment = ProbeExperiment{"front.csv", 2.0, 3.0, 0.1, 0.2, 0.5, 2.5};
    s.probes[5].type = ProbeType::Front, s.probes[5].method = FrontMethod::Colour;
    s.probes[5].from = Vec3d(0, 0.01, 0.1), s.probes[5].to = Vec3d(1, 0.01, 0.1);
    s.probes[6].type = ProbeType::Fluid;
    s.output.formats = {FrameFormat::Ply, FrameFormat::Vtu};
    s.output.attributes = {"velocity", "density"};
    s.output.attributes_explicit = true;
    s.output.surface.smoothing = 0.0;
    ASSERT_EQ(refusal(s), "accepted");
    expect_round_trip(s, "everything (wcsph)");

    // A height field replaces the mesh (the loader derives its vertices, triangles and box).
    Scene hf = load_scene(SPH_SOURCE_DIR "/scenes/dam_break.json");
    hf.boundaries.push_back(heightfield_boundary(Aabb{Vec3d(0.5, 0, 0), Vec3d(1.2, 0, 0.2)},
                                                 {{0, 0.1, 0.05}, {0.02, 0.12, 0.07}}));
    ASSERT_EQ(refusal(hf), "accepted");
    expect_round_trip(hf, "dam_break with a height field");

    Scene pc = test::tank_scene(Vec3d(0.3, 0.2, 0.3), Vec3d(1.0, 1.0, 1.0));
    pc.simulation.method = Method::Pcisph;
    pc.simulation.stepping.mode = SteppingMode::Adaptive;
    pc.fluid.viscosity.reset();
    pc.fluid.surface_tension = 0.5;
    pc.pcisph.loop = PcisphLoop::UntilConverged;
    pc.pcisph.eta_max = 0.08;
    pc.pcisph.delta_shock = 0.03;
    pc.boundary.handling = BoundaryHandling::DirectForcing;
    pc.boundary.friction = 0.4;
    pc.emitters.push_back(EmitterDesc{Vec3d(0.5, 0.8, 0.5), Vec3d(0, -1, 0), 0.05, 500, 0.1, 0.9, 1000});
    pc.emitters.push_back(EmitterDesc{});  // no end, no cap
    pc.emitters.back().position = Vec3d(0.7, 0.8, 0.5);
    ASSERT_EQ(refusal(pc), "accepted");
    expect_round_trip(pc, "pcisph");

    Scene df = test::tank_scene(Vec3d(0.3, 0.2, 0.3), Vec3d(1.0, 1.0, 1.0));
    df.simulation.method = Method::Dfsph;
    df.simulation.stepping.mode = SteppingMode::Adaptive;
    df.dfsph.warm_start = false;
    df.dfsph.eta = 0.001;
    df.dfsph.max_divergence_iterations = 7;
    expect_round_trip(df, "dfsph");
}

// What a library user can get wrong, refused as the loader refuses it in a file (the same
// message: the key's path, the value found, what was expected) and before anything is built.
TEST(SceneWriter, ValidateRefusesACodeBuiltSceneWithTheLoadersMessage) {
    const Scene good = test::tank_scene(Vec3d(0.1, 0.1, 0.1), Vec3d(0.2, 0.2, 0.2));
    ASSERT_EQ(refusal(good), "accepted");
    const std::string at = "scene \"test_tank\" (built in code): ";

    Scene s = good;
    s.fluid.particle_radius = -0.01;
    EXPECT_EQ(refusal(s), at + "/fluid/particle_radius: found -0.01, expected a number > 0 (metres)");

    s = good;
    s.simulation.gravity.y() = std::numeric_limits<double>::quiet_NaN();  // no JSON number: null
    EXPECT_EQ(refusal(s), at + "/simulation/gravity/1: found null, expected a number (m/s^2)");

    s = good;
    s.probes.push_back(ProbeDesc{});
    s.probes.back().name = "totals";
    s.probes.back().rate = std::numeric_limits<double>::quiet_NaN();  // a key that is there, null
    EXPECT_EQ(refusal(s), at + "/probes/0/rate: found null, expected a number > 0 (samples per simulated second)");

    s = good;
    s.fluid_blocks.front().box.max = Vec3d(0.1, 0.3, 0.1);
    EXPECT_EQ(refusal(s), at + "/fluid_blocks/0: found {\"hydrostatic\":false,\"max\":[0.1,0.3,0.1],\"min\":[0.0,0.0,0.0],"
                               "\"velocity\":[0.0,..., expected a block inside the container /boundaries/0 "
                               "(min [0,0,0], max [0.2,0.2,0.2])");  // the value shown cut at 80 characters

    s = good;
    s.simulation.stepping.dt_min = 1e-2;  // above dt_max
    EXPECT_EQ(refusal(s), at + "/simulation/stepping/dt_min: found 0.01, expected a number > 0 and < dt_max = 0.005 (seconds)");

    s = good;
    s.fluid.density_diffusion = 0.1;  // summation density: nothing to diffuse
    EXPECT_EQ(refusal(s).rfind(at + "/fluid/density_diffusion: found 0.1, expected no key unless fluid.density is "
                                    "\"continuity\"", 0),
              0u)
        << refusal(s);

    // A loaded scene changed in code is named by its file.
    Scene d = load_scene(SPH_SOURCE_DIR "/scenes/dam_break.json");
    d.simulation.end_time = 0;
    EXPECT_EQ(refusal(d), std::string(SPH_SOURCE_DIR) + "/scenes/dam_break.json (changed in code): /simulation/end_time: "
                                                        "found 0.0, expected a number > 0 (seconds)");
}

// The values a scene file does not hold, which the loader derives (a cylinder's box, a height
// field's surface and box, a mesh's box, a circle's start): built in code by the sph:: helpers
// they equal the loader's (the round trips above); set otherwise, or left stale after an edit,
// they are refused naming the boundary, what was found and what the rest of it gives. Agreement
// is to 1e-12 relative, so a value derived by another order of the same operations passes.
TEST(SceneWriter, ValidateRefusesDerivedValuesThatDisagreeWithTheRest) {
    const Scene good = test::tank_scene(Vec3d(0.1, 0.1, 0.1), Vec3d(1, 1, 1));
    const std::string at = "scene \"test_tank\" (built in code): /boundaries/1";
    const auto with = [&](const BoundaryDesc& b) {
        Scene s = good;
        s.boundaries.push_back(b);
        return s;
    };

    BoundaryDesc cyl = cylinder_boundary(Vec3d(0.5, 0.2, 0.5), Vec3d(0, 2, 0), 0.1, 0.3);
    EXPECT_EQ(cyl.axis, Vec3d(0, 1, 0));
    EXPECT_EQ(cyl.box.min, Vec3d(0.4, 0.2, 0.4));
    EXPECT_EQ(cyl.box.max, Vec3d(0.6, 0.5, 0.6));
    EXPECT_EQ(refusal(with(cyl)), "accepted");
    BoundaryDesc off = cyl;
    off.box.max.x() += 1e-13;  // within 1e-12
    EXPECT_EQ(refusal(with(off)), "accepted");
    off.box.max.x() += 1e-9;
    EXPECT_EQ(refusal(with(off)), at + ": found a cylinder whose box is min [0.4,0.2,0.4], max [0.6000000010001,0.5,0.6], "
                                       "expected the box "
                                       "its center, axis, radius and height give, min [0.4,0.2,0.4], max [0.6,0.5,0.6] "
                                       "(sph::cylinder_boundary fills it)");
    BoundaryDesc unset;  // the fields set by hand, the box forgotten
    unset.shape = BoundaryShape::Cylinder;
    unset.center = cyl.center, unset.axis = cyl.axis, unset.radius = cyl.radius, unset.height = cyl.height;
    EXPECT_EQ(refusal(with(unset)), at + ": found a cylinder whose box is min [0,0,0], max [0,0,0], expected the box its "
                                         "center, axis, radius and height give, min [0.4,0.2,0.4], max [0.6,0.5,0.6] "
                                         "(sph::cylinder_boundary fills it)");

    BoundaryDesc hf = heightfield_boundary(Aabb{Vec3d(0.2, 0, 0.2), Vec3d(0.8, 0, 0.8)}, {{0.1, 0.2}, {0.15, 0.05}});
    EXPECT_EQ(hf.vertices.size(), 4u);
    EXPECT_EQ(hf.triangles.size(), 2u);
    EXPECT_EQ(hf.box.min, Vec3d(0.2, 0.05, 0.2));
    EXPECT_EQ(hf.box.max, Vec3d(0.8, 0.2, 0.8));
    EXPECT_EQ(refusal(with(hf)), "accepted");
    EXPECT_EQ(refusal(with(translated(hf, Vec3d(0.05, 0.1, -0.05)))), "accepted");  // heights, surface and box move together
    BoundaryDesc stale = hf;
    stale.heights[1][1] = 0.3;  // edited after the surface was built
    EXPECT_EQ(refusal(with(stale)), at + ": found a heightfield with 4 vertices and 2 triangles that are not its heights' "
                                         "surface, expected the 4 vertices and 2 triangles its heights give over its box "
                                         "in x and z (sph::heightfield_boundary builds them)");
    stale = heightfield_boundary(Aabb{Vec3d(0.2, 0, 0.2), Vec3d(0.8, 0, 0.8)}, stale.heights);
    stale.box.max.y() = 0.2;  // the surface rebuilt, the top of the box put back by hand
    EXPECT_EQ(refusal(with(stale)), at + ": found a heightfield whose box is min [0.2,0.1,0.2], max [0.8,0.2,0.8], expected "
                                         "its x and z span with the heights' range in y, min [0.2,0.1,0.2], max "
                                         "[0.8,0.3,0.8] (sph::heightfield_boundary fills it)");
    // Too few heights: no surface is built, and the loader's rule names the heights.
    EXPECT_EQ(refusal(with(heightfield_boundary(Aabb{Vec3d(0.2, 0, 0.2), Vec3d(0.8, 0, 0.8)}, {{0.1, 0.2}}))),
              at + "/heights: found [[0.1,0.2]], expected an array of at least 2 rows (along z), each an array of the same "
                   "number (>= 2) of heights (metres, along x)");

    BoundaryDesc mesh = mesh_boundary({Vec3d(0.3, 0.4, 0.3), Vec3d(0.6, 0.4, 0.3), Vec3d(0.3, 0.5, 0.6)}, {{0, 2, 1}});
    EXPECT_EQ(mesh.box.min, Vec3d(0.3, 0.4, 0.3));
    EXPECT_EQ(mesh.box.max, Vec3d(0.6, 0.5, 0.6));
    EXPECT_EQ(refusal(with(mesh)), "accepted");
    mesh.vertices[1].x() = 0.7;  // moved after the box was taken
    EXPECT_EQ(refusal(with(mesh)), at + ": found a mesh whose box is min [0.3,0.4,0.3], max [0.6,0.5,0.6], expected its "
                                        "vertices' bounding box, min [0.3,0.4,0.3], max [0.7,0.5,0.6] "
                                        "(sph::mesh_boundary fills it)");

    BoundaryDesc rod = test::box_obstacle(Aabb{Vec3d(0.45, 0.1, 0.45), Vec3d(0.55, 0.6, 0.55)}, linear_motion(Vec3d::Zero()));
    rod.motion = circle_motion(Vec3d(0.4, 0.3, 0.5), 0.1, Vec3d(0, 1, 0), 0.5, reference_point(rod));
    EXPECT_EQ(refusal(with(rod)), "accepted");
    rod.motion = circle_motion(Vec3d(0.4, 0.3, 0.5), 0.1, Vec3d(0, 1, 0), 0.5, Vec3d(0.4, 0.3, 0.9));  // not the rod's point
    EXPECT_EQ(refusal(with(rod)), at + "/motion: found a circle whose start direction is [0,0,1], expected [1,0,0], the "
                                       "direction of the box's reference point from the circle's centre in its plane "
                                       "(sph::circle_motion with sph::reference_point of the boundary gives it)");

    // Directions and axes the loader makes unit vectors: set by hand at another length, the run
    // would differ from the same scene read from a file (a motion twice as far, a probe reading
    // along another line).
    BoundaryDesc shaken = test::box_obstacle(Aabb{Vec3d(0.45, 0.1, 0.45), Vec3d(0.55, 0.6, 0.55)},
                                             sinusoidal_motion(Vec3d(1, 0, 0), 0.02, 0.5));
    shaken.motion->axis = Vec3d(2, 0, 0);
    EXPECT_EQ(refusal(with(shaken)), at + "/motion/axis: found [2.0,0.0,0.0], expected [1.0,0.0,0.0], the value the loader "
                                          "makes of it (a direction or axis is a unit vector: sph::unit)");
    Scene probed = good;
    ProbeDesc sensor;
    sensor.name = "wall";
    sensor.type = ProbeType::Pressure, sensor.source = PressureSource::Sensor;
    sensor.point = Vec3d(1, 0.05, 0.5), sensor.diameter = 0.02, sensor.normal = Vec3d(-3, 0, 0);
    probed.probes.push_back(sensor);
    EXPECT_EQ(refusal(probed), "scene \"test_tank\" (built in code): /probes/0/normal: found [-3.0,0.0,0.0], expected "
                               "[-1.0,0.0,0.0], the value the loader makes of it (a direction or axis is a unit vector: "
                               "sph::unit)");
    probed.probes.back().normal = Vec3d(-1, 0, 0);
    EXPECT_EQ(refusal(probed), "accepted");
    ProbeDesc colour;  // along y, its direction left at the default x
    colour.name = "rise";
    colour.type = ProbeType::Front, colour.method = FrontMethod::Colour;
    colour.from = Vec3d(0.5, 0, 0.5), colour.to = Vec3d(0.5, 1, 0.5);
    probed.probes.push_back(colour);
    EXPECT_EQ(refusal(probed), "scene \"test_tank\" (built in code): /probes/1/direction: found [1,0,0] on a colour front, "
                               "expected [0,1,0], the unit vector from its `from` to its `to`, which the probe reads along");
    probed.probes.back().direction = Vec3d(0, 1, 0);
    EXPECT_EQ(refusal(probed), "accepted");
}
