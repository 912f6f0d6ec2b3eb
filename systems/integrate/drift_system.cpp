// Binned stepping's lazy drift: He et al. Alg. 2 lines 19-21 (x, v from the base state) and
// line 9 (rho from its slope, He eq. 5; p from Tait, He eq. 2) evaluated for the rows a step
// reads (drift_system.hpp states the contract).
#include "systems/integrate/drift_system.hpp"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <atomic>
#include <functional>
#include <numeric>

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"
#include "systems/density/density_kernels.hpp"
#include "systems/integrate/drift.hpp"

namespace sph {

namespace {

/// Rows per task of the streaming passes.
constexpr std::size_t kGrain = 4096;

}  // namespace

void drift_fluid(World& w) {
    ComponentStore& s = w.fluid.store;
    auto x = s.get(comp::position);
    auto v = s.get(comp::velocity);
    auto rho = s.get(comp::density);
    auto p = s.get(comp::pressure);
    const auto x0 = s.get(comp::position_last);
    const auto v0 = s.get(comp::velocity_last);
    const auto rho0 = s.get(comp::density_last);
    const auto a = s.get(comp::acceleration);
    const auto drho = s.get(comp::drho_dt);
    const auto t_last = s.get(comp::t_last);
    const Tick now = w.clock.t_ticks;
    const Real rest = w.physics.rest_density, b = w.physics.tait_b;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x.size(), kGrain), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            if (t_last[i] == now) continue;
            const Real dt = drift_interval(now, t_last[i]);
            v[i] = drifted_velocity(v0[i], a[i], dt);
            x[i] = drifted_position(x0[i], v[i], dt);
            rho[i] = drifted_density(rho0[i], drho[i], dt);
            p[i] = tait_pressure(rho[i], rest, b);
        }
    });
}

// ---- drift ------------------------------------------------------------------------------------

void place_every_row(std::span<Vec3> x, std::span<const Vec3> x0, std::span<const Vec3> v0, std::span<const Vec3> a,
                     std::span<const std::int64_t> t_last, Tick now) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x.size(), kGrain), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i)
            if (t_last[i] != now) x[i] = position_at(now, t_last[i], x0[i], v0[i], a[i]);
    });
}

Access DriftSystem::access() const {
    Access acc = Access()
        .read(fluid(comp::position_last), fluid(comp::velocity_last), fluid(comp::acceleration), fluid(comp::t_last))
        .write(fluid(comp::position));
    if (m_rows == Rows::AroundDue) acc.read(res::fluid_grid, res::active_set).write(res::placed).rows(res::placed);
    return acc;
}

void DriftSystem::register_components(World& w) {
    // The base state at t_last = 0 is the initial state (t_last is 0 until a row is evaluated,
    // and a row whose t_last is the clock's time holds x = x_last, v = v_last: what
    // BoundaryNeighbourSystem's from_base reads at the first step).
    const bool fresh = !w.fluid.store.has(comp::position_last.name);
    w.fluid.store.add(comp::position_last);
    w.fluid.store.add(comp::velocity_last);
    if (fresh) {
        const auto x = w.fluid.store.get(comp::position);
        const auto v = w.fluid.store.get(comp::velocity);
        std::copy(x.begin(), x.end(), w.fluid.store.get(comp::position_last).begin());
        std::copy(v.begin(), v.end(), w.fluid.store.get(comp::velocity_last).begin());
    }
    w.fluid.store.add(comp::density_last);
    w.fluid.store.add(comp::drho_dt);
    w.fluid.store.add(comp::t_last);
    w.fluid.store.add(comp::acceleration);
    w.synchronise = drift_fluid;
}

void DriftSystem::run(Context& ctx) {
    auto x = ctx.write(fluid(comp::position));
    const auto x0 = ctx.read(fluid(comp::position_last));
    const auto v0 = ctx.read(fluid(comp::velocity_last));
    const auto a = ctx.read(fluid(comp::acceleration));
    const auto t_last = ctx.read(fluid(comp::t_last));
    const Tick now = ctx.clock().t_ticks;
    if (m_rows == Rows::Every) {
        place_every_row(x, x0, v0, a, t_last, now);
        return;
    }
    auto& placed = ctx.write(res::placed);
    placed.clear();  // FluidGridSystem's list, checked when it ran
    const UniformGrid& grid = ctx.read(res::fluid_grid);
    // A grid built this step: FluidGridSystem placed every row.
    if (grid.drift() == 0) return;
    auto place = [&](std::size_t i) {
        if (t_last[i] != now) x[i] = position_at(now, t_last[i], x0[i], v0[i], a[i]);
    };
    // Each due row (its current cell decides which cells its search reads), then the cells
    // within h + drift of it (FluidNeighbourSystem's reach against a kept grid, the ranges of
    // UniformGrid::ranges_within), each cell once.
    const auto& set = ctx.read(res::active_set);
    const Real reach = Real(ctx.physics().h) + grid.drift();
    const std::size_t n = x.size();
    const auto limit = std::size_t(kStreamShare * double(n));
    m_cell_mark.resize(grid.cell_count(), 0);
    m_cells.clear();
    std::size_t rows = 0;
    for (std::size_t k = 0; k < set.size() && rows < limit; ++k) {
        place(set[k]);
        const Eigen::Vector3i lo = grid.cell_coords(x[set[k]] - Vec3::Constant(reach));
        const Eigen::Vector3i hi = grid.cell_coords(x[set[k]] + Vec3::Constant(reach));
        for (int cz = lo[2]; cz <= hi[2]; ++cz)
            for (int cy = lo[1]; cy <= hi[1]; ++cy) {
                const std::int64_t row = grid.cell_index({0, cy, cz});
                for (std::int64_t c = row + lo[0]; c <= row + hi[0]; ++c) {
                    if (m_cell_mark[std::size_t(c)]) continue;
                    m_cell_mark[std::size_t(c)] = 1;
                    m_cells.push_back(c);
                    rows += grid.cell_start(c + 1) - grid.cell_start(c);
                }
            }
    }
    for (std::int64_t c : m_cells) m_cell_mark[std::size_t(c)] = 0;
    if (rows >= limit) {
        // A large share of the fluid (scattered due rows): every row, streamed, costs less.
        place_every_row(x, x0, v0, a, t_last, now);
        placed.resize(n);
        std::iota(placed.begin(), placed.end(), Index(0));
        return;
    }
    // By cell in ascending order (the rows of a cell are contiguous slots; the order makes the
    // list, and so the engine's check of it, deterministic), in parallel over the cells.
    std::sort(m_cells.begin(), m_cells.end());
    const auto slots = grid.sorted_index();
    placed.resize(rows);
    m_offset.resize(m_cells.size() + 1);
    m_offset[0] = 0;
    for (std::size_t k = 0; k < m_cells.size(); ++k)
        m_offset[k + 1] = m_offset[k] + (grid.cell_start(m_cells[k] + 1) - grid.cell_start(m_cells[k]));
    auto place_cells = [&](std::size_t b, std::size_t e) {
        for (std::size_t k = b; k < e; ++k) {
            Index out = m_offset[k];
            for (Index s = grid.cell_start(m_cells[k]), s_end = grid.cell_start(m_cells[k] + 1); s < s_end; ++s) {
                place(slots[s]);
                placed[out++] = slots[s];
            }
        }
    };
    if (rows < kParallelRows) {
        place_cells(0, m_cells.size());
        return;
    }
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m_cells.size(), 64),
                      [&](const auto& r) { place_cells(r.begin(), r.end()); });
}

// ---- drift_rows -------------------------------------------------------------------------------

Access DriftRowsSystem::access() const {
    Access acc = Access()
        .read(fluid(comp::velocity_last), fluid(comp::acceleration), fluid(comp::t_last), fluid(comp::density_last),
              fluid(comp::drho_dt))
        .read(res::active_set)
        .read_if(!m_all, res::fluid_neighbours)
        .write(fluid(comp::velocity), fluid(comp::density), fluid(comp::pressure), res::drifted);
    if (!m_all) acc.rows(res::drifted);
    return acc;
}

void DriftRowsSystem::register_components(World& w) {
    w.fluid.store.add(comp::density);
    w.fluid.store.add(comp::pressure);
}

void DriftRowsSystem::run(Context& ctx) {
    auto v = ctx.write(fluid(comp::velocity));
    auto rho = ctx.write(fluid(comp::density));
    auto p = ctx.write(fluid(comp::pressure));
    const auto v0 = ctx.read(fluid(comp::velocity_last));
    const auto a = ctx.read(fluid(comp::acceleration));
    const auto t_last = ctx.read(fluid(comp::t_last));
    const auto rho0 = ctx.read(fluid(comp::density_last));
    const auto drho = ctx.read(fluid(comp::drho_dt));
    auto& rows = ctx.write(res::drifted);
    const Tick now = ctx.clock().t_ticks;
    const Real rest = ctx.physics().rest_density, b = ctx.physics().tait_b;
    auto drift = [&](std::size_t i) {
        if (t_last[i] == now) return;
        const Real dt = drift_interval(now, t_last[i]);
        v[i] = drifted_velocity(v0[i], a[i], dt);
        rho[i] = drifted_density(rho0[i], drho[i], dt);
        p[i] = tait_pressure(rho[i], rest, b);
    };
    auto drift_velocity = [&](std::size_t i) {
        if (t_last[i] != now) v[i] = drifted_velocity(v0[i], a[i], drift_interval(now, t_last[i]));
    };
    rows.clear();
    const std::size_t n = v.size();
    const auto& set = ctx.read(res::active_set);
    // Every row, in one streaming pass (clearing the claim marks when `marked`).
    auto stream = [&](bool velocity_only, bool marked) {
        rows.resize(n);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, kGrain), [&](const auto& r) {
            std::iota(rows.begin() + std::ptrdiff_t(r.begin()), rows.begin() + std::ptrdiff_t(r.end()), Index(r.begin()));
            if (velocity_only)
                for (std::size_t i = r.begin(); i < r.end(); ++i) drift_velocity(i);
            else
                for (std::size_t i = r.begin(); i < r.end(); ++i) drift(i);
            if (marked) std::fill(m_mark.begin() + std::ptrdiff_t(r.begin()), m_mark.begin() + std::ptrdiff_t(r.end()), 0);
        });
    };
    // Every row evaluated with the summation density: the density system sums rho and p of
    // each anew, so only the velocity is read before that.
    const bool velocity_only = m_summed && set.size() == n;
    if (m_all || velocity_only || kStreamRows * set.size() >= n) {
        // From n / kStreamRows active rows on, their lists reach most rows even where the active
        // rows lie together, and marking them costs more than streaming through all.
        stream(velocity_only, false);
        return;
    }
    // The active rows and their fluid neighbours, each once and ascending.
    const NeighbourLists& lists = ctx.read(res::fluid_neighbours);
    m_mark.resize(n, 0);
    if (set.size() <= 64) {
        // A handful (a fine bin's step): one task, no atomics.
        for (Index i : set) {
            if (!m_mark[i]) rows.push_back(i), m_mark[i] = 1;
            for (Index j : lists.of(i))
                if (!m_mark[j]) rows.push_back(j), m_mark[j] = 1;
        }
        std::sort(rows.begin(), rows.end());
        for (Index i : rows) {
            drift(i);
            m_mark[i] = 0;
        }
        return;
    }
    // More: mark (a relaxed byte store: no read-modify-write), count the marks (a byte a row),
    // then drift the marked rows in one scan of the marks (a byte a row, cheaper than sorting
    // the claims once they are thousands), or, when they are kStreamMarked of the rows or more
    // (scattered active rows: up to 30 or 40 neighbours each), every row streamed.
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, set.size(), 256), [&](const auto& r) {
        for (std::size_t k = r.begin(); k < r.end(); ++k) {
            std::atomic_ref<std::uint8_t>(m_mark[set[k]]).store(1, std::memory_order_relaxed);
            for (Index j : lists.of(set[k])) std::atomic_ref<std::uint8_t>(m_mark[j]).store(1, std::memory_order_relaxed);
        }
    });
    constexpr std::size_t kChunk = 16384;
    const std::size_t chunks = (n + kChunk - 1) / kChunk;
    const std::size_t marked = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, n, kChunk), std::size_t(0),
        [&](const auto& r, std::size_t sum) {
            for (std::size_t i = r.begin(); i < r.end(); ++i) sum += m_mark[i];
            return sum;
        },
        std::plus<>());
    if (double(marked) >= kStreamMarked * double(n)) {
        stream(false, true);
        return;
    }
    std::vector<std::vector<Index>> parts(chunks);
    tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t c) {
        auto& out = parts[c];
        for (std::size_t i = c * kChunk, e = std::min(n, i + kChunk); i < e; ++i) {
            if (!m_mark[i]) continue;
            m_mark[i] = 0;
            drift(i);
            out.push_back(Index(i));
        }
    });
    for (const auto& part : parts) rows.insert(rows.end(), part.begin(), part.end());
}

}  // namespace sph
