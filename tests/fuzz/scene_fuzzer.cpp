// libFuzzer target for the scene loader (built with clang by tools/fuzz.sh, not by CMake).
// Contract under test: any byte string either parses into a Scene or throws sph::InputError;
// anything else (a crash, a sanitizer report, another exception, a hang) is a bug.
#include <cstddef>
#include <cstdint>
#include <string>

#include "engine/core/errors.hpp"
#include "engine/data/scene.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    try {
        const sph::Scene s = sph::parse_scene(text, "fuzz.json");
        (void)s.particle_radius();
    } catch (const sph::InputError&) {
        // the expected outcome for malformed input
    }
    return 0;
}
