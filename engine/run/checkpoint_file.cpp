// The checkpoint container (checkpoint.hpp): header, checksum, sections and the run's "meta".
// Kept apart from checkpoint.cpp, which needs the whole engine, so that tests/fuzz can fuzz
// the reader on its own.
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>

#include "engine/core/types.hpp"
#include "engine/run/checkpoint.hpp"

namespace sph {

std::uint64_t fnv1a64(std::string_view bytes) {
    std::uint64_t h = 14695981039346656037ull;
    for (const char c : bytes) {
        h ^= std::uint8_t(c);
        h *= 1099511628211ull;
    }
    return h;
}

Checkpoint read_checkpoint(const std::filesystem::path& file) {
    const std::string name = file.string();
    std::error_code ec;
    const auto st = std::filesystem::status(file, ec);
    if (ec || !std::filesystem::exists(st))
        throw CheckpointError(name + ": cannot open checkpoint file (" +
                              (ec ? ec.message() : std::string("no such file")) + ")");
    if (!std::filesystem::is_regular_file(st))
        throw CheckpointError(name + ": is not a regular file (a folder, device or pipe), expected a checkpoint "
                                     "written by sph-run --checkpoint-every");
    const std::uintmax_t size = std::filesystem::file_size(file, ec);
    if (ec) throw CheckpointError(name + ": cannot read its size (" + ec.message() + ")");
    if (size > kCheckpointMaxBytes)
        throw CheckpointError(name + ": holds " + std::to_string(size) + " bytes, more than the " +
                              std::to_string(kCheckpointMaxBytes) + " a checkpoint may have");
    std::ifstream in(file, std::ios::binary);
    if (!in) throw CheckpointError(name + ": cannot open checkpoint file (" + std::strerror(errno) + ")");
    std::string all(std::size_t(size), '\0');
    in.read(all.data(), std::streamsize(size));
    if (std::size_t(in.gcount()) != all.size())
        throw CheckpointError(name + ": could read only " + std::to_string(in.gcount()) + " of its " +
                              std::to_string(size) + " bytes");
    return parse_checkpoint(all, file);
}

Checkpoint parse_checkpoint(std::string_view all, const std::filesystem::path& file) {
    const std::string name = file.string();
    if (all.size() < kCheckpointHeaderBytes || std::memcmp(all.data(), kCheckpointMagic, sizeof kCheckpointMagic) != 0)
        throw CheckpointError(name + ": not an sph checkpoint (expected the magic \"SPHCKPT\" at the start)");
    std::uint32_t version, real_bytes;
    std::uint64_t length, checksum;
    std::memcpy(&version, all.data() + 8, 4);
    std::memcpy(&real_bytes, all.data() + 12, 4);
    std::memcpy(&length, all.data() + 16, 8);
    std::memcpy(&checksum, all.data() + 24, 8);
    if (version != kCheckpointVersion)
        throw CheckpointError(name + ": checkpoint format version " + std::to_string(version) +
                              ", expected version " + std::to_string(kCheckpointVersion) +
                              " (written by another version of sph)");
    if (real_bytes != sizeof(Real))
        throw CheckpointError(name + ": written with " + std::to_string(real_bytes) +
                              "-byte particle fields, this build uses " + std::to_string(sizeof(Real)) +
                              " (SPH_DOUBLE differs)");
    if (all.size() - kCheckpointHeaderBytes != length)
        throw CheckpointError(name + ": holds " + std::to_string(all.size() - kCheckpointHeaderBytes) +
                              " payload bytes, the header says " + std::to_string(length) + " (truncated?)");
    const std::string_view payload = all.substr(kCheckpointHeaderBytes);
    const std::uint64_t actual = fnv1a64(payload);
    if (actual != checksum) {
        char buf[96];
        std::snprintf(buf, sizeof buf, "checksum mismatch (stored %016llx, computed %016llx): the file is corrupt",
                      static_cast<unsigned long long>(checksum), static_cast<unsigned long long>(actual));
        throw CheckpointError(name + ": " + buf);
    }
    Checkpoint ck;
    ck.file = file;
    std::size_t pos = 0;
    auto take = [&](std::size_t n) {
        // n comes from the file: compare without pos + n, which a crafted length wraps round.
        if (n > payload.size() - pos) throw CheckpointError(name + ": a section runs past the end of the payload");
        const std::string_view v = payload.substr(pos, n);
        pos += n;
        return v;
    };
    while (pos < payload.size()) {
        std::uint32_t nlen;
        std::memcpy(&nlen, take(4).data(), 4);
        const std::string key(take(nlen));
        std::uint64_t dlen;
        std::memcpy(&dlen, take(8).data(), 8);
        if (dlen > payload.size()) throw CheckpointError(name + ": a section runs past the end of the payload");
        ck.sections[key] = std::string(take(std::size_t(dlen)));
    }
    for (const char* required : {"meta", "step", "fluid_neighbours", "boundary_neighbours", "active_set", "halo_set",
                                 "moving_bodies"})
        if (!ck.sections.count(required))
            throw CheckpointError(name + ": section '" + required + "' is missing");
    try {
        ck.meta = nlohmann::json::parse(ck.sections.at("meta"));
    } catch (const nlohmann::json::exception& e) {
        throw CheckpointError(name + ": section 'meta' is not JSON (" + e.what() + ")");
    }
    if (!ck.meta.is_object()) throw CheckpointError(name + ": section 'meta' is not a JSON object");
    return ck;
}

void check_run_meta(const Checkpoint& ck) {
    const nlohmann::json& m = ck.meta;
    using T = nlohmann::json::value_t;
    const auto expect = [&](const char* key, bool ok_type, const char* what) {
        const auto it = m.find(key);
        if (it == m.end())
            throw CheckpointError(ck.file.string() + ": meta key '" + key + "' is missing, expected " + what +
                                  " (a checkpoint written by sph-run has it)");
        if (!ok_type)
            throw CheckpointError(ck.file.string() + ": meta key '" + key + "' is " + it->type_name() +
                                  ", expected " + what);
    };
    const auto type_of = [&](const char* key) { return m.contains(key) ? m[key].type() : T::null; };
    const auto number = [&](const char* key) {
        const T t = type_of(key);
        return t == T::number_float || t == T::number_integer || t == T::number_unsigned;
    };
    expect("scene_file", type_of("scene_file") == T::string, "a string");
    expect("scene_text", type_of("scene_text") == T::string, "a string");
    expect("out", type_of("out") == T::string, "a string");
    expect("checkpoint_every", number("checkpoint_every"), "a number");
    expect("t", number("t"), "a number");
    expect("step", type_of("step") == T::number_integer || type_of("step") == T::number_unsigned, "an integer");
    expect("recorder", type_of("recorder") == T::object, "an object");
    expect("overrides", type_of("overrides") == T::array, "an array");
    for (const auto& o : m["overrides"])
        if (!o.is_array() || o.size() != 2 || !o[0].is_string())
            throw CheckpointError(ck.file.string() + ": meta key 'overrides' holds " + o.dump().substr(0, 80) +
                                  ", expected [\"/json/path\", value] pairs");
    if (m.contains("run_id") && !m["run_id"].is_string())
        throw CheckpointError(ck.file.string() + ": meta key 'run_id' is " + std::string(m["run_id"].type_name()) +
                              ", expected a string");
}

}  // namespace sph
