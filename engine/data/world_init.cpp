// Sampling a scene into a World (initialise_world), as named steps in the order they run.
#include "engine/data/world_init.hpp"

#include <cmath>
#include <limits>
#include <tuple>

#include "engine/data/components.hpp"
#include "engine/data/sampling.hpp"

#include <spdlog/spdlog.h>

namespace sph {

namespace {

// m = rho0 / sum_j W(x_i - x_j) over an infinite cubic lattice of spacing s (self included),
// so that a particle inside a filled lattice has exactly the rest density (He eq. 1).
Real lattice_mass(const CubicSpline& kernel, Real spacing, Real rest_density) {
    const int reach = static_cast<int>(std::ceil(kernel.support() / spacing)) + 1;
    double sum = 0;
    for (int k = -reach; k <= reach; ++k)
        for (int j = -reach; j <= reach; ++j)
            for (int i = -reach; i <= reach; ++i)
                sum += kernel.w(Real(spacing * std::sqrt(double(i * i + j * j + k * k))));
    return Real(rest_density / sum);
}


/// The fluid lattice of every block, in double precision (written to the store once c_s is known).
struct FluidSample {
    std::vector<Vec3d> x, v;
    std::vector<std::size_t> block_of;
};

/// Constants that follow from the scene alone: spacing, support, kernel, lattice mass, domain.
void derive_constants(World& w, const Scene& scene) {
    w.scene = scene;
    Physics& ph = w.physics;
    const double r = scene.particle_radius();
    ph.particle_radius = Real(r);
    ph.spacing = Real(2 * r);
    ph.h = Real(scene.fluid.support * 2 * r);  // 4 r by default (He et al.)
    ph.rest_density = Real(scene.fluid.rest_density);
    ph.viscosity = Real(artificial_viscosity(scene));
    ph.boundary_viscosity = Real(boundary_artificial_viscosity(scene));
    ph.gravity = scene.simulation.gravity.cast<Real>();
    ph.continuity = density_form(scene) == DensityForm::Continuity;
    ph.extrapolated_wall_pressure = scene.simulation.method == Method::Wcsph && wall_pressure(scene) == WallPressure::Extrapolated;
    ph.density_diffusion = ph.continuity ? Real(scene.fluid.density_diffusion.value_or(0.1)) : Real(0);
    ph.kinematic_viscosity = Real(kinematic_viscosity(scene));
#ifdef SPH_DOUBLE
    ph.simd = false;  // the vectorised loops are float-only
#else
    ph.simd = scene.simulation.simd;
#endif
    w.kernel = CubicSpline(ph.h);
    ph.mass = lattice_mass(w.kernel, ph.spacing, ph.rest_density);
    w.domain = scene.domain ? *scene.domain : default_domain(scene, double(ph.h));
}

FluidSample sample_fluid(const Scene& scene, double r) {
    FluidSample f;
    for (std::size_t bi = 0; bi < scene.fluid_blocks.size(); ++bi) {
        const auto& block = scene.fluid_blocks[bi];
        // The lattice fills whole spacings; say when that leaves noticeably less water than
        // declared (the spacing is fixed by the particle radius, and a stretched lattice would
        // start away from the rest density).
        const BlockFill fill = block_fill(block.box, 2 * r);
        if (fill.shortfall() > 0.01) {
            const Vec3d e = block.box.max - block.box.min;
            spdlog::warn("/fluid_blocks/{}: {} x {} x {} = {} particles hold {:.4g} m^3 of water, {:.1f} % less than "
                         "the block's {:.4g} m^3 ({:.4g} x {:.4g} x {:.4g} m filled in whole spacings of 2 r = {:.4g} m); "
                         "sides that are multiples of the spacing hold their volume exactly",
                         bi, fill.particles.x(), fill.particles.y(), fill.particles.z(),
                         fill.particles.x() * fill.particles.y() * fill.particles.z(), fill.particle_volume,
                         100 * fill.shortfall(), fill.declared_volume, e.x(), e.y(), e.z(), 2 * r);
        }
        auto pts = sample_block(block.box, 2 * r);
        f.x.insert(f.x.end(), pts.begin(), pts.end());
        f.v.insert(f.v.end(), pts.size(), block.velocity);
        f.block_of.insert(f.block_of.end(), pts.size(), bi);
    }
    return f;
}

/// Boundary particles, sampled once at the fluid spacing 2 r (Ihmsen sec. 3.2's r0; h / 2 at the
/// default fluid.support of 2): the static
/// boundaries first, then each moving boundary as one contiguous range (a moving body).
/// Returns the sampled positions (double precision). The normals are not kept: only the
/// methods that read them register the column (ensure_boundary_normals).
std::vector<Vec3d> sample_boundaries(World& w, const Scene& scene, double r) {
    std::vector<Vec3d> bx;
    w.moving_bodies.clear();
    for (const bool moving : {false, true}) {
        for (std::size_t j = 0; j < scene.boundaries.size(); ++j) {
            const auto& b = scene.boundaries[j];
            if (b.motion.has_value() != moving) continue;
            auto s = sample_boundary(b, 2 * r, r);
            const std::size_t begin = bx.size();
            bx.insert(bx.end(), s.positions.begin(), s.positions.end());
            if (moving) w.moving_bodies.push_back(MovingBody{begin, bx.size(), j, Aabb{}, 0.0});
        }
        if (!moving) w.static_boundary_end = bx.size();
    }
    auto& bs = w.boundary.store;
    bs.add(comp::position);
    // Only scenes with a moving boundary get its columns (static scenes are unchanged).
    if (!w.moving_bodies.empty()) {
        bs.add(comp::rest_position);
        bs.add(comp::velocity);
    }
    bs.resize(bx.size());
    {
        auto x = bs.get(comp::position);
        for (std::size_t i = 0; i < bx.size(); ++i) x[i] = bx[i].cast<Real>();
    }
    if (!w.moving_bodies.empty()) {
        // x0 is the sampled position; at t = 0 a body is at x0 + d(0) with velocity v(0)
        // (d(0) is zero except for a sinusoid with a phase). BoundaryMotionSystem does the same
        // at the start of every step.
        auto x = bs.get(comp::position);
        auto x0 = bs.get(comp::rest_position);
        auto vb = bs.get(comp::velocity);
        for (MovingBody& body : w.moving_bodies) {
            const Motion& motion = *scene.boundaries[body.boundary].motion;
            const Vec3d d = displacement(motion, 0.0);
            const Vec3 v = velocity(motion, 0.0).cast<Real>();
            body.bounds = Aabb{Vec3d::Constant(std::numeric_limits<double>::max()),
                               Vec3d::Constant(std::numeric_limits<double>::lowest())};
            for (std::size_t i = body.begin; i < body.end; ++i) {
                x0[i] = x[i];
                x[i] = (x0[i].cast<double>() + d).cast<Real>();
                vb[i] = v;
                body.bounds.min = body.bounds.min.cwiseMin(x[i].cast<double>());
                body.bounds.max = body.bounds.max.cwiseMax(x[i].cast<double>());
            }
            body.speed = speed_bound(motion, 0.0);
        }
        for (std::size_t i = 0; i < w.static_boundary_end; ++i) x0[i] = x[i];
    }

    return bx;
}

/// Speed of sound: density fluctuation ~ (v_ref / c_s)^2 (Monaghan 1994) with
/// v_ref = sqrt(2 |g| H), H the fluid's top above the lowest point of the domain; then the
/// Tait stiffness B (He eq. 2).
void choose_speed_of_sound(World& w, const Scene& scene, const FluidSample& fluid, const std::vector<Vec3d>& bx) {
    Physics& ph = w.physics;
    const std::vector<Vec3d>& xs = fluid.x;
    const std::vector<Vec3d>& vs = fluid.v;
    const double g = scene.simulation.gravity.norm();
    double top = -std::numeric_limits<double>::max(), vmax0 = 0;
    const Vec3d up = g > 0 ? Vec3d(-scene.simulation.gravity / g) : Vec3d::UnitY();
    for (std::size_t i = 0; i < xs.size(); ++i) {
        top = std::max(top, xs[i].dot(up));
        vmax0 = std::max(vmax0, vs[i].norm());
    }
    // Emitted fluid enters at the emitter's height with its speed.
    for (const auto& e : scene.emitters) {
        top = std::max(top, e.position.dot(up));
        vmax0 = std::max(vmax0, e.velocity.norm());
    }
    double bottom = std::numeric_limits<double>::max();
    for (int c = 0; c < 8; ++c) {
        const Vec3d corner((c & 1) ? w.domain.max[0] : w.domain.min[0], (c & 2) ? w.domain.max[1] : w.domain.min[1],
                           (c & 4) ? w.domain.max[2] : w.domain.min[2]);
        bottom = std::min(bottom, corner.dot(up));
    }
    if (!bx.empty()) {
        bottom = std::numeric_limits<double>::max();
        for (const auto& p : bx) bottom = std::min(bottom, p.dot(up));
    }
    ph.fluid_height = (xs.empty() && scene.emitters.empty()) ? 0.0 : std::max(0.0, top - bottom);
    double vref = std::max(std::sqrt(2.0 * g * ph.fluid_height), vmax0);
    if (vref <= 0) vref = 1.0;  // nothing moves and nothing falls: any stiffness is stable
    ph.speed_of_sound = Real(scene.fluid.speed_of_sound ? *scene.fluid.speed_of_sound
                                                        : vref / std::sqrt(scene.fluid.density_fluctuation));
    ph.tait_b = ph.rest_density * ph.speed_of_sound * ph.speed_of_sound / Real(7);
}

/// Hydrostatic start: keep each block's bottom layer and compress the lattice along gravity
/// with dy'/dy = rho0 / rho(d), rho(d) = rho0 (1 + rho0 g d / B)^(1/7) the Tait density of
/// the pressure rho0 g d at depth d below the block's top (He eq. 2 inverted).
void compress_hydrostatic(const World& w, const Scene& scene, FluidSample& fluid) {
    const Physics& ph = w.physics;
    const double r = scene.particle_radius();
    const double g = scene.simulation.gravity.norm();
    const Vec3d up = g > 0 ? Vec3d(-scene.simulation.gravity / g) : Vec3d::UnitY();
    std::vector<Vec3d>& xs = fluid.x;
    const std::vector<std::size_t>& block_of = fluid.block_of;
    if (g > 0) {
        for (std::size_t bi = 0; bi < scene.fluid_blocks.size(); ++bi) {
            const auto& block = scene.fluid_blocks[bi];
            if (!block.hydrostatic) continue;
            double top_b = -std::numeric_limits<double>::max(), bottom_b = std::numeric_limits<double>::max();
            for (std::size_t i = 0; i < xs.size(); ++i)
                if (block_of[i] == bi) {
                    top_b = std::max(top_b, xs[i].dot(up) + r);
                    bottom_b = std::min(bottom_b, xs[i].dot(up));
                }
            const double b_eos = double(ph.tait_b), rho0 = double(ph.rest_density);
            auto compression = [&](double height) {  // rho0 / rho at this height
                const double d = std::max(0.0, top_b - height);
                return std::pow(1.0 + rho0 * g * d / b_eos, -1.0 / 7.0);
            };
            for (std::size_t i = 0; i < xs.size(); ++i) {
                if (block_of[i] != bi) continue;
                const double y = xs[i].dot(up);
                const int steps = 16;  // midpoint rule; the integrand is smooth and near 1
                double y_new = bottom_b;
                for (int k = 0; k < steps; ++k)
                    y_new += (y - bottom_b) / steps * compression(bottom_b + (k + 0.5) * (y - bottom_b) / steps);
                xs[i] += (y_new - y) * up;
            }
        }
    }
}

/// The fluid set: position, velocity and id (the sampling order) for every lattice point.
void write_fluid(World& w, const FluidSample& fluid) {
    const std::vector<Vec3d>& xs = fluid.x;
    const std::vector<Vec3d>& vs = fluid.v;
    auto& fs = w.fluid.store;
    fs.add(comp::position);
    fs.add(comp::velocity);
    fs.add(comp::id);
    fs.resize(xs.size());
    {
        auto x = fs.get(comp::position);
        auto v = fs.get(comp::velocity);
        auto id = fs.get(comp::id);
        for (std::size_t i = 0; i < xs.size(); ++i) {
            x[i] = xs[i].cast<Real>();
            v[i] = vs[i].cast<Real>();
            id[i] = std::uint32_t(i);
        }
    }

}

/// The boundary store's row order: the static particles (the first static_boundary_end of
/// `sampled`, in sampling order) in z-order of the boundary grid's cells, the moving bodies'
/// ranges as sampled. new[i] = sampled[perm[i]]; deterministic, so it can be recomputed.
std::vector<Index> boundary_order(const World& w, std::span<const Vec3> sampled) {
    std::vector<Index> perm = zorder_permutation(w.boundary_grid, sampled.subspan(0, w.static_boundary_end));
    for (std::size_t i = w.static_boundary_end; i < sampled.size(); ++i) perm.push_back(Index(i));
    return perm;
}

/// The grids: the fluid's over the domain, the boundary's over the domain and every boundary
/// particle; static boundary particles are put in z-order once.
void build_grids(World& w, const std::vector<Vec3d>& bx) {
    const Physics& ph = w.physics;
    auto& bs = w.boundary.store;
    w.fluid_grid = UniformGrid(w.domain, ph.h, "fluid grid (the scene's domain)", /*keep_coordinates=*/true);
    Aabb bbox = w.domain;
    for (const auto& p : bx) {
        bbox.min = bbox.min.cwiseMin(p);
        bbox.max = bbox.max.cwiseMax(p);
    }
    for (const MovingBody& body : w.moving_bodies) {
        bbox.min = bbox.min.cwiseMin(body.bounds.min);
        bbox.max = bbox.max.cwiseMax(body.bounds.max);
    }
    w.boundary_grid = UniformGrid(bbox, ph.h, "boundary grid (the domain and every boundary)");
    w.boundary_grid.mark_empty_neighbourhoods(true);  // most fluid queries meet no wall
    // A moving body's particles change cell every few dozen steps: BoundaryMotionSystem
    // rebuilds the grid only then (UniformGrid::in_built_cells).
    w.boundary_grid.keep_cells(!w.moving_bodies.empty());
    if (!bx.empty()) {
        // Static boundary particles never move: store them in z-order once, then index the
        // grid. Moving bodies keep their ranges (the permutation is the identity there).
        bs.permute(boundary_order(w, bs.get(comp::position)));
        w.boundary_grid.build(bs.get(comp::position));
    }
}

/// A WCSPH step at the acoustic bound above stable_lambda_c rings (scene.hpp): said once, at the start.
void warn_unstable_lambda_c(const Scene& scene) {
    const SteppingParams& st = scene.simulation.stepping;
    if (scene.simulation.method != Method::Wcsph || !st.acoustic || st.mode == SteppingMode::Constant) return;
    const double edge = stable_lambda_c(scene);
    if (st.lambda_c <= edge) return;
    spdlog::warn("simulation.stepping.lambda_c = {:g} is above {:g}, the largest at which a {} density's pressure "
                 "field stays quiet when particles step at the acoustic bound (measured: a resting tank's kinetic "
                 "energy grows 3-40x above it); particles that reach the bound will ring. Keep lambda_c at or below "
                 "{:g} (docs/methods.md, \"The acoustic condition\")",
                 st.lambda_c, edge, to_string(density_form(scene)), edge);
}

}  // namespace

void initialise_world(World& w, const Scene& scene) {
    warn_unstable_lambda_c(scene);
    derive_constants(w, scene);
    const double r = scene.particle_radius();
    FluidSample fluid = sample_fluid(scene, r);
    const std::vector<Vec3d> bx = sample_boundaries(w, scene, r);
    choose_speed_of_sound(w, scene, fluid, bx);
    compress_hydrostatic(w, scene, fluid);
    write_fluid(w, fluid);
    build_grids(w, bx);
    w.clock = Clock{};
    w.step_size = StepSize{};
    w.step_size.set(scene.simulation.stepping.dt);
}

std::vector<Vec3> sampled_boundary_normals(const World& w, std::size_t begin, std::size_t end) {
    const Scene& scene = w.scene;
    const double r = scene.particle_radius();
    end = std::min(end, w.boundary.size());
    begin = std::min(begin, end);
    std::vector<Vec3> out(end - begin, Vec3::Zero());
    if (begin < w.static_boundary_end) {  // the static part: sampled again and put in store order
        std::vector<Vec3> x, n;
        for (const auto& b : scene.boundaries) {
            if (b.motion) continue;
            const auto s = sample_boundary(b, 2 * r, r);
            for (std::size_t k = 0; k < s.positions.size(); ++k) {
                x.push_back(s.positions[k].cast<Real>());
                n.push_back(s.normals[k].cast<Real>());
            }
        }
        if (x.size() != w.static_boundary_end)
            throw std::logic_error("sampled_boundary_normals: the scene samples to another boundary");
        const std::vector<Index> perm = boundary_order(w, x);
        for (std::size_t i = begin; i < std::min(end, w.static_boundary_end); ++i) out[i - begin] = n[perm[i]];
    }
    for (const MovingBody& body : w.moving_bodies) {  // each body's range as sampled
        if (body.end <= begin || body.begin >= end) continue;
        const auto s = sample_boundary(scene.boundaries[body.boundary], 2 * r, r);
        for (std::size_t i = std::max(begin, body.begin); i < std::min(end, body.end); ++i)
            out[i - begin] = s.normals[i - body.begin].cast<Real>();
    }
    return out;
}

void ensure_boundary_normals(World& w) {
    auto& bs = w.boundary.store;
    if (bs.has(comp::normal.name)) return;
    const std::vector<Vec3> n = sampled_boundary_normals(w, 0, w.boundary.size());
    bs.add(comp::normal);
    std::copy(n.begin(), n.end(), bs.get(comp::normal).begin());
}

}  // namespace sph
