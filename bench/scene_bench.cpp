// What checking a scene costs beside loading it: load_scene (read and validate a file) against
// validate_scene (scene_to_json read back through the loader, what make_recipe adds for every
// scene), on the default scene and on the largest mesh scene (glass.json: the OBJ written inline).
#include <benchmark/benchmark.h>

#include <string>

#include "engine/data/scene.hpp"

using namespace sph;

namespace {
const char* const kScenes[] = {"dam_break", "glass"};
std::string scene_file(benchmark::State& state) {
    const char* name = kScenes[state.range(0)];
    state.SetLabel(name);
    return std::string(SPH_SOURCE_DIR "/scenes/") + name + ".json";
}
}  // namespace

static void BM_Scene_load(benchmark::State& state) {
    const std::string file = scene_file(state);
    for (auto _ : state) benchmark::DoNotOptimize(load_scene(file));
}
BENCHMARK(BM_Scene_load)->DenseRange(0, 1)->ArgName("scene")->Unit(benchmark::kMicrosecond);

static void BM_Scene_validate(benchmark::State& state) {
    const Scene scene = load_scene(scene_file(state));
    for (auto _ : state) validate_scene(scene);
}
BENCHMARK(BM_Scene_validate)->DenseRange(0, 1)->ArgName("scene")->Unit(benchmark::kMicrosecond);
