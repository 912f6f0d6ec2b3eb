// libFuzzer target for the checkpoint reader (built with clang by tools/fuzz.sh, not by CMake):
// the container (header, checksum, sections) and the run's "meta" keys sph-run reads back.
// Contract under test: any byte string either parses or throws sph::InputError (a
// CheckpointError naming the file); anything else (a crash, a sanitizer report, another
// exception, a hang such as a section length that wraps) is a bug. The fuzzer accepts inputs
// whose checksum is wrong only at the checksum test, so it also feeds each input with its
// checksum recomputed, to reach the sections and the meta checks.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>

#include "engine/core/errors.hpp"
#include "engine/run/checkpoint.hpp"

namespace {
void parse(const std::string& bytes) {
    try {
        const sph::Checkpoint ck = sph::parse_checkpoint(bytes, "fuzz.sphckpt");
        sph::check_run_meta(ck);
    } catch (const sph::InputError&) {
        // the expected outcome for malformed input
    }
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    std::string bytes(reinterpret_cast<const char*>(data), size);
    parse(bytes);
    if (bytes.size() >= sph::kCheckpointHeaderBytes) {
        const std::uint64_t length = bytes.size() - sph::kCheckpointHeaderBytes;
        const std::uint64_t sum = sph::fnv1a64(std::string_view(bytes).substr(sph::kCheckpointHeaderBytes));
        std::memcpy(bytes.data() + 16, &length, 8);
        std::memcpy(bytes.data() + 24, &sum, 8);
        parse(bytes);
    }
    return 0;
}
