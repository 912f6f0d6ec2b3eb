#pragma once
/// @file probe_desc.hpp
/// @brief What a scene asks to measure while it runs (scene key `probes`): each probe is sampled
/// at its own rate and written as a CSV series `probes/<name>.csv` (engine/probes.hpp).
/// Format, units and columns: scenes/README.md, section `probes`.
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "engine/core/types.hpp"

namespace sph {

enum class ProbeType { Pressure, Height, Front, Fluid };
/// @brief How a pressure probe reads the pressure: interpolated from the fluid at the point,
/// averaged over the boundary particles within `radius` of a wall point, or as a wall sensor of
/// face `diameter` reads: the wall pressure averaged over the disc of the face (normal `normal`),
/// its dry part counting as 0 (gauge).
enum class PressureSource { Fluid, Boundary, Sensor };
/// @brief How a front probe finds the front: the farthest fluid particle with at least
/// `min_neighbours` neighbours, or the 0.5 level of the colour function along a line.
enum class FrontMethod { Neighbours, Colour };
/// @brief How a height probe reads the water height along its line: the top of the continuous
/// column that starts at `from` (the first dry stretch of at least one spacing ends it, so
/// droplets and spray above do not count), or the highest wet point anywhere on the line.
enum class HeightMethod { Column, Highest };

/// @brief The scene file's word for each (the loader reads them, scene_to_json writes them).
const char* to_string(ProbeType t);
const char* to_string(PressureSource s);
const char* to_string(FrontMethod m);
const char* to_string(HeightMethod m);

/// @brief Where a probe's series can be compared with measured data (read by tools/sph_study.py
/// and the validation tests, ignored by the engine): the file's (T, Z) columns against the
/// probe's primary column scaled as T = t * t_scale, Z = (value - value_offset) * value_scale.
struct ProbeExperiment {
    std::string file;          ///< CSV path, relative to the scene file's folder
    double t_scale = 1.0;      ///< 1/s
    double value_scale = 1.0;  ///< 1/unit of the probe value
    double value_offset = 0.0; ///< unit of the probe value
    double max_shift = 0.0;    ///< largest constant time shift |dT| allowed (dimensionless)
    double t_min = -1e300, t_max = 1e300;  ///< compared range of T (dimensionless)
    bool operator==(const ProbeExperiment&) const = default;
};

struct ProbeDesc {
    ProbeType type = ProbeType::Fluid;
    std::string name;          ///< file name stem; default "<type>_<index>"
    double rate = 100.0;       ///< samples per simulated second
    // pressure
    PressureSource source = PressureSource::Fluid;
    Vec3d point{0, 0, 0};      ///< m
    double radius = 0.0;       ///< m, boundary source; default 2 particle spacings (0 = default)
    double diameter = 0.0;     ///< m, sensor source: the face's diameter
    Vec3d normal{0, 0, 0};     ///< sensor source: unit normal of the wall at the face
    // height, front (colour)
    Vec3d from{0, 0, 0}, to{0, 0, 0};  ///< m: the line, from its start to its end
    // height
    HeightMethod height_method = HeightMethod::Column;
    // front
    FrontMethod method = FrontMethod::Neighbours;
    Vec3d direction{1, 0, 0};  ///< unit; the front is the largest projection on it
    int min_neighbours = 4;
    std::optional<ProbeExperiment> experiment;
    bool operator==(const ProbeDesc&) const = default;
};

/// @brief Reads and validates the `probes` array; throws SceneError (file, JSON path, value
/// found, what was expected), like the rest of the scene loader.
std::vector<ProbeDesc> parse_probes(const nlohmann::json& value, const std::string& file,
                                    const std::string& path = "/probes");

}  // namespace sph
