#pragma once
/// @file io.hpp
/// @brief Output files. Every file is written to a temporary name beside it and renamed, so
/// a killed run leaves only complete files.
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace sph {

struct World;

/// @brief Writes `content` to `file` atomically (temporary file, fsync-free rename).
void write_file_atomic(const std::filesystem::path& file, std::string_view content);

/// @brief Writes the fluid particles as a VTK UnstructuredGrid (.vtu), binary appended raw
/// data, with the given point attributes (columns of the fluid store) for ParaView, then
/// `dt` (Float64, s) and `active` (UInt8) when the store has them (individual stepping),
/// then `id`. Field data `TimeValue` holds the simulated time at full precision.
void write_vtu(const std::filesystem::path& file, const World& world,
               const std::vector<std::string>& attributes);

/// @brief Peak resident memory of this process in bytes (getrusage).
std::size_t peak_memory_bytes();

}  // namespace sph
