#include "engine/simulation.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <cmath>
#include <sstream>
#include <tuple>
#include <type_traits>

#include "engine/components.hpp"
#include "engine/errors.hpp"
#include "engine/sampling.hpp"

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

}  // namespace

void initialise_world(World& w, const Scene& scene) {
    w.scene = scene;
    Physics& ph = w.physics;
    const double r = scene.particle_radius();
    ph.particle_radius = Real(r);
    ph.spacing = Real(2 * r);
    ph.h = Real(scene.fluid.support * 2 * r);  // 4 r by default (He et al.)
    ph.rest_density = Real(scene.fluid.rest_density);
    ph.viscosity = Real(scene.fluid.viscosity);
    ph.boundary_viscosity = Real(scene.fluid.boundary_viscosity.value_or(scene.fluid.viscosity));
    ph.gravity = scene.simulation.gravity.cast<Real>();
    w.kernel = CubicSpline(ph.h);
    ph.mass = lattice_mass(w.kernel, ph.spacing, ph.rest_density);
    w.domain = scene.domain ? *scene.domain : default_domain(scene, double(ph.h));

    // Fluid particles (positions are written once c_s is known: see the hydrostatic step).
    std::vector<Vec3d> xs;
    std::vector<Vec3d> vs;
    std::vector<std::size_t> block_of;
    for (std::size_t bi = 0; bi < scene.fluid_blocks.size(); ++bi) {
        const auto& block = scene.fluid_blocks[bi];
        auto pts = sample_block(block.box, 2 * r);
        xs.insert(xs.end(), pts.begin(), pts.end());
        vs.insert(vs.end(), pts.size(), block.velocity);
        block_of.insert(block_of.end(), pts.size(), bi);
    }
    auto& fs = w.fluid.store;
    fs.add(comp::position);
    fs.add(comp::velocity);
    fs.add(comp::id);
    fs.resize(xs.size());

    // Boundary particles, sampled once at the fluid spacing r0 = 2 r = h / 2: the static
    // boundaries first, then each moving boundary as one contiguous range (a moving body).
    std::vector<Vec3d> bx, bn;
    w.moving_bodies.clear();
    for (const bool moving : {false, true}) {
        for (std::size_t j = 0; j < scene.boundaries.size(); ++j) {
            const auto& b = scene.boundaries[j];
            if (b.motion.has_value() != moving) continue;
            auto s = sample_boundary(b, 2 * r, r);
            const std::size_t begin = bx.size();
            bx.insert(bx.end(), s.positions.begin(), s.positions.end());
            bn.insert(bn.end(), s.normals.begin(), s.normals.end());
            if (moving) w.moving_bodies.push_back(MovingBody{begin, bx.size(), j, Aabb{}, 0.0});
        }
        if (!moving) w.static_boundary_end = bx.size();
    }
    auto& bs = w.boundary.store;
    bs.add(comp::position);
    bs.add(comp::normal);
    // Only scenes with a moving boundary get its columns (static scenes are unchanged).
    if (!w.moving_bodies.empty()) {
        bs.add(comp::rest_position);
        bs.add(comp::velocity);
    }
    bs.resize(bx.size());
    {
        auto x = bs.get(comp::position);
        auto n = bs.get(comp::normal);
        for (std::size_t i = 0; i < bx.size(); ++i) {
            x[i] = bx[i].cast<Real>();
            n[i] = bn[i].cast<Real>();
        }
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

    // Speed of sound: density fluctuation ~ (v_ref / c_s)^2 (Monaghan 1994) with
    // v_ref = sqrt(2 |g| H), H the fluid's top above the lowest point of the domain.
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

    // Hydrostatic start: keep each block's bottom layer and compress the lattice along gravity
    // with dy'/dy = rho0 / rho(d), rho(d) = rho0 (1 + rho0 g d / B)^(1/7) the Tait density of
    // the pressure rho0 g d at depth d below the block's top (He eq. 2 inverted).
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

    w.fluid_grid = UniformGrid(w.domain, ph.h);
    Aabb bbox = w.domain;
    for (const auto& p : bx) {
        bbox.min = bbox.min.cwiseMin(p);
        bbox.max = bbox.max.cwiseMax(p);
    }
    for (const MovingBody& body : w.moving_bodies) {
        bbox.min = bbox.min.cwiseMin(body.bounds.min);
        bbox.max = bbox.max.cwiseMax(body.bounds.max);
    }
    w.boundary_grid = UniformGrid(bbox, ph.h);
    if (!bx.empty()) {
        // Static boundary particles never move: store them in z-order once, then index the
        // grid. Moving bodies keep their ranges (the permutation is the identity there); the
        // boundary motion system rebuilds the grid every step.
        const std::span<const Vec3> all = bs.get(comp::position);
        std::vector<Index> perm = zorder_permutation(w.boundary_grid, all.subspan(0, w.static_boundary_end));
        for (std::size_t i = w.static_boundary_end; i < all.size(); ++i) perm.push_back(Index(i));
        bs.permute(perm);
        w.boundary_grid.build(bs.get(comp::position));
    }
    w.emitters = EmitterState{};
    w.emitters.budget.assign(scene.emitters.size(), 0.0);
    w.emitters.emitted.assign(scene.emitters.size(), 0);
    w.emitters.next_id = std::uint32_t(xs.size());
    w.step = StepState{};
    w.step.set_dt(scene.simulation.stepping.dt);
}

Simulation::Simulation(const Scene& scene, Recipe recipe) {
    initialise_world(m_world, scene);
    for (auto& s : recipe.setup) s->register_components(m_world);
    for (auto& s : recipe.step) s->register_components(m_world);
    if (!recipe.setup.empty()) {
        SystemGraph setup(std::move(recipe.setup), m_world);
        setup.run();
    }
    m_graph = std::make_unique<SystemGraph>(std::move(recipe.step), m_world);
    m_rollback_steps = recipe.rollback_steps;
    if (m_rollback_steps > 0) m_ring = std::make_unique<StateRing>(m_rollback_steps);
    m_graph->set_after_system([this](std::size_t i) { trace_non_finite(i); });
}

namespace {

/// Index of the first non-finite element of a column, or n.
template <class T>
std::size_t first_non_finite(std::span<const T> v) {
    const std::size_t n = v.size();
    return tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, n, 8192), n,
        [&](const auto& r, std::size_t best) {
            for (std::size_t i = r.begin(); i < r.end() && i < best; ++i) {
                if constexpr (std::is_same_v<T, Vec3>) {
                    if (!v[i].allFinite()) return i;
                } else {
                    if (!std::isfinite(v[i])) return i;
                }
            }
            return best;
        },
        [](std::size_t a, std::size_t b) { return std::min(a, b); });
}

}  // namespace

void Simulation::trace_non_finite(std::size_t system) {
    // Cheap (a streaming read of the columns just written, ~1 % of a step) and it is what lets
    // a NaN be reported with the system that produced it rather than the one that carried it.
    const ComponentStore& store = m_world.fluid.store;
    for (const auto& wr : m_graph->systems()[system]->access().writes) {
        if (wr.rfind("fluid.", 0) != 0) continue;
        const std::string col = wr.substr(6);
        if (!store.has(col)) continue;
        const std::type_info& t = store.type_of(col);
        std::size_t bad = store.size();
        if (t == typeid(Vec3))
            bad = first_non_finite(store.get(Component<Vec3>{col}));
        else if (t == typeid(Real))
            bad = first_non_finite(store.get(Component<Real>{col}));
        else if (t == typeid(double))
            bad = first_non_finite(store.get(Component<double>{col}));
        if (bad == store.size()) continue;
        std::lock_guard lock(m_trace_mutex);
        // Recipe order is a topological order of the graph: a value can only reach a later
        // system, so the earliest one with a non-finite output is where it was produced.
        if (system < m_non_finite.system) m_non_finite = NonFinite{system, bad, col};
        return;
    }
}

std::size_t Simulation::particle_bytes() const {
    const World& w = m_world;
    return w.fluid.store.bytes() + w.boundary.store.bytes() + w.fluid_grid.bytes() + w.boundary_grid.bytes() +
           w.fluid_neighbours.bytes() + w.boundary_neighbours.bytes();
}

void Simulation::spatial_sort() {
    auto perm = zorder_permutation(m_world.fluid_grid, m_world.fluid.store.get(comp::position));
    m_world.fluid.store.permute(perm);
    // Lists that are kept across steps (individual stepping reuses inactive particles' lists)
    // follow the permutation; fluid->fluid entries are renumbered as well.
    m_world.fluid_neighbours.permute(perm, true);
    m_world.boundary_neighbours.permute(perm, false);
}

void Simulation::step() {
    const int interval = m_world.scene.simulation.sort_interval;
    if (interval > 0 && m_world.step.step % interval == 0) spatial_sort();
    StepState& st = m_world.step;
    if (m_ring) m_ring->save(m_world);
    st.rolled_back = false;
    if (m_world.scene.simulation.stepping.mode == SteppingMode::Constant) {
        // Constant stepping has no dt system: the step is the scene's, clipped at the end.
        st.dt_stable = m_world.scene.simulation.stepping.dt;
        st.set_dt_clipped(st.dt_stable);
    }
    m_non_finite = NonFinite{};
    m_graph->run();
    st.last_step = st.step;
    st.last_t = st.t;
    st.last_dt = st.dt;
    if (m_ring && m_world.pcisph.rollback_dt > 0) {
        // Shock (Ihmsen 2010 eq. 25-27): back to the state `m_rollback_steps` steps ago, resumed
        // with the step of eq. 24. The step counter, the shock count and the record of the
        // discarded step survive the restore.
        const double resume_dt = m_world.pcisph.rollback_dt;
        const StepState discarded = st;
        if (!(resume_dt >= m_world.scene.simulation.stepping.dt_min)) {
            std::ostringstream os;
            os << "shock at step " << st.step << " (t = " << st.t << " s): the step to resume with, " << resume_dt
               << " s (Ihmsen eq. 24), is below dt_min = " << m_world.scene.simulation.stepping.dt_min
               << " s; v_max = " << st.v_max << " m/s, F_max = " << st.a_max << " m/s^2 at particle "
               << st.a_max_particle;
            throw SimulationError(os.str(), st.a_max_particle, st.step, "adaptive_dt");
        }
        m_ring->restore(m_world, m_rollback_steps);
        StepState& r = m_world.step;
        r.step = discarded.step + 1;
        r.shocks = discarded.shocks + 1;
        r.rolled_back = true;
        r.last_step = discarded.last_step;
        r.last_t = discarded.last_t;
        r.last_dt = discarded.last_dt;
        // The discarded step's statistics stay visible to the recorder.
        r.rho_err_avg = discarded.rho_err_avg;
        r.rho_err_max = discarded.rho_err_max;
        r.v_max = discarded.v_max;
        r.a_max = discarded.a_max;
        r.iterations = discarded.iterations;
        r.boundary_active = discarded.boundary_active;
        r.collisions = discarded.collisions;
        r.dt_stable = discarded.dt_stable;
        m_world.pcisph.pending_dt = resume_dt;
        m_world.pcisph.rollback_dt = 0;
        return;
    }
    check_step();
    m_world.step.t_ticks += m_world.step.dt_ticks;
    m_world.step.t = to_seconds(m_world.step.t_ticks);
    ++m_world.step.step;
}

void Simulation::run_until(double end_time, const std::function<void(const Simulation&)>& after_step) {
    // Stop when the remaining time is below a millionth of a step, so round-off never adds
    // a sliver step at the end.
    m_world.step.t_stop = end_time;
    const Tick end = to_ticks(end_time + 0.5 * kSecondsPerTick);
    while (m_world.step.t_ticks < end) {
        step();
        if (after_step) after_step(*this);
    }
    m_world.step.t_stop = std::numeric_limits<double>::infinity();
}

void Simulation::check_step() {
    World& w = m_world;
    const auto x = w.fluid.store.get(comp::position);
    const auto v = w.fluid.store.get(comp::velocity);
    const Aabb& d = w.domain;
    // First offending particle by index (deterministic), or n when all are fine.
    const std::size_t n = x.size();
    const std::size_t bad = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, n, 4096), n,
        [&](const auto& r, std::size_t best) {
            for (std::size_t i = r.begin(); i < r.end() && i < best; ++i) {
                const bool finite = x[i].allFinite() && v[i].allFinite();
                const Vec3d p = x[i].template cast<double>();
                if (!finite || !d.contains(p)) return i;
            }
            return best;
        },
        [](std::size_t a, std::size_t b) { return std::min(a, b); });
    const double dt = w.step.dt;
    const auto& st = w.scene.simulation.stepping;
    const auto& systems = m_graph->systems();
    const bool traced = m_non_finite.system < systems.size();
    if (bad == n && !traced) {
        const double stable = w.step.dt_stable > 0 ? w.step.dt_stable : dt;  // a clipped last step is fine
        if (!(stable >= st.dt_min) || !std::isfinite(dt)) {
            std::ostringstream os;
            os << "time step collapsed at step " << w.step.step << " (t = " << w.step.t << " s): dt = " << stable
               << " s is below dt_min = " << st.dt_min << " s; the largest acceleration, " << w.step.a_max
               << " m/s^2, is at particle " << w.step.a_max_particle;
            throw SimulationError(os.str(), w.step.a_max_particle, w.step.step, "global_dt");
        }
        return;
    }
    std::ostringstream os;
    std::string culprit = "unknown";
    if (!traced && x[bad].allFinite() && v[bad].allFinite()) {
        const std::uint32_t id = w.fluid.store.has(comp::id.name) ? w.fluid.store.get(comp::id)[bad] : std::uint32_t(bad);
        // Left the domain: the last system that wrote positions moved it.
        for (const auto& s : systems)
            for (const auto& wr : s->access().writes)
                if (wr == res::fluid(comp::position.name)) culprit = s->name();
        os << "particle " << id << " left the domain at step " << w.step.step << " (t = " << w.step.t
           << " s): position (" << x[bad].transpose() << ") is outside [" << d.min.transpose() << "] - ["
           << d.max.transpose() << "], moved by system '" << culprit << "'";
        throw SimulationError(os.str(), id, w.step.step, culprit);
    }
    {
        // Non-finite: traced while the step ran to the earliest system (in recipe order) whose
        // output held a non-finite value; that value's particle is the one named.
        std::size_t particle = bad;
        std::string field = "position/velocity";
        if (traced) {
            culprit = systems[m_non_finite.system]->name();
            particle = m_non_finite.particle;
            field = m_non_finite.column;
        }
        const std::uint32_t pid =
            w.fluid.store.has(comp::id.name) ? w.fluid.store.get(comp::id)[particle] : std::uint32_t(particle);
        os << "particle " << pid << " became non-finite at step " << w.step.step << " (t = " << w.step.t
           << " s): " << field << " is NaN or infinite, first produced by system '" << culprit << "'";
        throw SimulationError(os.str(), pid, w.step.step, culprit);
    }
}

}  // namespace sph
