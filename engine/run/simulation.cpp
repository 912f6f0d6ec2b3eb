#include "engine/run/simulation.hpp"

#include <chrono>

#include <tbb/blocked_range.h>
#include <spdlog/spdlog.h>
#include <tbb/parallel_reduce.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <sstream>
#include <tuple>
#include <type_traits>

#if defined(__SSE2__)
#include <emmintrin.h>  // the domain check's block test (RealBox::any_outside)
#endif

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

/// Rows per task of the checks, and rows per branch-free block inside a task: a block is
/// tested without an early exit (so the compiler can keep it in vector registers) and only a
/// block that holds an offender is searched row by row.
constexpr std::size_t kCheckGrain = 8192, kCheckBlock = 256;

/// Whether any of `count` floats (or doubles) from p is not finite: its exponent bits all set.
/// A test on the bits, which the compiler vectorises (std::isfinite compiles to one scalar
/// compare per value): the every-row checks stream whole columns.
template <class F>
bool any_non_finite(const F* p, std::size_t count) {
    using Bits = std::conditional_t<sizeof(F) == 4, std::uint32_t, std::uint64_t>;
    constexpr Bits exponent = sizeof(F) == 4 ? Bits(0x7f800000u) : Bits(0x7ff0000000000000ull);
    Bits bad = 0;
    for (std::size_t k = 0; k < count; ++k) {
        Bits bits;
        std::memcpy(&bits, p + k, sizeof(F));
        bad |= Bits((bits & exponent) == exponent);
    }
    return bad != 0;
}

bool finite(Real v) { return std::isfinite(v); }
bool finite(double v) { return std::isfinite(v); }
bool finite(const Vec3& v) { return std::isfinite(v[0]) & std::isfinite(v[1]) & std::isfinite(v[2]); }
bool finite(const Mat3& m) { return finite(Vec3(m.col(0))) & finite(Vec3(m.col(1))) & finite(Vec3(m.col(2))); }

/// The first row, by position in `rows` (ascending, so also the lowest index) or by index when
/// `rows` is null, at which `bad(i)` holds; n (the column's length) when none does. With every
/// row, `block_bad(b, e)` (when given) says whether rows [b, e) may hold one, by a vectorised
/// test; only a block it flags is searched with `bad`.
template <class Bad, class BlockBad = std::nullptr_t>
std::size_t first_row(std::size_t n, const std::vector<Index>* rows, Bad bad, BlockBad block_bad = nullptr) {
    const std::size_t m = rows ? rows->size() : n;
    const auto row = [&](std::size_t k) { return rows ? std::size_t((*rows)[k]) : k; };
    const std::size_t k = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, m, kCheckGrain), m,
        [&](const auto& r, std::size_t best) {
            for (std::size_t b = r.begin(); b < r.end() && b < best; b += kCheckBlock) {
                const std::size_t e = std::min(r.end(), b + kCheckBlock);
                const auto scan = [&] {
                    bool any = false;
                    for (std::size_t k = b; k < e; ++k) any |= bad(row(k));
                    return any;
                };
                bool any;
                if constexpr (std::is_same_v<BlockBad, std::nullptr_t>)
                    any = scan();
                else
                    any = rows ? scan() : block_bad(b, e);
                if (!any) continue;
                for (std::size_t k = b; k < e; ++k)
                    if (bad(row(k))) return std::min(best, k);
            }
            return best;
        },
        [](std::size_t a, std::size_t b) { return std::min(a, b); });
    return k == m ? n : row(k);
}

/// The domain in single precision, so that a Real position is tested without a conversion:
/// lo is the smallest float >= the double bound and hi the largest <= it, which makes
/// x >= lo exactly when double(x) >= min (Aabb::contains), and likewise for hi.
struct RealBox {
    Vec3 lo, hi;
    explicit RealBox(const Aabb& d) {
        constexpr Real inf = std::numeric_limits<Real>::infinity();
        for (int a = 0; a < 3; ++a) {
            lo[a] = Real(d.min[a]);
            if (double(lo[a]) < d.min[a]) lo[a] = std::nextafter(lo[a], inf);
            hi[a] = Real(d.max[a]);
            if (double(hi[a]) > d.max[a]) hi[a] = std::nextafter(hi[a], -inf);
        }
    }
    /// False for a non-finite position too (every comparison with NaN is false).
    bool contains(const Vec3& x) const {
        return (x[0] >= lo[0]) & (x[0] <= hi[0]) & (x[1] >= lo[1]) & (x[1] <= hi[1]) & (x[2] >= lo[2]) &
               (x[2] <= hi[2]);
    }
    /// Whether any of the `count` positions from p (x, y, z packed) is outside or not finite.
    /// With SSE2 (every x86-64) four positions, twelve values, at a time in three vectors
    /// against the bounds repeated (the compiler does not vectorise this loop itself); then the
    /// rest one by one.
    bool any_outside(const Vec3* p, std::size_t count) const {
        std::size_t k = 0;
        bool bad = false;
#if defined(__SSE2__) && !defined(SPH_DOUBLE)
        const Real* f = p->data();
        const __m128 lo_a = _mm_setr_ps(lo[0], lo[1], lo[2], lo[0]), lo_b = _mm_setr_ps(lo[1], lo[2], lo[0], lo[1]),
                     lo_c = _mm_setr_ps(lo[2], lo[0], lo[1], lo[2]);
        const __m128 hi_a = _mm_setr_ps(hi[0], hi[1], hi[2], hi[0]), hi_b = _mm_setr_ps(hi[1], hi[2], hi[0], hi[1]),
                     hi_c = _mm_setr_ps(hi[2], hi[0], hi[1], hi[2]);
        __m128 out = _mm_setzero_ps();
        // Outside: below lo, above hi, or unordered (NaN); an infinity is below or above.
        const auto test = [](__m128 x, __m128 l, __m128 h) {
            return _mm_or_ps(_mm_or_ps(_mm_cmplt_ps(x, l), _mm_cmpgt_ps(x, h)), _mm_cmpunord_ps(x, x));
        };
        for (; k + 4 <= count; k += 4) {
            const Real* q = f + 3 * k;
            out = _mm_or_ps(out, test(_mm_loadu_ps(q), lo_a, hi_a));
            out = _mm_or_ps(out, test(_mm_loadu_ps(q + 4), lo_b, hi_b));
            out = _mm_or_ps(out, test(_mm_loadu_ps(q + 8), lo_c, hi_c));
        }
        bad = _mm_movemask_ps(out) != 0;
#endif
        for (; k < count; ++k) bad |= !contains(p[k]);
        return bad;
    }
};

}  // namespace

void Simulation::trace_non_finite(std::size_t system) {
    // A streaming read of the columns just written, on the rows written (a few per cent of a
    // sparse step), and what lets a NaN be reported with the system that produced it rather
    // than the one that carried it, and a particle that left the domain with the system that
    // moved it.
    const ComponentStore& store = m_world.fluid.store;
    const Access& access = m_graph->access(system);
    // A system that declares its rows (Access::rows) is checked there only.
    const std::vector<Index>* rows = nullptr;
    if (access.written_rows() == key_of(res::active_set)) rows = &m_world.active_set;
    if (access.written_rows() == key_of(res::collided)) rows = &m_world.collided;
    if (access.written_rows() == key_of(res::drifted)) rows = &m_world.drifted;
    if (access.written_rows() == key_of(res::placed)) rows = &m_world.placed;
    if (access.written_rows() == key_of(res::stepped)) rows = &m_world.stepped;
    const std::size_t n = store.size();
    // A row list names each row at most once (Access::rows), so n of them are every row: read
    // in order, without the index.
    if (rows != nullptr && rows->size() == n) rows = nullptr;
    // Recipe order is a topological order of the graph: a value can only reach a later system,
    // so the earliest one with a non-finite output is where it was produced.
    auto record = [&](Fault& f, std::size_t particle, const std::string& col, const Vec3& position = Vec3::Zero()) {
        std::lock_guard lock(m_trace_mutex);
        if (system < f.system) f = Fault{system, particle, col, position};
    };
    for (const auto& wr : access.writes()) {
        if (wr.rfind("fluid.", 0) != 0 || access.is_copy(wr)) continue;
        const std::string col = wr.substr(6);
        if (!store.has(col)) continue;
        const std::type_info& t = store.type_of(col);
        std::size_t bad = n;
        if (col == comp::position.name) {
            // One read for both checks: a position outside the domain or not finite.
            const auto x = store.get(comp::position);
            const RealBox box(m_world.domain);
            bad = first_row(n, rows, [&](std::size_t i) { return !box.contains(x[i]); },
                            [&](std::size_t b, std::size_t e) { return box.any_outside(x.data() + b, e - b); });
            if (bad == n) continue;
            if (finite(x[bad])) {
                record(m_outside, bad, col, x[bad]);
                // A non-finite position further on outranks it (the rare path: a second read).
                bad = first_row(n, rows, [&](std::size_t i) { return !finite(x[i]); });
                if (bad == n) continue;
            }
        } else if (t == typeid(Vec3)) {
            const auto v = store.get(Component<Vec3>{col});
            bad = first_row(n, rows, [&](std::size_t i) { return !finite(v[i]); },
                            [&](std::size_t b, std::size_t e) { return any_non_finite(v[b].data(), 3 * (e - b)); });
        } else if (t == typeid(Mat3)) {  // the kernel-gradient correction L_i
            const auto v = store.get(Component<Mat3>{col});
            bad = first_row(n, rows, [&](std::size_t i) { return !finite(v[i]); },
                            [&](std::size_t b, std::size_t e) { return any_non_finite(v[b].data(), 9 * (e - b)); });
        } else if (t == typeid(Real)) {
            const auto v = store.get(Component<Real>{col});
            bad = first_row(n, rows, [&](std::size_t i) { return !finite(v[i]); },
                            [&](std::size_t b, std::size_t e) { return any_non_finite(v.data() + b, e - b); });
        } else if (t == typeid(double)) {
            const auto v = store.get(Component<double>{col});
            bad = first_row(n, rows, [&](std::size_t i) { return !finite(v[i]); },
                            [&](std::size_t b, std::size_t e) { return any_non_finite(v.data() + b, e - b); });
        }
        if (bad == n) continue;
        record(m_non_finite, bad, col);
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
    // Lists that are kept across steps (the slab layout: individual stepping reuses inactive
    // particles' lists) follow the permutation, fluid->fluid entries renumbered as well. The
    // compact layout is rebuilt by every step before any system reads it (a binned subset
    // build empties the blocks of the rows it last queried, which the old numbering names), so
    // it is left as it is: renumbering it cost more than the rest of the sort.
    if (!m_world.fluid_neighbours.compact()) m_world.fluid_neighbours.permute(perm, true);
    if (!m_world.boundary_neighbours.compact()) m_world.boundary_neighbours.permute(perm, false);
}

bool Simulation::sort_due() const {
    const SimulationParams& sim = m_world.scene.simulation;
    if (sim.sort_interval <= 0) return false;
    // A per-particle step (binned, individual) evaluates the rows that are due, often a few in
    // a thousand, and the order decays with the motion of the rows evaluated: sorting every
    // sort_interval steps would re-sort (and rebuild the grid for) a fluid that has barely moved.
    if (sim.stepping.mode == SteppingMode::Binned || sim.stepping.mode == SteppingMode::Individual)
        return m_world.clock.step == 0 ||
               m_world.clock.rows_since_sort >= std::uint64_t(sim.sort_interval) * m_world.fluid.size();
    return m_world.clock.step % sim.sort_interval == 0;
}

void Simulation::step() {
    step_once();
    if (m_sync_observers) synchronise();
}

void Simulation::step_once() {
    m_sort_seconds = 0;
    m_sorted = sort_due();
    if (m_sorted) {
        const auto t0 = std::chrono::steady_clock::now();
        spatial_sort();
        m_world.clock.rows_since_sort = 0;
        m_sort_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    }
    if (m_ring) m_ring->save(m_world);
    m_non_finite = m_outside = Fault{};
    m_graph->run();
    m_behind = bool(m_world.synchronise);  // a lazy recipe leaves the sleeping rows behind
    m_last = StepRecord{m_world.clock.step, m_world.clock.t, m_world.step_size.dt, m_world.step_size.dt_stable, false};
    if (m_ring && m_world.rollback.request_dt > 0) {
        serve_rollback();
        return;
    }
    check_step();
    m_world.clock.rows_since_sort += m_world.counter_value(counter::active.name);
    m_world.clock.t_ticks += m_world.step_size.dt_ticks;
    m_world.clock.t = to_seconds(m_world.clock.t_ticks);
    ++m_world.clock.step;
}

void Simulation::forget_history() {
    if (m_ring) m_ring->clear();
    m_restored_at = m_world.clock.step;
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
    const std::size_t went = m_ring->restore(m_world, m_rollback_steps);
    if (went < m_rollback_steps && m_restored_at >= 0)
        spdlog::warn("step {}: a rollback of {} steps reached {} (the run resumed from a checkpoint at step {}, which "
                     "holds one state); from here the run may differ from an uninterrupted one",
                     discarded.step, m_rollback_steps, went, m_restored_at);
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
    // The rows each system wrote were checked when it ran (trace_non_finite): every position
    // written is finite and inside the domain, every other column written is finite. What
    // remains is the step size.
    World& w = m_world;
    const double dt = w.step_size.dt;
    const auto& st = w.scene.simulation.stepping;
    const auto& systems = m_graph->systems();
    const std::size_t n = w.fluid.store.size();
    const auto id_of = [&](std::size_t row) {
        return w.fluid.store.has(comp::id.name) ? w.fluid.store.get(comp::id)[row] : std::uint32_t(row);
    };
    std::ostringstream os;
    if (m_non_finite.system < systems.size()) {
        // Non-finite: the earliest system (in recipe order) whose output held a non-finite
        // value produced it; that value's particle is the one named.
        const std::string culprit = systems[m_non_finite.system]->name();
        const std::uint32_t pid = id_of(m_non_finite.particle);
        os << "particle " << pid << " became non-finite at step " << w.clock.step << " (t = " << w.clock.t
           << " s): " << m_non_finite.column << " is NaN or infinite, first produced by system '" << culprit << "'";
        throw SimulationError(os.str(), pid, w.clock.step, culprit);
    }
    if (m_outside.system < systems.size()) {
        // Left the domain: named with the system that moved it there.
        const std::string culprit = systems[m_outside.system]->name();
        const std::uint32_t id = id_of(m_outside.particle);
        const Vec3 x = m_outside.position;
        const Aabb& d = w.domain;
        os << "particle " << id << " left the domain at step " << w.clock.step << " (t = " << w.clock.t
           << " s): position (" << x.transpose() << ") is outside [" << d.min.transpose() << "] - ["
           << d.max.transpose() << "], moved by system '" << culprit << "'";
        throw SimulationError(os.str(), id, w.clock.step, culprit);
    }
    const double stable = w.step_size.dt_stable > 0 ? w.step_size.dt_stable : dt;  // a clipped last step is fine
    if (stable >= st.dt_min && std::isfinite(dt)) return;
    os << "time step collapsed at step " << w.clock.step << " (t = " << w.clock.t << " s): dt = " << stable
       << " s from system '" << step_size_owner() << "' is below dt_min = " << st.dt_min << " s; ";
    // What can limit a step, each with its own figure (a sound speed that is too high is not an
    // acceleration problem, and with no particle there is no particle to name).
    if (n == 0) {
        os << "there is no fluid particle yet, so no particle's velocity or acceleration limits it: the "
              "scene's own figures do (gravity "
           << w.physics.gravity.norm() << " m/s^2, speed of sound " << w.physics.speed_of_sound
           << " m/s, h / c_s = " << w.physics.h / w.physics.speed_of_sound << " s)";
    } else {
        os << "the fastest particle moves at v_max = " << w.stats.v_max << " m/s, the largest acceleration is "
           << w.stats.a_max << " m/s^2 at particle " << w.stats.a_max_particle << ", the speed of sound is "
           << w.physics.speed_of_sound << " m/s (h / c_s = " << w.physics.h / w.physics.speed_of_sound << " s)";
    }
    throw SimulationError(os.str(), w.stats.a_max_particle, w.clock.step, step_size_owner());
}

}  // namespace sph
