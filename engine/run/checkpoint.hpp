#pragma once
/// @file checkpoint.hpp
/// @brief Checkpoints: the complete state of a run (every particle column of both sets, the
/// neighbour lists, the step scalars, the moving bodies) plus caller data (the scene text,
/// the outputs' state), so that a resumed run continues bit for bit.
///
/// File format, version 2 (all integers little-endian):
///   8 bytes  magic "SPHCKPT\0"
///   u32      format version (2; version 1 stored the step state as raw bytes and is refused)
///   u32      bytes of a particle field value (4: float build, 8: SPH_DOUBLE build)
///   u64      payload length in bytes
///   u64      FNV-1a 64 hash of the payload
///   payload  sections, each: u32 name length, name, u64 data length, data
/// Sections: "meta" (JSON text from the caller), "step" (JSON: clock, step size, statistics,
/// rollback and counters by name, doubles as bit patterns), "resource/<name>" (each Kept
/// resource a system owns, as its bytes), "fluid/<column>" and
/// "boundary/<column>" (u32 element size, then the raw column), "fluid_neighbours" and
/// "boundary_neighbours" (capacity, counts, entries), "active_set", "halo_set",
/// "moving_bodies".
#include <filesystem>
#include <map>
#include <string>

#include <nlohmann/json.hpp>

#include "engine/core/errors.hpp"

namespace sph {

class Simulation;

inline constexpr std::uint32_t kCheckpointVersion = 2;

/// @brief A checkpoint file that cannot be used: missing, truncated, corrupt (checksum),
/// another format version or precision, or not matching the scene. Bad input: exit code 2.
class CheckpointError : public InputError {
public:
    using InputError::InputError;
};

/// @brief A checkpoint read back and verified (magic, version, precision, length, checksum).
struct Checkpoint {
    std::filesystem::path file;
    nlohmann::json meta;
    std::map<std::string, std::string> sections;
};

/// @brief Writes the simulation's state and `meta` atomically to `file`.
void write_checkpoint(const std::filesystem::path& file, const Simulation& sim, const nlohmann::json& meta);

/// @brief Reads and verifies a checkpoint. Throws CheckpointError naming the file and what
/// is wrong with it.
Checkpoint read_checkpoint(const std::filesystem::path& file);

/// @brief Overwrites the state of `sim` (built from the same scene) with the checkpoint's.
/// Throws CheckpointError when the columns or the boundary sampling differ.
void restore_checkpoint(Simulation& sim, const Checkpoint& checkpoint);

/// @brief FNV-1a, 64 bit, of a byte string (the checkpoint's checksum).
std::uint64_t fnv1a64(std::string_view bytes);

}  // namespace sph
