#pragma once
/// @file scene.hpp
/// @brief A validated scene: what to simulate, how, and what to write. Loaded from strict JSON
/// (see scenes/README.md for the format, with units) or built in code.
#include <algorithm>
#include <array>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "engine/data/motion.hpp"
#include "engine/data/probe_desc.hpp"
#include "engine/core/types.hpp"

namespace sph {

enum class Method { Wcsph, Pcisph, Dfsph };
/// `constant` for every method; `global`, `individual` and `binned` are WCSPH modes; `adaptive`
/// is the PCISPH mode of Ihmsen et al. 2010 (eq. 16-27) and DFSPH's CFL step (Bender & Koschier
/// 2017 eq. 20). `binned` is per-particle stepping on
/// power-of-two bins with a neighbour limiter and wake-up (engine/core/timeline.hpp,
/// systems/timestep/binned_step_system.hpp); `individual` is He et al.'s Alg. 2 (with
/// `activation: paper` as published; the default `deadline` changes lines 2 and 17, docs/methods.md).
enum class SteppingMode { Constant, Global, Individual, Adaptive, Binned };
/// PCISPH iteration rule: `fixed` runs exactly `iterations` (Ihmsen 2010: three);
/// `until_converged` is Solenthaler & Pajarola's loop: while max rho_err > eta or k < iterations,
/// at most `max_iterations`.
enum class PcisphLoop { Fixed, UntilConverged };
/// Ihmsen 2010 sec. 3.2 (boundary density and pressure, eq. 13, plus direct forcing eq. 9-12),
/// or `direct_forcing` alone (Ihmsen eq. 9-12 without boundary density or pressure: the comparison
/// of the paper's sec. 4.1 with Becker, Teschner & Tessendorf 2009).
enum class BoundaryHandling { Ihmsen, DirectForcing };
/// WCSPH pressure force: `symmetric` is He et al. eq. 4; `corrected` multiplies each pair's
/// kernel gradient by the symmetrised correction (L_i + L_j) / 2 of Bonet & Lok 1999, which
/// makes the force first-order consistent while keeping it antisymmetric (momentum conserved)
/// and repulsive (systems/forces/gradient_correction_system.hpp).
enum class PressureGradient { Symmetric, Corrected };
/// WCSPH density: `summation` is He et al. eq. 1 (rho_i = sum_j m_j W_ij, recomputed at every
/// evaluation); `continuity` integrates drho_i/dt = sum_j m_j v_ij . grad W_ij (He eq. 5) plus
/// the delta-SPH density diffusion (fluid.density_diffusion; Molteni & Colagrossi 2009 with the
/// hydrostatic correction of Fourtakas et al. 2019), starting from the summation density.
enum class DensityForm { Summation, Continuity };
/// WCSPH: the pressure a boundary particle b exerts on a fluid neighbour i, in
/// a_i -= sum_b psi_b (p_i / rho_i^2 + p_b / rho_b^2) grad W_ib. `mirrored`: p_b = p_i and
/// rho_b = rho_i (Akinci et al. 2012 with He et al.'s pressure mirroring), the force 2 p_i / rho_i^2;
/// `extrapolated`: p_b from the fluid around b with the hydrostatic term (Adami, Hu & Adams 2012,
/// eq. 27), rho_b from the equation of state (systems/boundary/wall_pressure_system.hpp).
enum class WallPressure { Mirrored, Extrapolated };
/// When `individual` evaluates a particle whose deadline t_last + Delta t_i is near (the rule
/// behind He et al. Alg. 2 line 2). `deadline`: at the last step that starts before the
/// deadline, and no step is longer than the earliest deadline it would carry an inactive
/// particle past; so no particle holds its force for longer than its Delta t_i. `paper`: at the
/// first step that starts at or after the deadline (He: t_last + Delta t_i < t_sim, tie counted
/// as active); a particle then holds its force for up to Delta t_i + Delta t_sim, almost twice
/// its step when the two are close. systems/active/select_active_system.hpp.
enum class Activation { Deadline, Paper };

/// @brief Names as written in scene files and on the command line.
const char* to_string(Method m);
const char* to_string(SteppingMode m);
const char* to_string(PcisphLoop l);
const char* to_string(BoundaryHandling b);
const char* to_string(PressureGradient g);
const char* to_string(DensityForm d);
const char* to_string(WallPressure w);
const char* to_string(Activation a);
/// @brief Every method and every stepping mode the loader knows, by name (sph-run --list-modes;
/// the study tool runs each pair a scene accepts, so a new mode joins it with no new code).
std::vector<std::string> method_names();
std::vector<std::string> stepping_mode_names();

/// @brief Time-step control (He et al. eq. 6-8 for `global`; eq. 9 and Alg. 2 for
/// `individual`, whose defaults are lambda_v 0.05, lambda_f 0.025 and no acoustic condition).
struct SteppingParams {
    SteppingMode mode = SteppingMode::Global;
    double dt = 4e-4;          ///< s; the step of `constant` (`global` computes every step, the first too).
    double lambda_v = 0.1;     ///< He eq. 6 CFL coefficient.
    double lambda_f = 0.05;    ///< He eq. 7 force coefficient.
    bool acoustic = true;      ///< Also apply dt <= lambda_c h / (c_s + v_max).
    double lambda_c = 0.4;     ///< Acoustic (sound-speed CFL) coefficient.
    double dt_max = 5e-3;      ///< s; upper bound on any step.
    double dt_min = 1e-7;      ///< s; a step below this stops the run with a diagnosis.
    Activation activation = Activation::Deadline;  ///< `individual` only (see Activation).
    /// `binned` only: keep the fluid grid on steps with few due rows while no row can have moved
    /// far (FluidGridSystem); false builds it every step. The results are the same bit for bit.
    bool keep_grid = true;
    bool operator==(const SteppingParams&) const = default;
};

/// @brief PCISPH (Solenthaler & Pajarola 2009; Ihmsen et al. 2010 Alg. 2) and its adaptive step.
/// Densities are relative: eta = 0.01 is a 1 % density error (the paper's eta_avg%).
struct PcisphParams {
    int iterations = 3;          ///< fixed: iterations per step; until_converged: the minimum
    int max_iterations = 50;     ///< until_converged: upper bound
    PcisphLoop loop = PcisphLoop::Fixed;
    double eta = 0.01;           ///< eta_avg: target average compression (fraction of rho0)
    std::optional<double> eta_max;       ///< default 10 eta (Ihmsen sec. 3.3)
    std::optional<double> delta_shock;   ///< eq. 25 threshold; default 4 eta, within (eta, eta_max)
    bool operator==(const PcisphParams&) const = default;
};

/// @brief Divergence-free SPH (Bender & Koschier 2015, 2017): the density solver's target
/// `eta` (average compression, fraction of rho0) and the divergence solver's `eta_divergence`
/// (average rate of compression times dt, the same unit), the iteration bounds, warm starts and
/// the CFL factor of the adaptive step, dt = cfl 2 r / v_max (their eq. 20, d = 2 r).
struct DfsphParams {
    double eta = 0.0005;             ///< density solver: stop when avg max(rho*/rho0 - 1, 0) <= eta
    double eta_divergence = 0.001;   ///< divergence solver: stop when dt avg max(Drho/Dt, 0)/rho0 <= this
    int min_iterations = 2;          ///< density solver passes at least (Bender & Koschier: 2)
    int max_iterations = 100;
    int min_divergence_iterations = 1;
    int max_divergence_iterations = 100;
    bool divergence = true;          ///< run the divergence solver
    bool warm_start = true;          ///< start each solver from half the previous step's stiffness
    /// Over-relaxation omega of the density solver's Jacobi update (1: Bender & Koschier's);
    /// 1.5 cuts its passes by a third to a half at the same error (docs/results/dfsph.md).
    double relaxation = 1.5;
    double cfl = 0.4;                ///< adaptive: dt = cfl 2 r / v_max, at most stepping.dt_max
    bool operator==(const DfsphParams&) const = default;
};

/// @brief Boundary handling of PCISPH (`boundary` section of a scene).
struct BoundaryParams {
    BoundaryHandling handling = BoundaryHandling::Ihmsen;
    double friction = 1.0;  ///< epsilon of Ihmsen eq. 12: 1 keeps the tangential velocity (free slip)
    bool operator==(const BoundaryParams&) const = default;
};

struct SimulationParams {
    Method method = Method::Wcsph;
    SteppingParams stepping;
    double end_time = 1.0;       ///< s, simulated.
    double frame_rate = 30.0;    ///< frames per simulated second; 0 writes no frames.
    double scale = 1.0;          ///< particle-count multiplier: radius /= cbrt(scale).
    Vec3d gravity{0.0, -9.81, 0.0};  ///< m/s^2
    /// Steps between z-order re-sorts of the particle columns; in binned and individual
    /// stepping, whose steps evaluate part of the rows, the rows that many whole-fluid steps evaluate
    /// (sort_interval x fluid rows, counted by Clock::rows_since_sort).
    int sort_interval = 16;
    /// Vectorised pair loops (neighbour filter, density, forces) at the widest instruction set
    /// the CPU has (runtime dispatch: AVX-512, AVX2, else portable); false runs the scalar
    /// reference loops. Float builds only: with SPH_DOUBLE the scalar loops always run.
    bool simd = true;
    bool operator==(const SimulationParams&) const = default;
};

struct FluidParams {
    double rest_density = 1000.0;     ///< kg/m^3
    double particle_radius = 0.01;    ///< m, before `scale`; spacing is 2 r, support h = support * 2 r.
    /// Kernel support radius h in particle spacings (default 2: h = 4 r, Ihmsen et al.'s r0 = h / 2; He
/// et al. state no ratio). A larger
    /// support lowers the kernel-sum error at a cost of about support^3 neighbours per particle.
    double support = 2.0;
    /// Monaghan artificial viscosity alpha (dimensionless). Unset: artificial_viscosity(scene),
    /// 0.01 with the continuity density (stable with delta-SPH, docs/methods.md), else 0.1.
    std::optional<double> viscosity;
    std::optional<double> speed_of_sound;  ///< m/s; default from density_fluctuation.
    double density_fluctuation = 0.01;     ///< target |rho/rho0 - 1| for the default c_s.
    /// Becker & Teschner 2007 eq. 13 cohesion coefficient kappa (m^3/s^2):
    /// a_i = -kappa sum_j (m_j/m_i) x_ij W_ij. 0: no surface-tension system (PCISPH and DFSPH).
    double surface_tension = 0.0;
    /// Monaghan alpha between fluid and boundary particles (default: `viscosity`); 0 makes every
    /// wall free-slip (it then exerts only its Akinci pressure force, normal to it).
    std::optional<double> boundary_viscosity;
    /// WCSPH only: `corrected` for hydrostatic accuracy (docs/results/validation.md), at the cost of one
    /// more pass over the neighbours per step.
    PressureGradient pressure_gradient = PressureGradient::Symmetric;
    /// WCSPH only: how the density evolves (DensityForm). Unset: density_form(scene), `continuity`
    /// for WCSPH, `summation` (their own solvers' density) for PCISPH and DFSPH.
    std::optional<DensityForm> density;
    /// delta of the delta-SPH diffusion term with `density: continuity` (Molteni & Colagrossi 2009
    /// eq. 8; 0.1 as in the literature and DualSPHysics); 0 turns it off. Unset: 0.1.
    std::optional<double> density_diffusion;
    /// Kinematic viscosity nu (m^2/s) of the laminar term of Morris et al. 1997 (WCSPH; 0: none).
    /// Unset: kinematic_viscosity(scene), water's 1e-6 for WCSPH, 0 for PCISPH and DFSPH.
    std::optional<double> kinematic_viscosity;
    /// WCSPH only: the boundary particles' pressure (WallPressure). Unset: `extrapolated` with the
    /// continuity density, `mirrored` with the summation density.
    std::optional<WallPressure> wall_pressure;
    bool operator==(const FluidParams&) const = default;
};

/// @brief A linear standing wave (sloshing mode n) given to the fluid of a one-block WCSPH scene
/// at time `at` (Lamb 1932 sec. 348; ../shared/validation/analytical_references.md): with x', y'
/// measured from the block's min corner, L its length along x, d its depth along y (gravity
/// along -y), k = n pi / L and omega^2 = |g| k tanh(k d), the velocity of
/// eta = a0 sin(omega t) cos(k x') at t = 0,
///   u = a0 omega (-cosh(k y') sin(k x'), sinh(k y') cos(k x'), 0) / sinh(k d).
/// `at` > 0 lets the tank come to rest first (the lattice is not the discrete equilibrium, and
/// its settling carries as much energy as a small wave); it needs `global` or `constant`.
struct StandingWaveDesc {
    double amplitude = 0.0;  ///< a0, m
    int mode = 1;            ///< n >= 1
    double at = 0.0;         ///< s
    bool operator==(const StandingWaveDesc&) const = default;
};

/// @brief A block of fluid particles on a cubic lattice of spacing 2 r, filling [min, max].
struct FluidBlock {
    Aabb box;
    Vec3d velocity{0, 0, 0};  ///< m/s, initial.
    /// Start at hydrostatic equilibrium (default true; with method dfsph, whose equilibrium is the
    /// uncompressed lattice, false unless the block sets it): the lattice is compressed along gravity so that the
    /// summation density at depth d is the Tait density of pressure rho0 g d. Otherwise the
    /// column starts at rho0 everywhere and rings acoustically (period 4 H / c_s).
    bool hydrostatic = true;
    bool operator==(const FluidBlock&) const = default;
};

enum class BoundaryShape { Container, Box, Sphere, Cylinder, Heightfield, Mesh };
const char* to_string(BoundaryShape s);

/// @brief A rigid boundary sampled with particles (Akinci et al. 2012).
/// `container`: the inside of a box holds the fluid (its six walls are sampled);
/// `box`: a solid obstacle; `sphere`: a solid ball. Static unless it has a `motion`, a
/// prescribed translation (engine/motion.hpp): the declared geometry is its position at
/// displacement zero, and at time t every point of it is moved by displacement(motion, t).
struct BoundaryDesc {
    BoundaryShape shape = BoundaryShape::Container;
    Aabb box;                 ///< container, box
    Vec3d center{0, 0, 0};    ///< sphere; cylinder: centre of its base
    double radius = 0.0;      ///< sphere, cylinder, m
    Vec3d axis{0, 1, 0};      ///< cylinder: unit axis from the base
    double height = 0.0;      ///< cylinder, m
    /// heightfield and mesh: the surface as triangles, the front (counter-clockwise) side
    /// facing the fluid; `box` is their bounding box. Heightfield: heights[k][i] is the surface
    /// height y at x = min.x + i (max.x - min.x)/(columns - 1), z likewise along rows k.
    std::vector<Vec3d> vertices;
    std::vector<std::array<int, 3>> triangles;
    std::vector<std::vector<double>> heights;  ///< heightfield
    std::filesystem::path file;                ///< mesh: the OBJ file (resolved)
    std::optional<Motion> motion;  ///< none: static
    bool operator==(const BoundaryDesc&) const = default;
};

/// @brief Reads the triangles of a Wavefront OBJ file (`v` and `f` lines; polygons are fanned
/// into triangles; `vt`/`vn` references and other statements are ignored). Throws InputError
/// naming the file (as `name`, when given) and line of a malformed statement.
void read_obj(const std::filesystem::path& file, std::vector<Vec3d>& vertices, std::vector<std::array<int, 3>>& triangles,
              const std::string& name = {});

/// @brief Boundaries built in code with the values a scene file does not give filled in as the
/// loader derives them: a cylinder's box (and its axis made a unit vector); a height field's
/// vertices, triangles and box (the surface over `span` in x and z, heights[k][i] as in
/// BoundaryDesc; span's y is replaced by the heights' range); a mesh's box. validate_scene refuses
/// a boundary whose derived values differ from these. Nothing else is checked here (validate_scene
/// names a bad radius, too few heights, a vertex index out of range, ...).
BoundaryDesc cylinder_boundary(const Vec3d& center, const Vec3d& axis, double radius, double height);
BoundaryDesc heightfield_boundary(const Aabb& span, std::vector<std::vector<double>> heights);
BoundaryDesc mesh_boundary(std::vector<Vec3d> vertices, std::vector<std::array<int, 3>> triangles);

/// @brief The point a circle motion carries round its circle: the centre of the box or sphere.
Vec3d reference_point(const BoundaryDesc& b);
/// @brief The same boundary moved by `d` metres (its motion is kept).
BoundaryDesc translated(const BoundaryDesc& b, const Vec3d& d);

/// @brief A disc that emits fluid particles (methods "pcisph" and "dfsph"): candidates on a square lattice of
/// spacing 2 r over the disc through `position`, normal to `velocity`. A candidate is inserted
/// only when no fluid particle and no boundary particle is closer than 0.95 x 2 r, and only
/// while the emitter's budget (rate x elapsed time) allows: a particle is never placed inside
/// another or inside a boundary.
struct EmitterDesc {
    Vec3d position{0, 0, 0};  ///< m, centre of the disc
    Vec3d velocity{0, -1, 0}; ///< m/s, of the emitted particles; its direction is the disc's normal
    double radius = 0.05;     ///< m
    double rate = 1000;       ///< particles per second, at most
    double start = 0;         ///< s
    double end = std::numeric_limits<double>::infinity();  ///< s
    std::uint64_t max_particles = std::numeric_limits<std::uint64_t>::max();  ///< this emitter's total
    bool operator==(const EmitterDesc&) const = default;
};

/// @brief The candidate positions of an emitter, in the order they are tried: a square lattice of
/// the given spacing (2 r) over its disc, normal to its velocity (at most 2001 per row).
std::vector<Vec3d> emitter_disc(const EmitterDesc& e, double spacing);

/// @brief Frame formats: particles as VTK .vtu (ParaView), Houdini classic .bgeo (partio) or
/// binary .ply (Blender); the fluid surface as an OpenVDB level set (.vdb) or a triangle mesh
/// (binary .ply), both built from one level set per frame (engine/run/surface.hpp).
enum class FrameFormat { Vtu, Bgeo, Ply, Vdb, Mesh };
const char* to_string(FrameFormat f);
/// @brief True for the formats that write particles (vtu, bgeo, ply).
constexpr bool is_particle_format(FrameFormat f) { return f == FrameFormat::Vtu || f == FrameFormat::Bgeo || f == FrameFormat::Ply; }

/// @brief How the fluid surface is built (`output.surface`, metres). Unset values follow the
/// particle radius r, so a scene keeps its look when `simulation.scale` refines it.
struct SurfaceParams {
    std::optional<double> voxel_size;     ///< level-set voxel edge; default r (half the spacing)
    std::optional<double> sphere_radius;  ///< radius of each particle's sphere; default 3 r (1.5 spacings)
    std::optional<double> smoothing;      ///< Gaussian filter width; default r; 0: none
    /// Offset the surface so it encloses the particles' volume N (2 r)³ (what the fluid holds).
    bool keep_volume = true;
    /// The values used for particle radius r (the defaults filled in).
    struct Resolved {
        double voxel_size, sphere_radius, smoothing;
        bool keep_volume;
    };
    Resolved resolve(double r) const {
        return {voxel_size.value_or(r), sphere_radius.value_or(3.0 * r), smoothing.value_or(r), keep_volume};
    }
    bool operator==(const SurfaceParams&) const = default;
};

struct OutputParams {
    std::vector<FrameFormat> formats{FrameFormat::Vtu};
    SurfaceParams surface;
    bool writes(FrameFormat f) const { return std::find(formats.begin(), formats.end(), f) != formats.end(); }
    bool writes_particles() const { return std::any_of(formats.begin(), formats.end(), is_particle_format); }
    bool writes_surface() const { return writes(FrameFormat::Vdb) || writes(FrameFormat::Mesh); }
    /// Particle attributes written per frame, besides position and id (always written): any
    /// of "position", "velocity", "density", "pressure", "acceleration", "dt", "active", "bin".
    std::vector<std::string> attributes{"velocity", "density", "pressure"};
    /// False: the default list above, to which individual stepping adds dt and active.
    bool attributes_explicit = false;
    bool operator==(const OutputParams&) const = default;
};

/// @brief Particles per axis when a box is filled on a cubic lattice of the given spacing:
/// particle k sits at min + spacing/2 + k*spacing and n = floor(extent/spacing + 1e-6).
inline Eigen::Vector3i lattice_dims(const Aabb& box, double spacing) {
    Eigen::Vector3i n;
    for (int a = 0; a < 3; ++a) {
        const double cells = (box.max[a] - box.min[a]) / spacing + 1e-6;
        n[a] = cells > 0 ? static_cast<int>(cells) : 0;
    }
    return n;
}

/// @brief A complete, validated scene.
struct Scene {
    std::string name = "scene";
    std::filesystem::path source;  ///< file it was loaded from (empty if built in code)
    SimulationParams simulation;
    /// Particles leaving this box stop the run (exit 3). Defaults to the bounding box of the
    /// boundaries grown by one support radius.
    std::optional<Aabb> domain;
    FluidParams fluid;
    std::vector<FluidBlock> fluid_blocks;
    std::vector<BoundaryDesc> boundaries;
    std::vector<EmitterDesc> emitters;
    OutputParams output;
    PcisphParams pcisph;      ///< method "pcisph" only
    DfsphParams dfsph;        ///< method "dfsph" only
    BoundaryParams boundary;  ///< method "pcisph" only
    std::vector<ProbeDesc> probes;  ///< measurements written as CSV series (engine/probes.hpp)
    std::optional<StandingWaveDesc> standing_wave;  ///< method "wcsph", one fluid block

    /// @brief Particle radius after `scale`.
    double particle_radius() const;
    bool operator==(const Scene&) const = default;
};

/// @brief The density form a scene runs with: fluid.density, or unset `continuity` for WCSPH (with
/// delta-SPH, which makes low artificial viscosity usable) and `summation` for PCISPH and DFSPH.
DensityForm density_form(const Scene& scene);

/// @brief The Monaghan alpha a scene runs with: fluid.viscosity, or unset 0.01 with the continuity
/// density (DualSPHysics' value; with delta-SPH and extrapolated walls the dam break needs no
/// more, docs/results/validation.md) and 0.1 otherwise (He et al.'s scenes).
double artificial_viscosity(const Scene& scene);

/// @brief The Monaghan alpha against boundary particles: fluid.boundary_viscosity, or unset the
/// fluid's (artificial_viscosity). 0: free-slip walls. Every method applies it at the walls.
double boundary_artificial_viscosity(const Scene& scene);

/// @brief The laminar kinematic viscosity a scene runs with: fluid.kinematic_viscosity, or unset
/// water's 1e-6 m^2/s for WCSPH and 0 for PCISPH and DFSPH (which have no laminar term).
double kinematic_viscosity(const Scene& scene);

/// @brief The wall pressure a WCSPH scene runs with: fluid.wall_pressure, or unset `extrapolated`
/// with the continuity density and `mirrored` with the summation density.
WallPressure wall_pressure(const Scene& scene);

/// @brief The standing wave's linear period 2 pi / omega and amplitude decay rate 2 nu k^2 under
/// the laminar viscosity nu (the dissipation of the irrotational flow; Lamb 1932 sec. 348).
struct WaveTheory {
    double period = 0, decay = 0;
};
WaveTheory standing_wave_theory(const Scene& scene);
/// @brief The standing wave's velocity at x (StandingWaveDesc).
Vec3d standing_wave_velocity(const Scene& scene, const Vec3d& x);

/// @brief True when any boundary of the scene has a motion.
bool has_moving_boundaries(const Scene& scene);

/// @brief A scene's size before sampling, for a memory check by the program that runs it: the
/// fluid particles on the blocks' lattices and an estimate of the bytes they and the boundary
/// need (~400 per fluid particle with every column and list, ~100 per boundary particle at
/// spacing 2 r on the boundary surfaces).
struct SizeEstimate {
    double fluid_particles = 0;
    double boundary_particles = 0;
    double bytes = 0;
    double boundary_bytes = 0;                  ///< the boundary's part of `bytes`
    std::size_t largest_boundary = 0;           ///< index in Scene::boundaries of the largest
    double largest_boundary_particles = 0;
};
SizeEstimate estimate_size(const Scene& scene);

/// @brief Whether `method` runs with a kernel support of `support` particle spacings: WCSPH with
/// any in [1.5, 4]; PCISPH and DFSPH with 2 only (docs/methods.md, "Known limitations"). The
/// loader (and so validate_scene) refuses a scene against it.
inline bool method_takes_support(Method method, double support) {
    return method == Method::Wcsph || support == 2.0;
}

/// @brief The largest acoustic coefficient lambda_c (`simulation.stepping.lambda_c`) under which
/// WCSPH's pressure field stays quiet when every particle steps at the acoustic bound
/// lambda_c h / (c_s + |v|) (h the support): 0.8 with the summation density, 0.7 with the
/// continuity density (delta-SPH). Measured on hydrostatic_tank with the bound alone setting the
/// step, from 4,500 to 105,000 particles: above these the resting water's kinetic energy grows
/// 3-25x and at lambda_c 1.0 the continuity run collapses (docs/results/he_table1.md, "lambda_c
/// 0.8, the stable edge" and "lambda_c above the stable edge"). The summation density's edge is 0.9 at 4,500 particles only; from
/// 8,100 it is 0.8. Symplectic Euler is stable for omega dt < 2 on each mode; these are where
/// the fastest acoustic mode of the discrete fluid crosses it. The loader accepts up to 1.0 and
/// initialise_world warns above this value.
double stable_lambda_c(const Scene& scene);

/// @brief Loads and validates a scene file. Throws SceneError (a typed InputError) naming the
/// file, the JSON path, the value found and what was expected.
/// @param overrides JSON-pointer paths and values applied before validation (command line).
Scene load_scene(const std::filesystem::path& file,
                 const std::vector<std::pair<std::string, nlohmann::json>>& overrides = {});

/// @brief The text of a scene file; throws InputError ("cannot open scene file (reason)").
std::string read_scene_file(const std::filesystem::path& file);

/// @brief Parses and validates scene JSON text; `file` names it in error messages.
Scene parse_scene(const std::string& text, const std::string& file,
                  const std::vector<std::pair<std::string, nlohmann::json>>& overrides = {});

/// @brief The scene as a scene file (scenes/README.md): every value written out, an optional key
/// only when set, a method's own sections only, a mesh inline (`vertices`, `triangles`) whatever
/// file it was read from. It loads back into an equal Scene but for `source` and a mesh's `file`
/// (and for values the loader derives, e.g. a cylinder's box, when a scene built in code set
/// them otherwise).
nlohmann::json scene_to_json(const Scene& scene);

/// @brief Checks a scene built or changed in code against every rule the loader applies to a
/// scene file (scene_to_json read back by parse_scene): throws SceneError naming the key by its
/// scene-file path (`/fluid/particle_radius`), the value found and what was expected, the scene
/// named as `scene "NAME" (built in code)` or `FILE (changed in code)`. make_recipe calls it.
void validate_scene(const Scene& scene);

/// @brief The domain of a scene that declares none: the bounding box of its boundaries (swept by
/// their motion to the end time), fluid blocks and emitters, grown by the support radius h (m).
Aabb default_domain(const Scene& scene, double h);

/// @brief Parses a command-line `--set path=value`: path in dotted form
/// (`simulation.stepping.lambda_v`), value as JSON (a bare word is taken as a string).
std::pair<std::string, nlohmann::json> parse_override(const std::string& assignment);

}  // namespace sph
