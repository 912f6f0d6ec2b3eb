#include "engine/run/simulation.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <cmath>
#include <sstream>
#include <tuple>
#include <type_traits>

#include "engine/data/components.hpp"
#include "engine/core/errors.hpp"
#include "engine/data/sampling.hpp"

namespace sph {

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
    give_wave_if_due();  // a wave at 0 is in the first frame
}

namespace {

/// Index of the first non-finite element of a column, or n; only the listed rows when `rows`
/// is given (ascending, so the first found is still the lowest index).
template <class T>
std::size_t first_non_finite(std::span<const T> v, const std::vector<Index>* rows) {
    const std::size_t n = v.size(), m = rows ? rows->size() : n;
    const std::size_t k = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, m, 8192), m,
        [&](const auto& r, std::size_t best) {
            for (std::size_t k = r.begin(); k < r.end() && k < best; ++k) {
                const std::size_t i = rows ? (*rows)[k] : k;
                if constexpr (std::is_same_v<T, Vec3>) {
                    if (!v[i].allFinite()) return k;
                } else {
                    if (!std::isfinite(v[i])) return k;
                }
            }
            return best;
        },
        [](std::size_t a, std::size_t b) { return std::min(a, b); });
    return k == m ? n : (rows ? (*rows)[k] : k);
}

}  // namespace

void Simulation::trace_non_finite(std::size_t system) {
    // Cheap (a streaming read of the columns just written, ~1 % of a step) and it is what lets
    // a NaN be reported with the system that produced it rather than the one that carried it.
    const ComponentStore& store = m_world.fluid.store;
    const Access& access = m_graph->access(system);
    // A system that declares its rows (Access::rows) is checked there only.
    const std::vector<Index>* rows = nullptr;
    if (access.written_rows() == key_of(res::active_set)) rows = &m_world.active_set;
    if (access.written_rows() == key_of(res::collided)) rows = &m_world.collided;
    if (access.written_rows() == key_of(res::drifted)) rows = &m_world.drifted;
    for (const auto& wr : access.writes()) {
        if (wr.rfind("fluid.", 0) != 0) continue;
        const std::string col = wr.substr(6);
        if (!store.has(col)) continue;
        const std::type_info& t = store.type_of(col);
        std::size_t bad = store.size();
        if (t == typeid(Vec3))
            bad = first_non_finite(store.get(Component<Vec3>{col}), rows);
        else if (t == typeid(Real))
            bad = first_non_finite(store.get(Component<Real>{col}), rows);
        else if (t == typeid(double))
            bad = first_non_finite(store.get(Component<double>{col}), rows);
        if (bad == store.size()) continue;
        std::lock_guard lock(m_trace_mutex);
        // Recipe order is a topological order of the graph: a value can only reach a later
        // system, so the earliest one with a non-finite output is where it was produced.
        if (system < m_non_finite.system) m_non_finite = NonFinite{system, bad, col};
        return;
    }
}

std::size_t Simulation::particle_bytes() const {
    std::size_t sum = 0;
    for (const auto& [name, bytes] : memory_parts()) sum += bytes;
    return sum;
}

std::vector<std::pair<std::string, std::size_t>> Simulation::memory_parts() const {
    const World& w = m_world;
    std::vector<std::pair<std::string, std::size_t>> parts;
    for (const auto& name : w.fluid.store.names()) parts.emplace_back("fluid." + name, w.fluid.store.bytes(name));
    for (const auto& name : w.boundary.store.names()) parts.emplace_back("boundary." + name, w.boundary.store.bytes(name));
    parts.emplace_back("fluid.grid", w.fluid_grid.bytes());
    parts.emplace_back("boundary.grid", w.boundary_grid.bytes());
    parts.emplace_back("fluid.neighbours", w.fluid_neighbours.bytes());
    parts.emplace_back("fluid.boundary_neighbours", w.boundary_neighbours.bytes());
    // Resources a system owns that report their heap (DFSPH's stored pair gradients).
    for (const auto& [name, r] : w.resources.items())
        if (const std::size_t bytes = r->memory()) parts.emplace_back(name, bytes);
    return parts;
}

void Simulation::synchronise() {
    if (!m_behind) return;
    m_world.synchronise(m_world);
    m_behind = false;
}

void Simulation::spatial_sort() {
    synchronise();  // the order follows every row's position at the clock's time
    auto perm = zorder_permutation(m_world.fluid_grid, m_world.fluid.store.get(comp::position));
    m_world.fluid.store.permute(perm);
    // Lists that are kept across steps (individual stepping reuses inactive particles' lists)
    // follow the permutation; fluid->fluid entries are renumbered as well.
    m_world.fluid_neighbours.permute(perm, true);
    m_world.boundary_neighbours.permute(perm, false);
}

void Simulation::step() {
    step_once();
    if (m_sync_observers) synchronise();
}

void Simulation::step_once() {
    const int interval = m_world.scene.simulation.sort_interval;
    if (interval > 0 && m_world.clock.step % interval == 0) spatial_sort();
    if (m_ring) m_ring->save(m_world);
    m_non_finite = NonFinite{};
    m_graph->run();
    m_behind = bool(m_world.synchronise);  // a lazy recipe leaves the sleeping rows behind
    m_last = StepRecord{m_world.clock.step, m_world.clock.t, m_world.step_size.dt, m_world.step_size.dt_stable, false};
    if (m_ring && m_world.rollback.request_dt > 0) {
        serve_rollback();
        return;
    }
    check_step();
    m_world.clock.t_ticks += m_world.step_size.dt_ticks;
    m_world.clock.t = to_seconds(m_world.clock.t_ticks);
    ++m_world.clock.step;
}

void Simulation::serve_rollback() {
    // Back to the state `m_rollback_steps` steps ago (the particle columns, the clock and the
    // Kept resources), resumed with the step the requesting system asked for. The step counter
    // and the rollback count survive the restore; the statistics and counters of the discarded
    // step stay in the world (they are not part of the saved state), so the outputs report it.
    Rollback& rb = m_world.rollback;
    const double resume_dt = rb.request_dt;
    const Clock discarded = m_world.clock;
    if (!(resume_dt >= m_world.scene.simulation.stepping.dt_min)) {
        std::ostringstream os;
        os << rb.reason << " at step " << discarded.step << " (t = " << discarded.t << " s): the step to resume with, "
           << resume_dt << " s, is below dt_min = " << m_world.scene.simulation.stepping.dt_min << " s; v_max = "
           << m_world.stats.v_max << " m/s, F_max = " << m_world.stats.a_max << " m/s^2 at particle "
           << m_world.stats.a_max_particle;
        throw SimulationError(os.str(), m_world.stats.a_max_particle, discarded.step, rb.requested_by);
    }
    m_ring->restore(m_world, m_rollback_steps);
    m_world.clock.step = discarded.step + 1;
    m_world.clock.rollbacks = discarded.rollbacks + 1;
    m_last.rolled_back = true;
    rb.request_dt = 0;
    rb.resume_dt = resume_dt;
}

std::string Simulation::step_size_owner() const {
    std::string owner = "the step size";
    const std::string dt = key_of(res::dt);
    for (std::size_t i = 0; i < m_graph->systems().size(); ++i)
        if (m_graph->access(i).may_write(dt)) owner = m_graph->systems()[i]->name();
    return owner;
}

bool Simulation::run_until(double end_time, const std::function<void(const Simulation&)>& after_step) {
    const auto& wave = m_world.scene.standing_wave;
    if (wave && !m_wave_given && end_time >= wave->at && m_world.clock.t < wave->at && !advance(wave->at, after_step))
        return false;
    give_wave_if_due();
    return advance(end_time, after_step);
}

void Simulation::give_wave_if_due() {
    const auto& wave = m_world.scene.standing_wave;
    if (!wave || m_wave_given || m_world.clock.t_ticks != to_ticks(wave->at + 0.5 * kSecondsPerTick)) return;
    const auto x = m_world.fluid.store.get(comp::position);
    auto v = m_world.fluid.store.get(comp::velocity);
    for (std::size_t i = 0; i < x.size(); ++i)
        v[i] = standing_wave_velocity(m_world.scene, x[i].cast<double>()).cast<Real>();
    m_wave_given = true;
}

bool Simulation::advance(double end_time, const std::function<void(const Simulation&)>& after_step) {
    // The end in whole ticks (rounded to the nearest): the step-size systems clip the last step
    // to land on it exactly, so round-off never adds a sliver step at the end.
    m_world.clock.t_stop = end_time;
    const Tick end = to_ticks(end_time + 0.5 * kSecondsPerTick);
    m_stop.store(false, std::memory_order_relaxed);
    while (m_world.clock.t_ticks < end) {
        step();
        if (after_step) after_step(*this);
        if (m_stop.exchange(false, std::memory_order_relaxed)) break;
    }
    synchronise();
    m_world.clock.t_stop = std::numeric_limits<double>::infinity();
    return m_world.clock.t_ticks >= end;
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
    const double dt = w.step_size.dt;
    const auto& st = w.scene.simulation.stepping;
    const auto& systems = m_graph->systems();
    const bool traced = m_non_finite.system < systems.size();
    if (bad == n && !traced) {
        const double stable = w.step_size.dt_stable > 0 ? w.step_size.dt_stable : dt;  // a clipped last step is fine
        if (!(stable >= st.dt_min) || !std::isfinite(dt)) {
            std::ostringstream os;
            os << "time step collapsed at step " << w.clock.step << " (t = " << w.clock.t << " s): dt = " << stable
               << " s from system '" << step_size_owner() << "' is below dt_min = " << st.dt_min << " s; ";
            // What can limit a step, each with its own figure (a sound speed that is too high is
            // not an acceleration problem, and with no particle there is no particle to name).
            if (n == 0) {
                os << "there is no fluid particle yet, so no particle's velocity or acceleration limits it: the "
                      "scene's own figures do (gravity "
                   << w.physics.gravity.norm() << " m/s^2, speed of sound " << w.physics.speed_of_sound
                   << " m/s, h / c_s = " << w.physics.h / w.physics.speed_of_sound << " s)";
            } else {
                os << "the fastest particle moves at v_max = " << w.stats.v_max
                   << " m/s, the largest acceleration is " << w.stats.a_max << " m/s^2 at particle "
                   << w.stats.a_max_particle << ", the speed of sound is " << w.physics.speed_of_sound
                   << " m/s (h / c_s = " << w.physics.h / w.physics.speed_of_sound << " s)";
            }
            throw SimulationError(os.str(), w.stats.a_max_particle, w.clock.step, step_size_owner());
        }
        return;
    }
    std::ostringstream os;
    std::string culprit = "unknown";
    if (!traced && x[bad].allFinite() && v[bad].allFinite()) {
        const std::uint32_t id = w.fluid.store.has(comp::id.name) ? w.fluid.store.get(comp::id)[bad] : std::uint32_t(bad);
        // Left the domain: the last system that wrote positions moved it.
        for (std::size_t i = 0; i < systems.size(); ++i)
            if (m_graph->access(i).may_write(key_of(fluid(comp::position)))) culprit = systems[i]->name();
        os << "particle " << id << " left the domain at step " << w.clock.step << " (t = " << w.clock.t
           << " s): position (" << x[bad].transpose() << ") is outside [" << d.min.transpose() << "] - ["
           << d.max.transpose() << "], moved by system '" << culprit << "'";
        throw SimulationError(os.str(), id, w.clock.step, culprit);
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
        os << "particle " << pid << " became non-finite at step " << w.clock.step << " (t = " << w.clock.t
           << " s): " << field << " is NaN or infinite, first produced by system '" << culprit << "'";
        throw SimulationError(os.str(), pid, w.clock.step, culprit);
    }
}

}  // namespace sph
