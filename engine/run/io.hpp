#pragma once
/// @file io.hpp
/// @brief Output files. Every file is written to a temporary name beside it and renamed, so
/// a killed run leaves only complete files.
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace sph {

struct World;

/// @brief A file written under no name, or a temporary one, and renamed onto its target by
/// commit(): readers (and a killed run) only ever see the old complete file or the new one.
/// On Linux the data goes into an unnamed O_TMPFILE in the target's directory, which the
/// kernel discards if the process dies before commit(); the name appears with linkat(2) under
/// a temporary name that rename(2) moves onto the target at once. Elsewhere (a filesystem
/// without O_TMPFILE) a named temporary "<file>.tmp<pid>.<n>" is written and renamed.
class AtomicFile {
public:
    explicit AtomicFile(std::filesystem::path target);
    ~AtomicFile();  ///< without commit(): the data is discarded
    AtomicFile(const AtomicFile&) = delete;
    AtomicFile& operator=(const AtomicFile&) = delete;
    void write(std::string_view bytes);
    /// @brief Appends the first `bytes` bytes of an existing file (e.g. the committed prefix
    /// of the target itself); throws InputError if it holds fewer.
    void copy_prefix(const std::filesystem::path& from, std::uint64_t bytes);
    void commit();

private:
    std::filesystem::path m_target, m_named_tmp;
    int m_fd = -1;
    bool m_unnamed = false;
};

/// @brief A short hidden name beside `target` (".sph.tmp<pid>.<n>"), unique in this process,
/// whatever the target's length (a name near the file system's 255-byte limit plus a suffix
/// would not fit), for writers that must name their temporary file (then rename it).
std::filesystem::path temporary_name(const std::filesystem::path& target);

/// @brief Writes `content` to `file` atomically (an AtomicFile; no fsync).
void write_file_atomic(const std::filesystem::path& file, std::string_view content);

/// @brief The point attributes a frame holds, from the scene's `output.attributes`: exactly
/// those when the scene lists them; otherwise the default list plus `dt` and `active` when the
/// method has those columns (individual stepping). Position and id are always written.
std::vector<std::string> frame_attributes(const World& world);

/// @brief Writes the fluid particles as a VTK UnstructuredGrid (.vtu), binary appended raw
/// data, for ParaView: `position` as the points, then the given attributes (any of velocity,
/// density, pressure, acceleration as stored; `dt` as Float64 seconds; `active` as UInt8),
/// then `id`. Field data `TimeValue` holds the simulated time at full precision. Attributes
/// the store does not hold are skipped.
void write_vtu(const std::filesystem::path& file, const World& world,
               const std::vector<std::string>& attributes);

/// @brief Writes the same arrays as a Houdini classic BGEO (version 5, uncompressed, the
/// format partio reads): P, then `v` (velocity), `accel`, density, pressure, dt (float32),
/// active and id (int32).
void write_bgeo(const std::filesystem::path& file, const World& world,
                const std::vector<std::string>& attributes);

/// @brief Writes the same arrays as binary little-endian PLY (one vertex element), for
/// Blender: x y z, vectors as <name>_x/_y/_z, scalars as <name>.
void write_ply(const std::filesystem::path& file, const World& world,
               const std::vector<std::string>& attributes);

/// @brief Writes `stem`.vtu / .bgeo / .ply, one per format of the scene's `output.formats`,
/// with frame_attributes(world).
void write_frame(const std::filesystem::path& stem, const World& world);

/// @brief Writes boundary particles [begin, end) as `stem`.vtu / .bgeo / .ply (the scene's
/// particle formats; .ply when it has only surface formats): position, normal and (moving bodies) velocity, and `id` = the boundary row, so a
/// render shows the tank, the obstacles and the paddle beside the fluid; `t` is the time the
/// files carry.
void write_boundary(const std::filesystem::path& stem, const World& world, std::size_t begin, std::size_t end,
                    double t);

/// @brief Peak resident memory of this process in bytes (getrusage).
std::size_t peak_memory_bytes();

}  // namespace sph
