// Binned stepping: raw bins, the neighbour limiter (at most kLimiterSpan = 2 bins, a 4x step;
// Saitoh & Makino 2009), wake-up, and the next due time (binned_step_system.hpp states the rules).
#include "systems/timestep/binned_step_system.hpp"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <limits>

#include "engine/core/grid.hpp"
#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"
#include "systems/timestep/binned_state.hpp"

namespace sph {

Access BinnedStepSystem::access() const {
    return Access()
        .read(res::active_set, res::fluid_neighbours, res::fluid_grid, fluid(comp::dt_raw), fluid(comp::active))
        .write(fluid(comp::bin), fluid(comp::ti_end), fluid(comp::dt), res::bin_timeline, res::due_buckets,
               res::dt, res::drift_bound, res::stepped, counter::woken, counter::limiter_passes,
               counter::limiter_rows)
        .rows(res::stepped);
}

void BinnedStepSystem::register_components(World& w) {
    w.fluid.store.add(comp::bin);
    w.fluid.store.add(comp::ti_end);
    w.fluid.store.add(comp::dt);
    w.fluid.store.add(comp::dt_raw);
    w.resources.add<DriftBound>(res::drift_bound.name, Lifetime::Scratch);
}

namespace {

/// Rows per task: a few thousand integer gathers, so small active sets run in one task.
constexpr std::size_t kGrain = 2048;

/// Lowers an 8-bit value to at most `v`; true when it changed.
bool atomic_lower(std::uint8_t& target, std::uint8_t v) {
    std::atomic_ref<std::uint8_t> a(target);
    std::uint8_t cur = a.load(std::memory_order_relaxed);
    while (v < cur)
        if (a.compare_exchange_weak(cur, v, std::memory_order_relaxed)) return true;
    return false;
}

/// Per cell of `grid`: the bins of its rows folded by `fold` from `init` (init when empty): the
/// smallest with std::min and 255, the largest with std::max and 0.
template <class Fold>
void cell_bounds(const UniformGrid& grid, std::span<const std::uint8_t> bin, std::uint8_t init, Fold fold,
                 std::vector<std::uint8_t>& out) {
    out.resize(grid.cell_count());
    const auto slots = grid.sorted_index();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, out.size(), 4096), [&](const auto& r) {
        Index s = grid.cell_start(std::int64_t(r.begin()));
        for (std::size_t c = r.begin(); c < r.end(); ++c) {
            const Index e = grid.cell_start(std::int64_t(c + 1));
            std::uint8_t v = init;
            for (; s < e; ++s) v = fold(v, bin[slots[s]]);
            out[c] = v;
        }
    });
}

/// `out[c]` = `in` folded by `fold` over the 3 x 3 x 3 cells around c (clamped at the grid's
/// faces), separably: along x, then y, then z, each pass one sequential read of the cells
/// (`tmp` holds the middle pass). A max (min) is the largest (smallest) over the block.
template <class Fold>
void fold_blocks(const Eigen::Vector3i& d, const std::vector<std::uint8_t>& in, Fold fold, std::vector<std::uint8_t>& tmp,
                 std::vector<std::uint8_t>& out) {
    const std::size_t nx = std::size_t(d[0]), ny = std::size_t(d[1]), nz = std::size_t(d[2]);
    tmp.resize(in.size());
    out.resize(in.size());
    if (in.empty()) return;
    const std::size_t lines = ny * nz, grain = std::max<std::size_t>(1, 4096 / nx);
    // x: within each line of cells.
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, lines, grain), [&](const auto& r) {
        for (std::size_t l = r.begin(); l < r.end(); ++l) {
            const std::uint8_t* a = in.data() + l * nx;
            std::uint8_t* o = out.data() + l * nx;
            for (std::size_t x = 0; x < nx; ++x) {
                std::uint8_t v = a[x];
                if (x > 0) v = fold(v, a[x - 1]);
                if (x + 1 < nx) v = fold(v, a[x + 1]);
                o[x] = v;
            }
        }
    });
    // y, then z: a line folded with its neighbour lines, element by element.
    const auto across = [&](const std::vector<std::uint8_t>& src, std::vector<std::uint8_t>& dst, std::size_t stride,
                            std::size_t extent, std::size_t period) {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, lines, grain), [&](const auto& r) {
            for (std::size_t l = r.begin(); l < r.end(); ++l) {
                const std::size_t pos = l / period % extent;  // the line's y (period 1) or z (period ny)
                const std::uint8_t* a = src.data() + l * nx;
                const std::uint8_t* below = pos > 0 ? a - stride : a;
                const std::uint8_t* above = pos + 1 < extent ? a + stride : a;
                std::uint8_t* o = dst.data() + l * nx;
                for (std::size_t x = 0; x < nx; ++x) o[x] = fold(fold(a[x], below[x]), above[x]);
            }
        });
    };
    across(out, tmp, nx, ny, 1);
    across(tmp, out, nx * ny, nz, ny);
}

/// Per cell of `grid`: the bins of the rows in its 3 x 3 x 3 block folded by `fold` from `init`
/// (cell_bounds, then fold_blocks; `cell` and `tmp` are scratch).
template <class Fold>
void block_bounds(const UniformGrid& grid, std::span<const std::uint8_t> bin, std::uint8_t init, Fold fold,
                  std::vector<std::uint8_t>& cell, std::vector<std::uint8_t>& tmp, std::vector<std::uint8_t>& out) {
    cell_bounds(grid, bin, init, fold, cell);
    fold_blocks(grid.dims(), cell, fold, tmp, out);
}

/// The rows i with keep(i, B) into `rows`, B = block[cell of i]: a cell bound folded over the 27
/// cells around i's (fold_blocks; every row within a fresh grid's search of i lies in them). A
/// cell whose B fails `may` (no row of any bin could be kept) is not read.
template <class May, class Keep>
void rows_by_cell(const UniformGrid& grid, const std::vector<std::uint8_t>& block, May may, Keep keep,
                  std::vector<Index>& rows) {
    const auto slots = grid.sorted_index();
    tbb::enumerable_thread_specific<std::vector<Index>> found;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, grid.cell_count(), 4096), [&](const auto& r) {
        auto& out = found.local();
        Index k = grid.cell_start(std::int64_t(r.begin()));
        for (std::size_t c = r.begin(); c < r.end(); ++c) {
            const Index e = grid.cell_start(std::int64_t(c + 1));
            const int v = block[c];
            if (!may(v)) {
                k = e;
                continue;
            }
            for (; k < e; ++k)
                if (keep(slots[k], v)) out.push_back(slots[k]);
        }
    });
    rows.clear();
    for (auto& v : found) rows.insert(rows.end(), v.begin(), v.end());
}

constexpr auto kMin = [](std::uint8_t a, std::uint8_t b) { return std::min(a, b); };
constexpr auto kMax = [](std::uint8_t a, std::uint8_t b) { return std::max(a, b); };

}  // namespace

void BinnedStepSystem::run(Context& ctx) {
    const auto& set = ctx.read(res::active_set);
    const NeighbourLists& lists = ctx.read(res::fluid_neighbours);
    const auto dt_raw = ctx.read(fluid(comp::dt_raw));
    const auto active = ctx.read(fluid(comp::active));
    auto bin = ctx.write(fluid(comp::bin));
    auto ti_end = ctx.write(fluid(comp::ti_end));
    auto dt = ctx.write(fluid(comp::dt));
    BinTimeline& tl = ctx.write(res::bin_timeline);
    DueBuckets& buckets = ctx.write(res::due_buckets);
    StepSize& s = ctx.write(res::dt);
    auto& stepped = ctx.write(res::stepped);
    stepped.clear();
    std::uint64_t woken_count = 0, passes = 0, visited = 0;
    constexpr int span = kLimiterSpan;
    double raw_hi = 0;  // the longest Delta t_i^raw of the step
    if (!set.empty()) {
        // The stable step of this step: the shortest Delta t_i^raw evaluated (checked against
        // dt_min by the engine, which names this system when it collapses).
        struct Range {
            double lo, hi;
        };
        const Range raw = tbb::parallel_reduce(
            tbb::blocked_range<std::size_t>(0, set.size(), kGrain),
            Range{std::numeric_limits<double>::infinity(), 0.0},
            [&](const auto& r, Range m) {
                for (std::size_t k = r.begin(); k < r.end(); ++k) {
                    m.lo = std::min(m.lo, dt_raw[set[k]]);
                    m.hi = std::max(m.hi, dt_raw[set[k]]);
                }
                return m;
            },
            [](Range a, Range b) { return Range{std::min(a.lo, b.lo), std::max(a.hi, b.hi)}; });
        s.dt_stable = raw.lo;
        raw_hi = raw.hi;
        // 0. Every particle due: no step is in flight, so the timeline starts afresh here with
        // a bin near the shortest step (BinTimeline::rebased).
        if (set.size() == bin.size() && m_headroom > 0) {
            const double headroom = raw.hi < 2 * raw.lo ? 1.0 : m_headroom;
            tl = BinTimeline::rebased(raw.lo, headroom, m_dt_min, m_dt_max, ctx.clock().t_ticks);
            buckets.due.clear();
            buckets.bin_lo = tl.max_bin;
            buckets.bin_hi = 0;
        }
        // The drift bound (binned_state.hpp): reset when every row is evaluated, else widened.
        DriftBound& drift = ctx.write(res::drift_bound);
        const std::uint64_t members = ctx.membership(SetId::Fluid);
        if (set.size() == bin.size()) {
            drift.shortest_raw = raw.lo;
            drift.quantum = tl.quantum;
            drift.membership = members;
            drift.reset_at = ctx.clock().t_ticks;
        } else if (drift.membership == members) {
            drift.shortest_raw = std::min(drift.shortest_raw, raw.lo);
            drift.quantum = std::max(drift.quantum, tl.quantum);
        }
    }
    const std::uint64_t now = tl.now;
    if (!set.empty()) {
        // 1. Raw bins, with the growth rule (at t = 0 every bin is aligned and any is allowed),
        // and the rows that can break the rule: the limiter pulls at bin_i > lo + 2 (every bin
        // is >= lo); the wake-up visits bin_i + 2 < hi (every bin is <= hi) and every row the
        // limiter may lower (with every row due: the rows that can bound others, below). A row
        // held back by the growth rule keeps a bin >= its old one, so lo = min(old bound, bin
        // of the shortest raw step) bounds every bin from below. The order of either list does
        // not change the result.
        buckets.bin_lo = std::min(buckets.bin_lo, tl.bin_for(s.dt_stable));
        const int lo = buckets.bin_lo, hi = buckets.bin_hi;
        // Every row active: no row sleeps (nothing to wake) and every list is built, so j is in
        // i's list exactly when i is in j's (the same squared distance). The limiter then pushes
        // from the rows that can bound a neighbour (bin_j + 2 below the largest raw bin, which
        // bounds every new bin) instead of pulling at every row above lo + 2.
        const bool dense = set.size() == bin.size();
        const int hi_raw = dense ? tl.bin_for(raw_hi) : 0;
        // A grid built this step from every row (no drift) places each row in its cell, and every
        // list entry of a row lies in the 27 cells around it: the smallest and largest bin of those
        // cells bound its neighbours' bins, so only a row more than 2 above the smallest can break
        // the limiter's rule and only one more than 2 below the largest can have a neighbour to
        // wake. On such steps (with at most kCellsPerRow cells a row) the rows to visit are found
        // by two passes over the cells instead of from the bounds on all bins, which at He's
        // lambda let nearly every row through: with every row due the limiter's, and with
        // kWakeByCellsShare of the rows or more the wake-up's (below it the passes cost more than
        // the list reads they spare: docs/results/benchmarks.md).
        const UniformGrid& grid = ctx.read(res::fluid_grid);
        const bool fresh = grid.drift() == 0 && grid.particle_count() == bin.size() &&
                           double(grid.cell_count()) <= kCellsPerRow * double(bin.size());
        const bool wake_by_cells = !dense && fresh && double(set.size()) >= kWakeByCellsShare * double(bin.size());
        tbb::enumerable_thread_specific<std::vector<Index>> limit_rows, wake_rows;
        std::atomic<int> lowest{BinTimeline::kMaxBin};  // the smallest new bin (every row due)
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, set.size(), kGrain), [&](const auto& r) {
            auto& lim = limit_rows.local();
            auto& wak = wake_rows.local();
            int low = BinTimeline::kMaxBin;
            for (std::size_t k = r.begin(); k < r.end(); ++k) {
                const Index i = set[k];
                int b = tl.bin_for(dt_raw[i]);
                if (now > 0) {
                    const int old = bin[i];
                    if (b > old) b = BinTimeline::aligned(now, old + 1) ? old + 1 : old;
                }
                bin[i] = std::uint8_t(b);
                if (dense) {
                    low = std::min(low, b);
                    if (!fresh && b + span < hi_raw) lim.push_back(i);
                    continue;
                }
                const bool limited = b > lo + span;
                if (limited) lim.push_back(i);
                if (!wake_by_cells && (limited || b + span < hi)) wak.push_back(i);
            }
            for (int cur = lowest.load(std::memory_order_relaxed);
                 low < cur && !lowest.compare_exchange_weak(cur, low, std::memory_order_relaxed);) {
            }
        });
        // Every row due: each new bin lies in [lowest, hi_raw] (a bin is at most its raw one), so
        // when that span is at most 2 no pair can break the limiter's rule and there is nothing
        // to do (at lambda_c 0.8 on dam_break_obstacles, every such step: docs/results/benchmarks.md).
        const bool by_cells = dense && fresh && hi_raw > lowest.load() + span;
        m_limit.clear();
        m_wake.clear();
        for (auto& v : limit_rows) m_limit.insert(m_limit.end(), v.begin(), v.end());
        for (auto& v : wake_rows) m_wake.insert(m_wake.end(), v.begin(), v.end());
        tbb::enumerable_thread_specific<std::vector<Index>> woken;
        // The limiter to its fixed point; true when it lowered a bin.
        auto limit = [&] {
            bool any_change = false;
            while (!m_limit.empty()) {
                ++passes;
                visited += m_limit.size();
                const bool changed = tbb::parallel_reduce(
                    tbb::blocked_range<std::size_t>(0, m_limit.size(), kGrain), false,
                    [&](const auto& r, bool any) {
                        for (std::size_t k = r.begin(); k < r.end(); ++k) {
                            const Index i = m_limit[k];
                            int lo = std::atomic_ref<std::uint8_t>(bin[i]).load(std::memory_order_relaxed);
                            for (Index j : lists.of(i)) {
                                const int bj = std::atomic_ref<std::uint8_t>(bin[j]).load(std::memory_order_relaxed);
                                lo = std::min(lo, bj + span);
                            }
                            any |= atomic_lower(bin[i], std::uint8_t(lo));
                        }
                        return any;
                    },
                    [](bool a, bool b) { return a || b; });
                if (!changed) break;
                any_change = true;
            }
            return any_change;
        };
        // One wake-up pass; true when it lowered a sleeping bin.
        auto wake = [&] {
            visited += m_wake.size();
            return !m_wake.empty() && tbb::parallel_reduce(
                tbb::blocked_range<std::size_t>(0, m_wake.size(), kGrain), false,
                [&](const auto& r, bool any) {
                    auto& out = woken.local();
                    for (std::size_t k = r.begin(); k < r.end(); ++k) {
                        const Index i = m_wake[k];
                        // Relaxed atomic loads: other tasks may lower these bins meanwhile (a
                        // row is in several lists); the passes repeat to the fixed point.
                        const auto load = [&](Index r) {
                            return int(std::atomic_ref<std::uint8_t>(bin[r]).load(std::memory_order_relaxed));
                        };
                        const int cap = load(i) + span;
                        for (Index j : lists.of(i))
                            // An active j never exceeds cap (the limiter's fixed point), so
                            // the activity flag is read only for the rare candidates.
                            if (load(j) > cap && !active[j] && atomic_lower(bin[j], std::uint8_t(cap))) {
                                out.push_back(j);
                                any = true;
                            }
                    }
                    return any;
                },
                [](bool a, bool b) { return a || b; });
        };
        // Pushing: bin_i = min(bin_i, bin_j + 2) for every i in j's list, then again from the
        // rows that lowered and can still bound a neighbour. A row lowered while it pushes is
        // among those, so its final bin is pushed too: every pair ends within 2 bins, and as
        // bins only fall the fixed point is the one the pulling passes reach.
        auto push_limit = [&] {
            tbb::enumerable_thread_specific<std::vector<Index>> lowered;
            while (!m_limit.empty()) {
                ++passes;
                visited += m_limit.size();
                for (auto& v : lowered) v.clear();
                tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m_limit.size(), kGrain), [&](const auto& r) {
                    auto& out = lowered.local();
                    for (std::size_t k = r.begin(); k < r.end(); ++k) {
                        const Index j = m_limit[k];
                        const int cap = std::atomic_ref<std::uint8_t>(bin[j]).load(std::memory_order_relaxed) + span;
                        for (Index i : lists.of(j))
                            if (atomic_lower(bin[i], std::uint8_t(cap)) && cap + span < hi_raw) out.push_back(i);
                    }
                });
                m_limit.clear();
                for (auto& v : lowered) m_limit.insert(m_limit.end(), v.begin(), v.end());
            }
        };
        // Otherwise: wake-up leaves the active bins as they are, so after it only a limiter pass
        // that changes an active bin (bounded by a newly lowered sleeping one) calls for another.
        if (by_cells) {
            // Pulled at the rows above their cells' lower bound + 2: bin_i = min(bin_i, bin_j + 2)
            // over i's list, at the bins of the moment; a row lowered here pushes below, so every
            // pair ends within 2 bins (the bounds need not hold once bins fall: what falls pushes).
            block_bounds(grid, bin, 255, kMin, m_cell, m_block_tmp, m_block);
            rows_by_cell(
                grid, m_block, [&](int low) { return hi_raw > low + span; },
                [&](Index i, int low) { return bin[i] > low + span; }, m_pull);
            tbb::enumerable_thread_specific<std::vector<Index>> lowered;
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m_pull.size(), kGrain), [&](const auto& r) {
                auto& out = lowered.local();
                for (std::size_t k = r.begin(); k < r.end(); ++k) {
                    const Index i = m_pull[k];
                    int low = std::atomic_ref<std::uint8_t>(bin[i]).load(std::memory_order_relaxed);
                    for (Index j : lists.of(i)) {
                        const int bj = std::atomic_ref<std::uint8_t>(bin[j]).load(std::memory_order_relaxed);
                        low = std::min(low, bj + span);
                    }
                    if (atomic_lower(bin[i], std::uint8_t(low)) && low + span < hi_raw) out.push_back(i);
                }
            });
            if (!m_pull.empty()) ++passes;
            visited += m_pull.size();
            m_limit.clear();
            for (auto& v : lowered) m_limit.insert(m_limit.end(), v.begin(), v.end());
            push_limit();
        } else if (dense) {
            push_limit();
        } else {
            if (wake_by_cells)  // an upper bound from here on: bins only fall
                block_bounds(grid, bin, 0, kMax, m_cell, m_block_tmp, m_block);
            limit();
            for (;;) {
                if (wake_by_cells)  // the only active rows with a neighbour the wake-up may lower
                    rows_by_cell(
                        grid, m_block, [&](int high) { return lo + span < high; },
                        [&](Index i, int high) { return active[i] && bin[i] + span < high; }, m_wake);
                if (!wake() || !limit()) break;
            }
        }
        // 4. New ends. Active particles: a whole step of their bin from now, filed by bin in
        // ascending row order: each fixed chunk of the set counts its rows per bin, and then
        // writes them at its offset in the bin's bucket (at most max_bin + 1 buckets touched,
        // each grown once). Woken ones: the first multiple of their new bin's step after now
        // (never after their old end).
        const std::size_t chunks = (set.size() + kGrain - 1) / kGrain;
        constexpr std::size_t kBins = BinTimeline::kMaxBin + 1;
        m_counts.assign(chunks * kBins, 0);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, chunks), [&](const auto& r) {
            for (std::size_t ch = r.begin(); ch < r.end(); ++ch) {
                Index* count = m_counts.data() + ch * kBins;
                for (std::size_t k = ch * kGrain, e = std::min(set.size(), k + kGrain); k < e; ++k) {
                    const Index i = set[k];
                    const int b = bin[i];
                    ti_end[i] = now + BinTimeline::length(b);
                    dt[i] = tl.seconds(BinTimeline::length(b));
                    ++count[b];
                }
            }
        });
        // Each chunk's first slot per bin (the counts become offsets), and the buckets grown.
        std::array<Index*, kBins> bucket{};
        for (std::size_t b = 0; b < kBins; ++b) {
            Index total = 0;
            for (std::size_t ch = 0; ch < chunks; ++ch) {
                const Index c = m_counts[ch * kBins + b];
                m_counts[ch * kBins + b] = total;
                total += c;
            }
            if (total == 0) continue;
            buckets.bin_hi = std::max(buckets.bin_hi, int(b));
            auto& v = buckets.due[now + BinTimeline::length(int(b))];
            const std::size_t base = v.size();
            v.resize(base + total);
            bucket[b] = v.data() + base;
        }
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, chunks), [&](const auto& r) {
            for (std::size_t ch = r.begin(); ch < r.end(); ++ch) {
                Index* next = m_counts.data() + ch * kBins;
                for (std::size_t k = ch * kGrain, e = std::min(set.size(), k + kGrain); k < e; ++k) {
                    const int b = bin[set[k]];
                    bucket[std::size_t(b)][next[b]++] = set[k];
                }
            }
        });
        std::vector<Index> cut;
        for (auto& v : woken) cut.insert(cut.end(), v.begin(), v.end());
        std::sort(cut.begin(), cut.end());
        cut.erase(std::unique(cut.begin(), cut.end()), cut.end());
        // The rows whose Delta t_i is written here (the engine checks those only): the active
        // set and the woken rows, ascending and each once.
        stepped.resize(set.size() + cut.size());
        stepped.resize(std::size_t(std::set_union(set.begin(), set.end(), cut.begin(), cut.end(), stepped.begin()) -
                                   stepped.begin()));
        for (Index j : cut) {
            const std::uint64_t end = BinTimeline::next_aligned(now, bin[j]);
            dt[j] = tl.seconds(BinTimeline::length(bin[j]));
            if (end < ti_end[j]) {
                ti_end[j] = end;
                buckets.due[end].push_back(j);
                ++woken_count;
            }
        }
    }
    // The next due time: the earliest bucket holding a particle that is still due there.
    while (!buckets.due.empty()) {
        const auto it = buckets.due.begin();
        const auto& v = it->second;
        if (it->first > now && std::any_of(v.begin(), v.end(), [&](Index i) { return ti_end[i] == it->first; })) break;
        buckets.due.erase(it);
    }
    tl.next = buckets.due.empty() ? now + BinTimeline::length(tl.max_bin) : buckets.due.begin()->first;
    ctx.write(res::drift_bound).next_due = buckets.due.empty() ? 0 : buckets.due.begin()->second.size();
    const Tick ticks = std::max<Tick>(1, ticks_of(tl, tl.next) - ctx.clock().t_ticks);
    s.set_clipped(2 * to_seconds(ticks), ticks, ctx.clock());
    ctx.write(counter::woken) = woken_count;
    ctx.write(counter::limiter_passes) = passes;
    ctx.write(counter::limiter_rows) = visited;
}

}  // namespace sph
