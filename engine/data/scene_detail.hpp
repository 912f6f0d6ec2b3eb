#pragma once
/// @file scene_detail.hpp
/// @brief Internal to the scene loader (scene*.cpp): the key vocabulary of every section, the
/// string helpers its messages are made of, JSON text -> document and command-line overrides.
/// Not installed API.
#include <array>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "engine/data/scene.hpp"

namespace sph::scene_detail {

using json = nlohmann::json;

// ---- Vocabulary: keys per section (in the order they are listed in messages) and names. ----

inline constexpr std::array<const char*, 14> k_top_keys{"name",  "description",  "simulation", "domain",
                                                 "fluid", "fluid_blocks", "boundaries", "output",
                                                 "pcisph", "dfsph", "boundary", "emitters", "probes",
                                                 "standing_wave"};
inline constexpr std::array<const char*, 3> k_wave_keys{"amplitude", "mode", "at"};
inline constexpr std::array<const char*, 7> k_emitter_keys{"position", "velocity", "radius", "rate", "start", "end",
                                                    "max_particles"};
inline constexpr std::array<const char*, 6> k_pcisph_keys{"iterations", "max_iterations", "loop",
                                                   "eta",        "eta_max",        "delta_shock"};
inline constexpr std::array<const char*, 10> k_dfsph_keys{
    "eta", "eta_divergence", "min_iterations", "max_iterations", "min_divergence_iterations",
    "max_divergence_iterations", "divergence", "warm_start", "relaxation", "cfl"};
inline constexpr std::array<const char*, 2> k_boundary_params_keys{"handling", "friction"};
inline constexpr std::array<const char*, 8> k_simulation_keys{
    "method", "stepping", "end_time", "frame_rate", "scale", "gravity", "sort_interval", "simd"};
inline constexpr std::array<const char*, 10> k_stepping_keys{"mode",     "dt",       "lambda_v", "lambda_f", "acoustic",
                                                      "lambda_c", "dt_max",   "dt_min",   "activation", "keep_grid"};
inline constexpr std::array<const char*, 13> k_fluid_keys{
    "rest_density",      "particle_radius", "viscosity", "speed_of_sound",    "density_fluctuation", "surface_tension",
    "boundary_viscosity", "pressure_gradient", "support", "density",           "density_diffusion",
    "kinematic_viscosity", "wall_pressure"};
inline constexpr std::array<const char*, 2> k_box_keys{"min", "max"};
inline constexpr std::array<const char*, 4> k_block_keys{"min", "max", "velocity", "hydrostatic"};
inline constexpr std::array<const char*, 4> k_boxlike_boundary_keys{"type", "min", "max", "motion"};
inline constexpr std::array<const char*, 4> k_sphere_boundary_keys{"type", "center", "radius", "motion"};
inline constexpr std::array<const char*, 6> k_cylinder_boundary_keys{"type", "center", "axis", "radius", "height", "motion"};
inline constexpr std::array<const char*, 4> k_heightfield_boundary_keys{"type", "min", "max", "heights"};
inline constexpr std::array<const char*, 6> k_mesh_boundary_keys{"type", "file", "vertices", "triangles", "scale", "translate"};
inline constexpr std::array<const char*, 2> k_linear_motion_keys{"type", "velocity"};
inline constexpr std::array<const char*, 5> k_sinusoidal_motion_keys{"type", "axis", "amplitude", "period",
                                                              "phase"};
inline constexpr std::array<const char*, 4> k_path_motion_keys{"type", "points", "speed", "loop"};
inline constexpr std::array<const char*, 5> k_circle_motion_keys{"type", "center", "radius", "axis",
                                                          "speed"};
inline constexpr std::array<const char*, 3> k_output_keys{"format", "attributes", "surface"};
inline constexpr std::array<const char*, 4> k_surface_keys{"voxel_size", "sphere_radius", "smoothing", "keep_volume"};

inline constexpr const char* k_name_expected =
    "a non-empty string other than \".\" and \"..\", without \"/\" or \"\\\" (it names the output folder)";

inline constexpr std::array<Method, 3> k_methods{Method::Wcsph, Method::Pcisph, Method::Dfsph};
inline constexpr std::array<SteppingMode, 5> k_modes{SteppingMode::Constant, SteppingMode::Global,
                                              SteppingMode::Individual, SteppingMode::Binned,
                                              SteppingMode::Adaptive};
inline constexpr std::array<PcisphLoop, 2> k_loops{PcisphLoop::Fixed, PcisphLoop::UntilConverged};
inline constexpr std::array<BoundaryHandling, 2> k_handlings{BoundaryHandling::Ihmsen,
                                                      BoundaryHandling::DirectForcing};
inline constexpr std::array<PressureGradient, 2> k_gradients{PressureGradient::Symmetric, PressureGradient::Corrected};
inline constexpr std::array<DensityForm, 2> k_density_forms{DensityForm::Summation, DensityForm::Continuity};
inline constexpr std::array<WallPressure, 2> k_wall_pressures{WallPressure::Mirrored, WallPressure::Extrapolated};
inline constexpr std::array<Activation, 2> k_activations{Activation::Deadline, Activation::Paper};
inline constexpr std::array<BoundaryShape, 6> k_shapes{BoundaryShape::Container, BoundaryShape::Box,
                                                BoundaryShape::Sphere,    BoundaryShape::Cylinder,
                                                BoundaryShape::Heightfield, BoundaryShape::Mesh};
inline constexpr std::array<MotionType, 4> k_motion_types{MotionType::Linear, MotionType::Sinusoidal,
                                                  MotionType::Path, MotionType::Circle};
inline constexpr std::array<FrameFormat, 5> k_formats{FrameFormat::Vtu, FrameFormat::Bgeo, FrameFormat::Ply,
                                                      FrameFormat::Vdb, FrameFormat::Mesh};
inline constexpr std::array<const char*, 8> k_attributes{"position", "velocity", "density", "pressure",
                                                  "acceleration", "dt",       "active",  "bin"};


// ---- Geometry of the schema (scene.cpp). ----
double surface_area(const Aabb& box);
/// Cells per axis as lattice_dims counts them, in double so a tiny radius cannot overflow int.
Vec3d lattice_cells(const Aabb& box, double spacing);
double lattice_count(const Aabb& box, double spacing);

// ---- Small string helpers (scene_text.cpp). ----
std::string escape_token(std::string_view key);
std::string child(const std::string& path, std::string_view key);
std::string child(const std::string& path, std::size_t index);
std::string shown(const std::string& path);
std::string truncate(std::string s, std::size_t max_chars = 80);
std::string dump(const json& v);
std::string in_quotes(std::string_view s);
std::string fmt_num(double x);
std::string fmt_computed(double x);
std::string fmt_vec(const Vec3d& v);
std::string fmt_vec_computed(const Vec3d& v);
std::string fmt_large(double x, int decimals);
std::string join(std::span<const char* const> names, bool quote);
std::string lower(std::string_view s);
std::size_t edit_distance(std::string_view a_in, std::string_view b_in);
std::string suggestion(std::string_view found, std::span<const char* const> names);
std::pair<std::size_t, std::size_t> line_column(const std::string& text, std::size_t offset);
bool is_word_char(char c);
std::size_t token_start(const std::string& text, std::size_t last);
std::string syntax_reason(const std::string& text, std::size_t& offset, const std::string& what);
json parse_document(const std::string& text, const std::string& file);
std::vector<std::string> pointer_tokens(const std::string& pointer, const std::string& file);
std::string apply_override(json& doc, const std::vector<std::string>& tokens, const json& value,
                           const std::string& file);

}  // namespace sph::scene_detail
