/// @file scene_loader_test.cpp
/// @brief Scene loading: the malformed corpus (exact messages), valid scenes, defaults,
/// command-line overrides and the scale rule.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "engine/core/errors.hpp"
#include "engine/data/scene.hpp"
#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/data/world_init.hpp"
#include "engine/run/simulation.hpp"
#include "systems/methods/recipes.hpp"

namespace sph {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using Overrides = std::vector<std::pair<std::string, json>>;

const fs::path k_corpus = fs::path(SPH_SOURCE_DIR) / "tests" / "data" / "malformed";

std::string read_text(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

std::string replace_all(std::string s, const std::string& from, const std::string& to) {
    for (std::size_t pos = s.find(from); pos != std::string::npos;
         pos = s.find(from, pos + to.size())) {
        s.replace(pos, from.size(), to);
    }
    return s;
}

/// The message of the InputError thrown by `f`, or a marker that fails any comparison.
template <class F>
std::string error_of(F&& f) {
    try {
        f();
    } catch (const InputError& e) {
        return e.what();
    }
    return "<no error thrown>";
}

// A valid scene to start from; tests change one thing at a time.
const char* const k_minimal = R"({
  "name": "minimal",
  "fluid_blocks": [{"min": [0, 0, 0], "max": [0.5, 0.5, 0.5]}]
})";

// ---- (a) Malformed corpus: every file must fail with exactly its .expected message. ----

TEST(SceneLoader, MalformedCorpusFailsWithExactMessages) {
    std::vector<fs::path> files;
    for (const auto& entry : fs::directory_iterator(k_corpus)) {
        // runner_*: refused by sph-run, not by the loader (tests/bad_scenes_cli.sh runs them).
        if (entry.path().filename().string().rfind("runner_", 0) == 0) {
            if (entry.path().extension() == ".json") {
                EXPECT_NO_THROW(load_scene(entry.path())) << entry.path();
            }
            continue;
        }
        if (entry.path().extension() == ".json") files.push_back(entry.path());
        if (entry.path().extension() == ".expected") {
            EXPECT_TRUE(fs::exists(fs::path(entry.path()).replace_extension(".json")))
                << entry.path().filename() << " has no .json beside it";
        }
    }
    std::sort(files.begin(), files.end());
    ASSERT_GE(files.size(), 40u) << "the malformed corpus at " << k_corpus << " is too small";

    for (const fs::path& file : files) {
        const fs::path expected_file = fs::path(file).replace_extension(".expected");
        ASSERT_TRUE(fs::exists(expected_file)) << file.filename() << " has no .expected file";
        std::string expected = read_text(expected_file);
        while (!expected.empty() && (expected.back() == '\n' || expected.back() == '\r')) {
            expected.pop_back();
        }
        expected = replace_all(expected, "<file>", file.string());

        try {
            load_scene(file);
            ADD_FAILURE() << file.filename() << ": loaded without an error; expected\n  "
                          << expected;
        } catch (const SceneError& e) {
            EXPECT_EQ(e.what(), expected) << "in " << file.filename();
            EXPECT_EQ(e.file(), file.string()) << "in " << file.filename();
            EXPECT_EQ(
                std::string(e.what()).rfind(file.string() + ": " + e.json_path() + ": found ", 0),
                0u)
                << "in " << file.filename() << ": the message does not start with file and path";
        } catch (const InputError& e) {
            EXPECT_EQ(e.what(), expected) << "in " << file.filename();
        } catch (const std::exception& e) {
            ADD_FAILURE() << file.filename() << ": threw a " << typeid(e).name()
                          << " that is not an InputError: " << e.what();
        }
    }
}

TEST(SceneLoader, MissingFileIsAnInputError) {
    const fs::path missing = fs::path(testing::TempDir()) / "no_such_scene.json";
    fs::remove(missing);
    EXPECT_EQ(error_of([&] { load_scene(missing); }),
              missing.string() + ": cannot open scene file (No such file or directory)");
    EXPECT_EQ(error_of([&] { load_scene(testing::TempDir()); }),
              fs::path(testing::TempDir()).string() + ": cannot open scene file (Is a directory)");
}

TEST(SceneLoader, SyntaxErrorColumnPointsAtTheTokenStart) {
    // The string before the missing comma holds an escaped quote; the column is that of the
    // next key's opening quote (line 1: {"a": "x\"y" "b": 1}).
    EXPECT_EQ(error_of([] { parse_scene(R"({"a": "x\"y" "b": 1})", "s.json"); }),
              "s.json: JSON syntax error at line 1, column 14: unexpected string literal; "
              "expected ',' or '}'");
    EXPECT_EQ(error_of([] { parse_scene("{\n\"a\": 12 3}", "s.json"); }),
              "s.json: JSON syntax error at line 2, column 9: unexpected number literal; "
              "expected ',' or '}'");
    // Columns count characters, not bytes: "é" is two bytes.
    EXPECT_EQ(error_of([] { parse_scene("{\"name\": \"\xc3\xa9\" x}", "s.json"); }),
              "s.json: JSON syntax error at line 1, column 14: invalid word \"x\" (strings need "
              "double quotes; the literals are true, false and null)");
}

TEST(SceneLoader, SuggestionsIgnoreCaseAndAllowTranspositions) {
    EXPECT_EQ(error_of([] {
                  parse_scene(R"({"name": "t", "simulation": {"stepping": {"mode": "Global"}}})",
                              "s.json");
              }),
              "s.json: /simulation/stepping/mode: found \"Global\", expected one of \"constant\", "
              "\"global\", \"individual\", \"binned\", \"adaptive\" (did you mean \"global\"?)");
    EXPECT_EQ(
        error_of([] { parse_scene(R"({"name": "t", "fluid": {"viscostiy": 0.1}})", "s.json"); }),
        "s.json: /fluid: found unknown key \"viscostiy\", expected one of: rest_density, "
        "particle_radius, viscosity, speed_of_sound, density_fluctuation, surface_tension, boundary_viscosity, "
        "pressure_gradient, support, density, density_diffusion, kinematic_viscosity, wall_pressure (did you mean \"viscosity\"?)");
}

// ---- (b) Valid scenes. ----

TEST(SceneLoader, CompleteSceneParsesEveryField) {
    const char* const text = R"({
      "name": "full",
      "description": "every key set to a value that differs from its default",
      "simulation": {
        "method": "wcsph",
        "stepping": {"mode": "constant", "dt": 0.0002, "lambda_v": 0.3, "lambda_f": 0.2,
                     "acoustic": false, "lambda_c": 0.5, "dt_max": 0.002, "dt_min": 1e-6, "activation": "paper"},
        "end_time": 2.5, "frame_rate": 0, "scale": 8, "gravity": [0, 0, -9.8], "sort_interval": 4
      },
      "domain": {"min": [-0.5, -0.5, -0.5], "max": [2.5, 1.5, 1.5]},
      "fluid": {"rest_density": 998.2, "particle_radius": 0.02, "viscosity": 0,
                "speed_of_sound": 40, "density_fluctuation": 0.02, "support": 2.5},
      "fluid_blocks": [
        {"min": [0, 0, 0], "max": [0.4, 0.6, 1]},
        {"min": [1.5, 0, 0], "max": [2, 0.2, 1], "velocity": [-1, 0, 0.5]}
      ],
      "boundaries": [
        {"type": "container", "min": [0, 0, 0], "max": [2, 1, 1]},
        {"type": "box", "min": [1, 0, 0.4], "max": [1.2, 0.3, 0.6]},
        {"type": "sphere", "center": [0.8, 0.5, 0.5], "radius": 0.1}
      ],
      "output": {"format": ["ply", "vtu", "bgeo"], "attributes": ["acceleration", "velocity", "dt", "active"]}
    })";
    const Scene s = parse_scene(text, "full.json");

    EXPECT_EQ(s.name, "full");
    EXPECT_TRUE(s.source.empty());  // parse_scene reads text, not a file
    EXPECT_EQ(s.simulation.method, Method::Wcsph);
    EXPECT_EQ(s.simulation.stepping.mode, SteppingMode::Constant);
    EXPECT_DOUBLE_EQ(s.simulation.stepping.dt, 2e-4);
    EXPECT_DOUBLE_EQ(s.simulation.stepping.lambda_v, 0.3);
    EXPECT_DOUBLE_EQ(s.simulation.stepping.lambda_f, 0.2);
    EXPECT_FALSE(s.simulation.stepping.acoustic);
    EXPECT_DOUBLE_EQ(s.simulation.stepping.lambda_c, 0.5);
    EXPECT_DOUBLE_EQ(s.simulation.stepping.dt_max, 2e-3);
    EXPECT_DOUBLE_EQ(s.simulation.stepping.dt_min, 1e-6);
    EXPECT_EQ(s.simulation.stepping.activation, Activation::Paper);
    EXPECT_DOUBLE_EQ(s.simulation.end_time, 2.5);
    EXPECT_DOUBLE_EQ(s.simulation.frame_rate, 0.0);
    EXPECT_DOUBLE_EQ(s.simulation.scale, 8.0);
    EXPECT_EQ(s.simulation.gravity, Vec3d(0, 0, -9.8));
    EXPECT_EQ(s.simulation.sort_interval, 4);

    ASSERT_TRUE(s.domain.has_value());
    EXPECT_EQ(s.domain->min, Vec3d(-0.5, -0.5, -0.5));
    EXPECT_EQ(s.domain->max, Vec3d(2.5, 1.5, 1.5));

    EXPECT_DOUBLE_EQ(s.fluid.rest_density, 998.2);
    EXPECT_DOUBLE_EQ(s.fluid.particle_radius, 0.02);
    EXPECT_EQ(s.fluid.viscosity, 0.0);
    ASSERT_TRUE(s.fluid.speed_of_sound.has_value());
    EXPECT_DOUBLE_EQ(*s.fluid.speed_of_sound, 40.0);
    EXPECT_DOUBLE_EQ(s.fluid.density_fluctuation, 0.02);
    EXPECT_DOUBLE_EQ(s.fluid.support, 2.5);

    ASSERT_EQ(s.fluid_blocks.size(), 2u);
    EXPECT_EQ(s.fluid_blocks[0].box.min, Vec3d(0, 0, 0));
    EXPECT_EQ(s.fluid_blocks[0].box.max, Vec3d(0.4, 0.6, 1));
    EXPECT_EQ(s.fluid_blocks[0].velocity, Vec3d(0, 0, 0));
    EXPECT_EQ(s.fluid_blocks[1].box.min, Vec3d(1.5, 0, 0));
    EXPECT_EQ(s.fluid_blocks[1].box.max, Vec3d(2, 0.2, 1));
    EXPECT_EQ(s.fluid_blocks[1].velocity, Vec3d(-1, 0, 0.5));

    ASSERT_EQ(s.boundaries.size(), 3u);
    EXPECT_EQ(s.boundaries[0].shape, BoundaryShape::Container);
    EXPECT_EQ(s.boundaries[0].box.min, Vec3d(0, 0, 0));
    EXPECT_EQ(s.boundaries[0].box.max, Vec3d(2, 1, 1));
    EXPECT_EQ(s.boundaries[1].shape, BoundaryShape::Box);
    EXPECT_EQ(s.boundaries[1].box.min, Vec3d(1, 0, 0.4));
    EXPECT_EQ(s.boundaries[1].box.max, Vec3d(1.2, 0.3, 0.6));
    EXPECT_EQ(s.boundaries[2].shape, BoundaryShape::Sphere);
    EXPECT_EQ(s.boundaries[2].center, Vec3d(0.8, 0.5, 0.5));
    EXPECT_DOUBLE_EQ(s.boundaries[2].radius, 0.1);

    EXPECT_EQ(s.output.formats, (std::vector<FrameFormat>{FrameFormat::Ply, FrameFormat::Vtu, FrameFormat::Bgeo}));
    EXPECT_EQ(s.output.attributes, (std::vector<std::string>{"acceleration", "velocity", "dt", "active"}));
    EXPECT_TRUE(s.output.attributes_explicit);

    EXPECT_DOUBLE_EQ(s.particle_radius(), 0.01);  // 0.02 / cbrt(8)
}

TEST(SceneLoader, MissingSectionsTakeTheStructDefaults) {
    const Scene s = parse_scene(k_minimal, "minimal.json");
    const Scene d;  // the documented defaults
    EXPECT_EQ(s.name, "minimal");
    EXPECT_EQ(s.simulation.method, d.simulation.method);
    EXPECT_EQ(s.simulation.stepping.mode, SteppingMode::Global);
    EXPECT_EQ(s.simulation.stepping.dt, d.simulation.stepping.dt);
    EXPECT_EQ(s.simulation.stepping.lambda_v, 0.1);
    EXPECT_EQ(s.simulation.stepping.lambda_f, 0.05);
    EXPECT_EQ(s.simulation.stepping.acoustic, d.simulation.stepping.acoustic);
    EXPECT_EQ(s.simulation.stepping.lambda_c, d.simulation.stepping.lambda_c);
    EXPECT_EQ(s.simulation.stepping.dt_max, d.simulation.stepping.dt_max);
    EXPECT_EQ(s.simulation.stepping.dt_min, d.simulation.stepping.dt_min);
    EXPECT_EQ(s.simulation.stepping.activation, Activation::Deadline);
    EXPECT_EQ(s.simulation.end_time, 1.0);
    EXPECT_EQ(s.simulation.frame_rate, 30.0);
    EXPECT_EQ(s.simulation.scale, 1.0);
    EXPECT_EQ(s.simulation.gravity, Vec3d(0, -9.81, 0));
    EXPECT_EQ(s.simulation.sort_interval, d.simulation.sort_interval);
    EXPECT_FALSE(s.domain.has_value());
    EXPECT_EQ(s.fluid.rest_density, 1000.0);
    EXPECT_EQ(s.fluid.particle_radius, 0.01);
    EXPECT_EQ(s.fluid.viscosity, d.fluid.viscosity);
    EXPECT_FALSE(s.fluid.speed_of_sound.has_value());
    EXPECT_EQ(s.fluid.density_fluctuation, d.fluid.density_fluctuation);
    ASSERT_EQ(s.fluid_blocks.size(), 1u);
    EXPECT_EQ(s.fluid_blocks[0].velocity, Vec3d(0, 0, 0));
    EXPECT_TRUE(s.boundaries.empty());
    EXPECT_EQ(s.output.formats, std::vector<FrameFormat>{FrameFormat::Vtu});
    EXPECT_EQ(s.output.attributes, (std::vector<std::string>{"velocity", "density", "pressure"}));
    EXPECT_FALSE(s.output.attributes_explicit);
    EXPECT_EQ(s.particle_radius(), 0.01);
}

TEST(SceneLoader, BlockSharingAFaceWithAnObstacleIsAllowed) {
    const char* const text = R"({
      "name": "t",
      "fluid_blocks": [{"min": [0, 0, 0], "max": [0.5, 0.5, 0.5]}],
      "boundaries": [{"type": "box", "min": [0.5, 0, 0], "max": [1, 1, 1]},
                     {"type": "sphere", "center": [0.25, 0.75, 0.25], "radius": 0.25}]
    })";
    EXPECT_NO_THROW(parse_scene(text, "t.json"));
}

// Blocks that share a face are valid (cross_blocks_overlap in the corpus is the overlapping
// case): their lattices interleave without a coincident pair. Bound: the nearest pair is at
// least 0.9 spacing apart (the hydrostatic start compresses the lattice along gravity by
// rho0 g H / (rho0 c_s^2) ~ 1e-3, far less than 10 %), where overlapping lattices would put
// pairs at distance 0.
TEST(SceneLoader, BlocksSharingAFaceGiveNoCoincidentParticles) {
    const char* const text = R"({
      "name": "t",
      "fluid_blocks": [{"min": [0, 0, 0], "max": [0.1, 0.1, 0.1]}, {"min": [0.1, 0, 0], "max": [0.2, 0.1, 0.1]}],
      "boundaries": [{"type": "container", "min": [0, 0, 0], "max": [0.3, 0.3, 0.3]}]
    })";
    const Scene scene = parse_scene(text, "t.json");
    const auto sim = make_simulation(scene);
    const auto x = sim->world().fluid.store.get(comp::position);
    ASSERT_EQ(x.size(), 250u);
    double nearest = 1e9;
    for (std::size_t i = 0; i < x.size(); ++i)
        for (std::size_t j = i + 1; j < x.size(); ++j) nearest = std::min(nearest, double((x[i] - x[j]).norm()));
    EXPECT_GE(nearest, 0.9 * 2 * scene.particle_radius());
}

TEST(SceneLoader, LoadSceneReadsTheFileAndRecordsItsSource) {
    const fs::path file = fs::path(testing::TempDir()) / "scene_loader_test_minimal.json";
    std::ofstream(file) << k_minimal;
    const Scene s = load_scene(file, {{"/simulation/end_time", 0.25}});
    EXPECT_EQ(s.name, "minimal");
    EXPECT_EQ(s.source, file);
    EXPECT_DOUBLE_EQ(s.simulation.end_time, 0.25);
    fs::remove(file);
}

// ---- Overrides. ----

TEST(SceneLoader, OverridesChangeValuesAndCreateMissingObjects) {
    const Overrides overrides{
        {"/simulation/stepping/mode", "constant"},  // "simulation" is absent: created
        {"/simulation/stepping/lambda_v", 0.2},
        {"/simulation/end_time", 2.5},
        {"/fluid_blocks/0/velocity", json::array({1, 0, 0})},
        {"/output/attributes", json::array({"density"})},
        {"/name", "renamed"},
    };
    const Scene s = parse_scene(k_minimal, "m.json", overrides);
    EXPECT_EQ(s.simulation.stepping.mode, SteppingMode::Constant);
    EXPECT_DOUBLE_EQ(s.simulation.stepping.lambda_v, 0.2);
    EXPECT_DOUBLE_EQ(s.simulation.end_time, 2.5);
    EXPECT_EQ(s.fluid_blocks[0].velocity, Vec3d(1, 0, 0));
    EXPECT_EQ(s.output.attributes, std::vector<std::string>{"density"});
    EXPECT_EQ(s.name, "renamed");
}

TEST(SceneLoader, OverrideReplacesAValueFromTheFile) {
    const char* const text = R"({"name": "t", "simulation": {"end_time": 3.0, "frame_rate": 10},
                                 "fluid_blocks": [{"min": [0, 0, 0], "max": [1, 1, 1]}]})";
    const Scene s = parse_scene(text, "t.json", {{"/simulation/end_time", 0.5}});
    EXPECT_DOUBLE_EQ(s.simulation.end_time, 0.5);
    EXPECT_DOUBLE_EQ(s.simulation.frame_rate, 10.0);  // siblings are kept
}

TEST(SceneLoader, InvalidOverrideSaysItWasSetOnTheCommandLine) {
    EXPECT_EQ(error_of([] {
                  parse_scene(k_minimal, "m.json", {{"/simulation/end_time", -1}});
              }),
              "m.json: /simulation/end_time: found -1, expected a number > 0 (seconds) (set on the "
              "command line)");
    EXPECT_EQ(error_of([] {
                  parse_scene(k_minimal, "m.json", {{"/simulation/stepping/mode", "globel"}});
              }),
              "m.json: /simulation/stepping/mode: found \"globel\", expected one of \"constant\", "
              "\"global\", \"individual\", \"binned\", \"adaptive\" (did you mean \"global\"?) (set on the command line)");
    EXPECT_EQ(error_of([] {
                  parse_scene(k_minimal, "m.json", {{"/simulation/endtime", 2}});
              }),
              "m.json: /simulation: found unknown key \"endtime\", expected one of: method, "
              "stepping, end_time, frame_rate, scale, gravity, sort_interval, simd (did you mean "
              "\"end_time\"?) (set on the command line)");
    // The error is reported at dt_min, but the override of dt_max caused it.
    EXPECT_EQ(error_of([] {
                  parse_scene(k_minimal, "m.json", {{"/simulation/stepping/dt_max", 1e-8}});
              }),
              "m.json: /simulation/stepping/dt_min: found 1e-07, expected a number > 0 and < "
              "dt_max = 1e-08 (seconds) (set on the command line)");
    // An override inside a value that is then rejected as a whole.
    EXPECT_EQ(error_of([] {
                  parse_scene(k_minimal, "m.json", {{"/fluid_blocks/0/max/0", 0}});
              }),
              "m.json: /fluid_blocks/0/max: found [0,0.5,0.5], expected a point above min [0,0,0] "
              "on every axis (metres) (set on the command line)");
    // A cross check that involves an overridden section.
    const char* const with_domain =
        R"({"name": "t", "domain": {"min": [-1, -1, -1], "max": [1, 1, 1]},
            "fluid_blocks": [{"min": [0, 0, 0], "max": [0.5, 0.5, 0.5]}]})";
    EXPECT_EQ(error_of([&] {
                  parse_scene(with_domain, "t.json", {{"/domain/max", json::array({0.4, 1, 1})}});
              }),
              "t.json: /fluid_blocks/0: found {\"max\":[0.5,0.5,0.5],\"min\":[0,0,0]}, expected a "
              "block inside the domain (min [-1,-1,-1], max [0.4,1,1]) (set on the command line)");
}

TEST(SceneLoader, ErrorsElsewhereDoNotBlameTheCommandLine) {
    const char* const text = R"({"name": "t", "simulation": {"end_time": -1},
                                 "fluid_blocks": [{"min": [0, 0, 0], "max": [1, 1, 1]}]})";
    EXPECT_EQ(error_of([&] {
                  parse_scene(text, "t.json", {{"/simulation/frame_rate", 10}});
              }),
              "t.json: /simulation/end_time: found -1, expected a number > 0 (seconds)");
    EXPECT_NO_THROW(parse_scene(text, "t.json", {{"/simulation/end_time", 1}}))
        << "the override fixes the file's value";
}

TEST(SceneLoader, OverridePathsThatCannotBeSet) {
    EXPECT_EQ(
        error_of([] {
            parse_scene(k_minimal, "m.json", {{"/fluid_blocks/3/min", json::array({0, 0, 0})}});
        }),
        "m.json: /fluid_blocks/3: found nothing, expected an array index from 0 to 0 (set on "
        "the command line)");
    EXPECT_EQ(error_of([] {
                  parse_scene(k_minimal, "m.json", {{"/name/first", "x"}});
              }),
              "m.json: /name: found \"minimal\", expected an object holding \"first\" (set on the "
              "command line)");
    EXPECT_EQ(error_of([] {
                  parse_scene(k_minimal, "m.json", {{"simulation", 1}});
              }),
              "m.json: cannot apply override \"simulation\": expected a JSON pointer starting with "
              "'/'");
}

TEST(SceneLoader, ParseOverride) {
    using P = std::pair<std::string, json>;
    EXPECT_EQ(parse_override("simulation.stepping.lambda_v=0.1"),
              P("/simulation/stepping/lambda_v", 0.1));
    EXPECT_EQ(parse_override("simulation.stepping.mode=global"),
              P("/simulation/stepping/mode", "global"));  // a bare word is a string
    EXPECT_EQ(parse_override("simulation.stepping.acoustic=false"),
              P("/simulation/stepping/acoustic", false));
    EXPECT_EQ(parse_override("simulation.gravity=[0, 0, -9.81]"),
              P("/simulation/gravity", json::array({0, 0, -9.81})));
    EXPECT_EQ(parse_override("name=\"42\""), P("/name", "42"));  // quoted: a string, not a number
    EXPECT_EQ(parse_override("name=a=b"), P("/name", "a=b"));    // split at the first '='
    EXPECT_EQ(parse_override(" simulation.end_time = 2 "), P("/simulation/end_time", 2));
    EXPECT_EQ(parse_override("fluid_blocks.0.velocity=[1,0,0]"),
              P("/fluid_blocks/0/velocity", json::array({1, 0, 0})));
    EXPECT_EQ(parse_override("/simulation/end_time=3"), P("/simulation/end_time", 3));

    EXPECT_THROW(parse_override("simulation.end_time"), InputError);  // no '='
    EXPECT_THROW(parse_override("=3"), InputError);                   // empty path
    EXPECT_THROW(parse_override("simulation..end_time=3"), InputError);
    EXPECT_THROW(parse_override("simulation.=3"), InputError);
    EXPECT_EQ(error_of([] { parse_override("simulation.end_time=1e999"); }),
              "--set \"simulation.end_time=1e999\": the number overflows a double");
    EXPECT_EQ(error_of([] { parse_override("end_time"); }),
              "--set \"end_time\": expected path=value, e.g. simulation.stepping.mode=global");
}

TEST(SceneLoader, ParseOverrideFeedsLoad) {
    const Scene s = parse_scene(k_minimal, "m.json",
                                {parse_override("simulation.stepping.mode=constant"),
                                 parse_override("fluid.particle_radius=0.02")});
    EXPECT_EQ(s.simulation.stepping.mode, SteppingMode::Constant);
    EXPECT_DOUBLE_EQ(s.fluid.particle_radius, 0.02);
}

// ---- Physics defaults (issue 16): a WCSPH scene that sets no physics runs the continuity
// density with delta-SPH, alpha 0.01, water's nu and extrapolated walls; PCISPH and DFSPH keep
// their own density and alpha 0.1. Set keys win. ----

TEST(SceneDefaults, WcsphRunsTheContinuityDensityWithLowAlphaAndWatersViscosity) {
    const char* const text = R"({"name": "t", "fluid_blocks": [{"min": [0, 0, 0], "max": [0.1, 0.1, 0.1]}]})";
    const Scene s = parse_scene(text, "t.json");
    EXPECT_FALSE(s.fluid.density.has_value());
    EXPECT_EQ(density_form(s), DensityForm::Continuity);
    EXPECT_EQ(artificial_viscosity(s), 0.01);
    EXPECT_EQ(kinematic_viscosity(s), 1e-6);
    EXPECT_EQ(wall_pressure(s), WallPressure::Extrapolated);
    World w;
    initialise_world(w, s);
    EXPECT_TRUE(w.physics.continuity);
    EXPECT_EQ(w.physics.density_diffusion, Real(0.1));
    EXPECT_EQ(w.physics.viscosity, Real(0.01));
    EXPECT_EQ(w.physics.boundary_viscosity, Real(0.01));
    EXPECT_EQ(w.physics.kinematic_viscosity, Real(1e-6));
    EXPECT_TRUE(w.physics.extrapolated_wall_pressure);
}

TEST(SceneDefaults, SummationKeepsHesAlphaAndSetKeysWin) {
    const Scene summation = parse_scene(
        R"({"name": "t", "fluid": {"density": "summation"}, "fluid_blocks": [{"min": [0, 0, 0], "max": [0.1, 0.1, 0.1]}]})", "t.json");
    EXPECT_EQ(artificial_viscosity(summation), 0.1);
    EXPECT_EQ(kinematic_viscosity(summation), 1e-6);
    EXPECT_EQ(wall_pressure(summation), WallPressure::Mirrored);
    const Scene set = parse_scene(R"({"name": "t", "fluid": {"viscosity": 0.05, "kinematic_viscosity": 0},
                                      "fluid_blocks": [{"min": [0, 0, 0], "max": [0.1, 0.1, 0.1]}]})", "t.json");
    EXPECT_EQ(density_form(set), DensityForm::Continuity);
    EXPECT_EQ(artificial_viscosity(set), 0.05);
    EXPECT_EQ(kinematic_viscosity(set), 0.0);
    for (const char* method : {"pcisph", "dfsph"}) {
        const Scene other = parse_scene(R"({"name": "t", "fluid_blocks": [{"min": [0, 0, 0], "max": [0.1, 0.1, 0.1]}]})", "t.json",
                                        {{"/simulation/method", method}});
        EXPECT_EQ(density_form(other), DensityForm::Summation) << method;
        EXPECT_EQ(artificial_viscosity(other), 0.1) << method;
        EXPECT_EQ(kinematic_viscosity(other), 0.0) << method;
    }
}

// ---- The standing wave (scenes/standing_wave.json). ----

// Linear theory for the shipped tank, by hand: k = pi / 1 m, d = 0.5 m, omega^2 = 9.81 k tanh(k d)
// = 28.266 1/s^2, period 2 pi / omega = 1.18181 s; decay 2 nu k^2 = 2 (2e-3) pi^2 = 0.0394784 1/s.
// The velocity field: divergence-free (central differences, step 1e-4 m: truncation ~1e-8 of
// u0 k, tolerance 1e-6 of it), no flow through the walls x = 0, x = L and the floor (1e-12 m/s),
// and at the surface the vertical velocity d eta / dt = a0 omega cos(k x) of the wave's start.
TEST(StandingWaveKey, TheoryAndVelocityOfTheShippedTank) {
    const Scene s = load_scene(fs::path(SPH_SOURCE_DIR) / "scenes" / "standing_wave.json");
    ASSERT_TRUE(s.standing_wave.has_value());
    const WaveTheory th = standing_wave_theory(s);
    EXPECT_NEAR(th.period, 1.18181, 1e-5);
    EXPECT_NEAR(th.decay, 0.0394784, 1e-7);
    const double k = std::numbers::pi, omega = 2 * std::numbers::pi / th.period, a0 = 0.02;
    const double u0k = a0 * omega / std::sinh(0.5 * k) * k, e = 1e-4;
    for (const double x : {0.1, 0.37, 0.5, 0.81})
        for (const double y : {0.05, 0.25, 0.45}) {
            const Vec3d p(x, y, 0.05);
            const double div = (standing_wave_velocity(s, p + Vec3d(e, 0, 0)).x() - standing_wave_velocity(s, p - Vec3d(e, 0, 0)).x() +
                                standing_wave_velocity(s, p + Vec3d(0, e, 0)).y() - standing_wave_velocity(s, p - Vec3d(0, e, 0)).y()) / (2 * e);
            EXPECT_NEAR(div, 0.0, 1e-6 * u0k) << x << ", " << y;
            EXPECT_EQ(standing_wave_velocity(s, p).z(), 0.0);
        }
    for (const double y : {0.0, 0.2, 0.5}) {
        EXPECT_NEAR(standing_wave_velocity(s, Vec3d(0, y, 0.05)).x(), 0.0, 1e-12);
        EXPECT_NEAR(standing_wave_velocity(s, Vec3d(1, y, 0.05)).x(), 0.0, 1e-12);
    }
    for (const double x : {0.0, 0.3, 1.0}) {
        EXPECT_NEAR(standing_wave_velocity(s, Vec3d(x, 0, 0.05)).y(), 0.0, 1e-12);
        EXPECT_NEAR(standing_wave_velocity(s, Vec3d(x, 0.5, 0.05)).y(), a0 * omega * std::cos(k * x), 1e-12);
    }
}

// The wave is given between two steps when the clock reads `at`: a run that passes through
// `at` in one call lands a step on it, leaves the fluid exactly the wave's velocity there, and
// ends bit for bit where a run split at `at` by its caller ends (100 particles, 2 threads).
TEST(StandingWaveKey, GivenOnceWhenTheClockReadsAt) {
    const char* const text = R"({"name": "t", "simulation": {"stepping": {"mode": "global"}},
        "fluid": {"particle_radius": 0.01},
        "fluid_blocks": [{"min": [0, 0, 0], "max": [0.2, 0.1, 0.04]}],
        "boundaries": [{"type": "container", "min": [0, 0, 0], "max": [0.2, 0.2, 0.04]}],
        "standing_wave": {"amplitude": 0.005, "at": 0.01}})";
    const Scene s = parse_scene(text, "t.json");
    auto split = make_simulation(s);
    split->run_until(0.01);
    {
        const World& w = split->world();
        ASSERT_EQ(w.fluid.size(), 100u);
        const auto x = w.fluid.store.get(comp::position);
        const auto v = w.fluid.store.get(comp::velocity);
        for (std::size_t i = 0; i < x.size(); ++i)
            EXPECT_EQ(v[i], standing_wave_velocity(s, x[i].cast<double>()).cast<Real>()) << "particle " << i;
    }
    split->run_until(0.02);
    auto whole = make_simulation(s);
    bool landed = false;
    whole->run_until(0.02, [&](const Simulation& sm) { landed |= sm.world().clock.t_ticks == to_ticks(0.01 + 0.5 * kSecondsPerTick); });
    EXPECT_TRUE(landed);
    const auto a = split->world().fluid.store.get(comp::position);
    const auto b = whole->world().fluid.store.get(comp::position);
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) EXPECT_EQ(a[i], b[i]) << "particle " << i;
    // And not again: the velocities moved on from the field (the wave is 5 mm, gravity acts 10 ms).
    const auto v = whole->world().fluid.store.get(comp::velocity);
    const auto x = whole->world().fluid.store.get(comp::position);
    double off = 0;
    for (std::size_t i = 0; i < x.size(); ++i) off = std::max(off, (v[i].cast<double>() - standing_wave_velocity(s, x[i].cast<double>())).norm());
    EXPECT_GT(off, 1e-4);
}

// ---- Scale and names. ----

TEST(SceneLoader, ParticleRadiusDividesByTheCubeRootOfScale) {
    Scene s;
    s.fluid.particle_radius = 0.02;
    s.simulation.scale = 1.0;
    EXPECT_DOUBLE_EQ(s.particle_radius(), 0.02);
    s.simulation.scale = 8.0;  // 8x the particles: half the radius
    EXPECT_DOUBLE_EQ(s.particle_radius(), 0.01);
    s.simulation.scale = 0.125;
    EXPECT_DOUBLE_EQ(s.particle_radius(), 0.04);
    s.simulation.scale = 1000.0;
    EXPECT_NEAR(s.particle_radius(), 0.002, 1e-15);
}

TEST(SceneLoader, ScaleIsAppliedBeforeTheThinBlockCheck) {
    // 0.03 m holds one particle at radius 0.01 (spacing 0.02) but none at scale 0.125
    // (radius 0.02, spacing 0.04).
    const char* const text = R"({"name": "t", "fluid": {"particle_radius": 0.01},
                                 "fluid_blocks": [{"min": [0, 0, 0], "max": [0.5, 0.03, 0.5]}]})";
    EXPECT_NO_THROW(parse_scene(text, "t.json"));
    EXPECT_THROW(parse_scene(text, "t.json", {{"/simulation/scale", 0.125}}), SceneError);
}

TEST(SceneLoader, EnumNames) {
    EXPECT_STREQ(to_string(Method::Wcsph), "wcsph");
    EXPECT_STREQ(to_string(SteppingMode::Constant), "constant");
    EXPECT_STREQ(to_string(SteppingMode::Global), "global");
    EXPECT_STREQ(to_string(BoundaryShape::Container), "container");
    EXPECT_STREQ(to_string(BoundaryShape::Box), "box");
    EXPECT_STREQ(to_string(BoundaryShape::Sphere), "sphere");
}

}  // namespace
}  // namespace sph
