/// @file scene.cpp
/// @brief The scene schema's names and geometry helpers, and reading a scene file. Loading is
/// split along its stages: scene_text.cpp (JSON text -> document), scene_overrides.cpp
/// (--set), scene_reader.cpp (document -> validated Scene).
#include "engine/data/scene.hpp"

#include <Eigen/Geometry>

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <memory>
#include <numbers>
#include <span>
#include <string_view>
#include <system_error>
#include <tuple>
#include <utility>

#include "engine/core/errors.hpp"
#include "engine/data/scene_detail.hpp"

namespace sph {

using json = nlohmann::json;

const char* to_string(Method m) {
    switch (m) {
        case Method::Wcsph:
            return "wcsph";
        case Method::Pcisph:
            return "pcisph";
        case Method::Dfsph:
            return "dfsph";
    }
    return "unknown";
}

const char* to_string(PcisphLoop l) {
    switch (l) {
        case PcisphLoop::Fixed:
            return "fixed";
        case PcisphLoop::UntilConverged:
            return "until_converged";
    }
    return "unknown";
}

const char* to_string(BoundaryHandling b) {
    switch (b) {
        case BoundaryHandling::Ihmsen:
            return "ihmsen";
        case BoundaryHandling::DirectForcing:
            return "direct_forcing";
    }
    return "unknown";
}

const char* to_string(PressureGradient g) {
    switch (g) {
        case PressureGradient::Symmetric:
            return "symmetric";
        case PressureGradient::Corrected:
            return "corrected";
    }
    return "unknown";
}

const char* to_string(DensityForm d) {
    switch (d) {
        case DensityForm::Summation:
            return "summation";
        case DensityForm::Continuity:
            return "continuity";
    }
    return "unknown";
}

const char* to_string(WallPressure w) {
    switch (w) {
        case WallPressure::Mirrored:
            return "mirrored";
        case WallPressure::Extrapolated:
            return "extrapolated";
    }
    return "unknown";
}

const char* to_string(Activation a) {
    switch (a) {
        case Activation::Deadline:
            return "deadline";
        case Activation::Paper:
            return "paper";
    }
    return "unknown";
}

const char* to_string(SteppingMode m) {
    switch (m) {
        case SteppingMode::Constant:
            return "constant";
        case SteppingMode::Global:
            return "global";
        case SteppingMode::Individual:
            return "individual";
        case SteppingMode::Adaptive:
            return "adaptive";
        case SteppingMode::Binned:
            return "binned";
    }
    return "unknown";
}

const char* to_string(BoundaryShape s) {
    switch (s) {
        case BoundaryShape::Container:
            return "container";
        case BoundaryShape::Box:
            return "box";
        case BoundaryShape::Sphere:
            return "sphere";
        case BoundaryShape::Cylinder:
            return "cylinder";
        case BoundaryShape::Heightfield:
            return "heightfield";
        case BoundaryShape::Mesh:
            return "mesh";
    }
    return "unknown";
}

const char* to_string(FrameFormat f) {
    switch (f) {
        case FrameFormat::Vtu:
            return "vtu";
        case FrameFormat::Bgeo:
            return "bgeo";
        case FrameFormat::Ply:
            return "ply";
        case FrameFormat::Vdb:
            return "vdb";
        case FrameFormat::Mesh:
            return "mesh";
    }
    return "unknown";
}

std::vector<Vec3d> emitter_disc(const EmitterDesc& e, double spacing) {
    const Vec3d n = e.velocity.normalized();
    const Vec3d u = (std::abs(n.x()) < 0.9 ? Vec3d::UnitX() : Vec3d::UnitY()).cross(n).normalized();
    const Vec3d v = n.cross(u);
    const int k = int(std::floor(std::min(e.radius / spacing, 1e3)));
    std::vector<Vec3d> out;
    for (int j = -k; j <= k; ++j)
        for (int i = -k; i <= k; ++i)
            if (double(i * i + j * j) * spacing * spacing <= e.radius * e.radius)
                out.push_back(e.position + spacing * (i * u + j * v));
    return out;
}

Vec3d reference_point(const BoundaryDesc& b) {
    return b.shape == BoundaryShape::Sphere ? b.center : Vec3d(0.5 * (b.box.min + b.box.max));
}

BoundaryDesc translated(const BoundaryDesc& b, const Vec3d& d) {
    BoundaryDesc out = b;
    out.box.min += d;
    out.box.max += d;
    out.center += d;
    for (auto& v : out.vertices) v += d;
    for (auto& row : out.heights)  // a height field's surface is its heights: they move with it
        for (double& y : row) y += d.y();
    return out;
}

DensityForm density_form(const Scene& scene) {
    if (scene.fluid.density) return *scene.fluid.density;
    return scene.simulation.method == Method::Wcsph ? DensityForm::Continuity : DensityForm::Summation;
}

double stable_lambda_c(const Scene& scene) {
    return density_form(scene) == DensityForm::Continuity ? 0.7 : 0.8;
}

Aabb default_domain(const Scene& scene, double h) {
    Aabb box{Vec3d::Constant(std::numeric_limits<double>::max()), Vec3d::Constant(std::numeric_limits<double>::lowest())};
    auto grow = [&](const Vec3d& p) {
        box.min = box.min.cwiseMin(p);
        box.max = box.max.cwiseMax(p);
    };
    for (const auto& b : scene.boundaries) {
        // A moving boundary covers its geometry swept by its displacement up to the end time.
        Vec3d lo = Vec3d::Zero(), hi = Vec3d::Zero();
        if (b.motion) std::tie(lo, hi) = displacement_bounds(*b.motion, scene.simulation.end_time);
        if (b.shape == BoundaryShape::Sphere) {
            grow(b.center - Vec3d::Constant(b.radius) + lo);
            grow(b.center + Vec3d::Constant(b.radius) + hi);
        } else {
            grow(b.box.min + lo);
            grow(b.box.max + hi);
        }
    }
    for (const auto& f : scene.fluid_blocks) {
        grow(f.box.min);
        grow(f.box.max);
    }
    for (const auto& e : scene.emitters) {
        grow(e.position - Vec3d::Constant(e.radius));
        grow(e.position + Vec3d::Constant(e.radius));
    }
    if (box.min[0] > box.max[0]) box = Aabb{Vec3d::Zero(), Vec3d::Constant(1.0)};
    box.min -= Vec3d::Constant(h);
    box.max += Vec3d::Constant(h);
    return box;
}

double artificial_viscosity(const Scene& scene) {
    if (scene.fluid.viscosity) return *scene.fluid.viscosity;
    return density_form(scene) == DensityForm::Continuity ? 0.01 : 0.1;
}

double boundary_artificial_viscosity(const Scene& scene) {
    return scene.fluid.boundary_viscosity.value_or(artificial_viscosity(scene));
}

double kinematic_viscosity(const Scene& scene) {
    if (scene.fluid.kinematic_viscosity) return *scene.fluid.kinematic_viscosity;
    return scene.simulation.method == Method::Wcsph ? 1e-6 : 0.0;
}

WallPressure wall_pressure(const Scene& scene) {
    if (scene.fluid.wall_pressure) return *scene.fluid.wall_pressure;
    return density_form(scene) == DensityForm::Continuity ? WallPressure::Extrapolated : WallPressure::Mirrored;
}

namespace {
struct WaveShape {
    double k = 0, omega = 0, depth = 0;
    Vec3d origin = Vec3d::Zero();
};
WaveShape wave_shape(const Scene& scene) {
    const Aabb& box = scene.fluid_blocks.front().box;
    WaveShape w;
    w.k = scene.standing_wave->mode * std::numbers::pi / (box.max.x() - box.min.x());
    w.depth = box.max.y() - box.min.y();
    w.omega = std::sqrt(scene.simulation.gravity.norm() * w.k * std::tanh(w.k * w.depth));
    w.origin = box.min;
    return w;
}
}  // namespace

WaveTheory standing_wave_theory(const Scene& scene) {
    const WaveShape w = wave_shape(scene);
    return {2 * std::numbers::pi / w.omega, 2 * kinematic_viscosity(scene) * w.k * w.k};
}

Vec3d standing_wave_velocity(const Scene& scene, const Vec3d& x) {
    const WaveShape w = wave_shape(scene);
    const Vec3d p = x - w.origin;
    const double u0 = scene.standing_wave->amplitude * w.omega / std::sinh(w.k * w.depth);
    return {-u0 * std::cosh(w.k * p.y()) * std::sin(w.k * p.x()), u0 * std::sinh(w.k * p.y()) * std::cos(w.k * p.x()), 0.0};
}

bool has_moving_boundaries(const Scene& scene) {
    return std::any_of(scene.boundaries.begin(), scene.boundaries.end(),
                       [](const BoundaryDesc& b) { return b.motion.has_value(); });
}


namespace scene_detail {

double surface_area(const Aabb& box) {
    const Vec3d e = box.extent();
    return 2.0 * (e.x() * e.y() + e.y() * e.z() + e.z() * e.x());
}

/// Cells per axis as lattice_dims counts them, in double so a tiny radius cannot overflow int.
Vec3d lattice_cells(const Aabb& box, double spacing) {
    Vec3d n;
    for (int a = 0; a < 3; ++a) {
        const double cells = (box.max[a] - box.min[a]) / spacing + 1e-6;
        n[a] = cells > 0 ? std::floor(cells) : 0.0;
    }
    return n;
}

double lattice_count(const Aabb& box, double spacing) {
    const Vec3d cells = lattice_cells(box, spacing);
    if (cells.maxCoeff() < 1e9) {  // fits lattice_dims' int: use the engine's own count
        const Eigen::Vector3i n = lattice_dims(box, spacing);
        return static_cast<double>(n[0]) * n[1] * n[2];
    }
    return cells.prod();
}

}  // namespace scene_detail

SizeEstimate estimate_size(const Scene& s) {
    using namespace scene_detail;
    const double spacing = 2.0 * s.particle_radius();
    SizeEstimate e;
    double area = 0.0;
    for (const FluidBlock& b : s.fluid_blocks) e.fluid_particles += lattice_count(b.box, spacing);
    for (std::size_t k = 0; k < s.boundaries.size(); ++k) {
        const BoundaryDesc& b = s.boundaries[k];
        const double a =
            b.shape == BoundaryShape::Sphere ? 4.0 * std::numbers::pi * b.radius * b.radius : surface_area(b.box);
        area += a;
        if (a / (spacing * spacing) > e.largest_boundary_particles) {
            e.largest_boundary = k;
            e.largest_boundary_particles = a / (spacing * spacing);
        }
    }
    e.boundary_particles = area / (spacing * spacing);
    e.boundary_bytes = e.boundary_particles * 100.0;
    e.bytes = e.fluid_particles * 400.0 + e.boundary_bytes;
    return e;
}

double Scene::particle_radius() const {
    return fluid.particle_radius / std::cbrt(simulation.scale);
}


std::string read_scene_file(const std::filesystem::path& file) {
    const std::string name = file.string();
    const auto cannot = [&](int err) {
        return InputError(name + ": cannot open scene file (" +
                          std::error_code(err, std::generic_category()).message() + ")");
    };
    // Only a regular file of bounded size: a FIFO would block and /dev/zero never end.
    std::error_code ec;
    const auto st = std::filesystem::status(file, ec);
    if (!ec && std::filesystem::exists(st)) {
        if (!std::filesystem::is_regular_file(st) && !std::filesystem::is_directory(st))  // a folder: EISDIR below
            throw InputError(name + ": cannot open scene file (it is a device, pipe or socket, expected a JSON file)");
        const auto size = std::filesystem::file_size(file, ec);
        constexpr std::uintmax_t kMax = std::uintmax_t(64) << 20;
        if (!ec && size > kMax)
            throw InputError(name + ": the scene file holds " + std::to_string(size) + " bytes, more than the " +
                             std::to_string(kMax) + " a scene may have (meshes belong in their own files)");
    }
    errno = 0;
    const std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(name.c_str(), "rb"),
                                                            &std::fclose);
    if (!f) throw cannot(errno);
    std::string text;
    std::array<char, 1 << 16> buf{};
    std::size_t n = 0;
    while ((n = std::fread(buf.data(), 1, buf.size(), f.get())) > 0) text.append(buf.data(), n);
    if (std::ferror(f.get())) throw cannot(errno);  // e.g. EISDIR for a directory
    return text;
}

Scene load_scene(const std::filesystem::path& file,
                 const std::vector<std::pair<std::string, nlohmann::json>>& overrides) {
    Scene scene = parse_scene(read_scene_file(file), file.string(), overrides);
    scene.source = file;
    return scene;
}


}  // namespace sph
