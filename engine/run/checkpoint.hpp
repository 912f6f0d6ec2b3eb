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
/// "moving_bodies"; with a recipe that keeps a rollback ring (PCISPH `adaptive`), each state it
/// holds, oldest first, as "ring/<k>/clock" (JSON, the end time as a bit pattern),
/// "ring/<k>/fluid/<column>", "ring/<k>/boundary/<column>" and "ring/<k>/resource/<name>" (since
/// 2026-12-07; a reader before it ignores them, and one after it reads a checkpoint without them
/// as before: the ring starts empty).
#include <filesystem>
#include <cstdint>
#include <map>
#include <string_view>
#include <string>

#include <nlohmann/json.hpp>

#include "engine/core/errors.hpp"

namespace sph {

class Simulation;

inline constexpr std::uint32_t kCheckpointVersion = 2;
inline constexpr char kCheckpointMagic[8] = {'S', 'P', 'H', 'C', 'K', 'P', 'T', '\0'};
inline constexpr std::size_t kCheckpointHeaderBytes = 8 + 4 + 4 + 8 + 8;
/// A checkpoint larger than this is refused before it is read (the largest a 24 GiB machine
/// could write is far smaller; a device such as /dev/zero never ends).
inline constexpr std::uintmax_t kCheckpointMaxBytes = std::uintmax_t(64) << 30;

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
/// is wrong with it (also when the path is not a regular file or is larger than
/// kCheckpointMaxBytes).
Checkpoint read_checkpoint(const std::filesystem::path& file);

/// @brief read_checkpoint on bytes already in memory; `name` is the file named in errors.
Checkpoint parse_checkpoint(std::string_view bytes, const std::filesystem::path& name);

/// @brief Checks the "meta" keys sph-run writes and reads back (scene_file, scene_text,
/// overrides, out, checkpoint_every, step, t, recorder, run_id) for presence and type. Throws
/// CheckpointError naming the file and the key.
void check_run_meta(const Checkpoint& checkpoint);

/// @brief Overwrites the state of `sim` (built from the same scene) with the checkpoint's.
/// Throws CheckpointError when the columns or the boundary sampling differ.
void restore_checkpoint(Simulation& sim, const Checkpoint& checkpoint);

/// @brief FNV-1a, 64 bit, of a byte string (the checkpoint's checksum).
std::uint64_t fnv1a64(std::string_view bytes);

}  // namespace sph
