// Binned stepping: the active set from the due-time buckets (SWIFT's integer activity test,
// `ti_end == ti_current`, here per particle and without a scan of all particles).
#include "systems/active/binned_select_system.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"
#include "systems/active/select_active_system.hpp"
#include "systems/timestep/binned_state.hpp"

namespace sph {

namespace {

/// From this many rows the last step's flags are cleared in parallel.
constexpr std::size_t kManyRows = 4096;
constexpr std::size_t kGrain = 4096;
constexpr std::size_t kScanChunk = 16384;

/// Sorts a sequence made of a few ascending runs (a bucket is appended to once per step that
/// files into it) by merging neighbouring runs: O(n log runs).
void sort_runs(std::vector<Index>& v) {
    std::vector<std::size_t> cuts{0};
    for (std::size_t k = 1; k < v.size(); ++k)
        if (v[k] < v[k - 1]) cuts.push_back(k);
    cuts.push_back(v.size());
    while (cuts.size() > 2) {
        std::vector<std::size_t> next{0};
        for (std::size_t r = 0; r + 2 < cuts.size(); r += 2) {
            std::inplace_merge(v.begin() + cuts[r], v.begin() + cuts[r + 1], v.begin() + cuts[r + 2]);
            next.push_back(cuts[r + 2]);
        }
        if (cuts.size() % 2 == 0) next.push_back(cuts.back());
        cuts.swap(next);
    }
}

}  // namespace

Access BinnedSelectSystem::access() const {
    return Access()
        .read(fluid(comp::position), fluid(comp::dt), res::moving_bodies)
        .write(fluid(comp::bin), fluid(comp::ti_end), fluid(comp::active), res::bin_timeline, res::due_buckets,
               res::active_set, counter::active);
}

void BinnedSelectSystem::register_components(World& w) {
    w.fluid.store.add(comp::bin);
    w.fluid.store.add(comp::ti_end);
    w.fluid.store.add(comp::dt);
    w.fluid.store.add(comp::t_last);
    w.fluid.store.add(comp::active);
    w.resources.add<BinTimeline>(res::bin_timeline.name, Lifetime::Kept) = BinTimeline::for_range(m_dt_min, m_dt_max);
    w.resources.add<DueBuckets>(res::due_buckets.name, Lifetime::Scratch);
}

void BinnedSelectSystem::run(Context& ctx) {
    auto bin = ctx.write(fluid(comp::bin));
    auto ti_end = ctx.write(fluid(comp::ti_end));
    auto active = ctx.write(fluid(comp::active));
    BinTimeline& tl = ctx.write(res::bin_timeline);
    DueBuckets& buckets = ctx.write(res::due_buckets);
    auto& set = ctx.write(res::active_set);
    const std::size_t n = ti_end.size();
    const std::uint64_t layout = ctx.layout(SetId::Fluid);
    if (buckets.layout != layout) {
        // Rows were reordered, added or restored: index the buckets anew. A row whose end lies
        // before the planned due time is new (an emitted particle, or the first step): it is
        // due then, on the largest bin that time allows.
        // A live end lies in (now, now + 2^bin], where a bin has one multiple of its step, so
        // there are at most max_bin + 1 distinct ends: found by a short linear search.
        buckets.due.clear();
        std::fill(active.begin(), active.end(), std::uint8_t(0));
        std::vector<std::pair<std::uint64_t, std::vector<Index>>> by_end;
        std::size_t last = 0;
        for (std::size_t i = 0; i < n; ++i) {
            if (ti_end[i] < tl.next) {
                ti_end[i] = tl.next;
                bin[i] = std::uint8_t(BinTimeline::largest_aligned_bin(tl.next, tl.max_bin));
            }
            if (last >= by_end.size() || by_end[last].first != ti_end[i]) {
                last = 0;
                while (last < by_end.size() && by_end[last].first != ti_end[i]) ++last;
                if (last == by_end.size()) by_end.emplace_back(ti_end[i], std::vector<Index>{});
            }
            by_end[last].second.push_back(Index(i));
        }
        for (auto& [end, rows] : by_end) buckets.due.emplace(end, std::move(rows));
        const auto [lo, hi] = std::minmax_element(bin.begin(), bin.end());
        buckets.bin_lo = n ? *lo : 0;
        buckets.bin_hi = n ? *hi : 0;
        buckets.layout = layout;
    } else if (set.size() < kManyRows) {
        for (Index i : set) active[i] = 0;  // the last step's flags
    } else {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, set.size(), kGrain), [&](const auto& r) {
            for (std::size_t k = r.begin(); k < r.end(); ++k) active[set[k]] = 0;
        });
    }
    set.clear();
    if (ctx.clock().t_ticks != ticks_of(tl, tl.next)) {
        ctx.write(counter::active) = 0;
        return;
    }
    tl.now = tl.next;
    const auto due = buckets.due.find(tl.now);
    const std::size_t filed = due == buckets.due.end() ? 0 : due->second.size();
    const auto& bodies = ctx.read(res::moving_bodies);
    const int top = BinTimeline::largest_aligned_bin(tl.now, tl.max_bin);
    if (16 * filed < n && bodies.empty()) {
        // Under 1/16 of the rows: the bucket's ascending runs, merged (O(rows log runs), no pass
        // over every row).
        if (filed) {
            for (Index i : due->second)
                if (ti_end[i] == tl.now && !active[i]) {
                    active[i] = 1;
                    set.push_back(i);
                }
        }
        sort_runs(set);
    } else {
        // A large share of the rows, or a scan of every row for the moving bodies anyway: flag
        // the due rows (a relaxed byte store; a row filed twice stores the same 1), then one
        // parallel scan of the flags collects the set ascending, in place of the serial merge
        // of the bucket's runs.
        if (filed) {
            const auto& rows = due->second;
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rows.size(), kGrain), [&](const auto& r) {
                for (std::size_t k = r.begin(); k < r.end(); ++k)
                    if (ti_end[rows[k]] == tl.now)
                        std::atomic_ref<std::uint8_t>(active[rows[k]]).store(1, std::memory_order_relaxed);
            });
        }
        // The same pass tests the other rows against the moving bodies: a row within reach is
        // due now (its step so far ends here), on the largest bin `now` allows; its entry at
        // the old end goes stale. Rows are independent, so chunks run in parallel, each
        // collecting its rows ascending.
        const bool near_bodies = !bodies.empty();
        const auto x = near_bodies ? ctx.read(fluid(comp::position)) : std::span<const Vec3>{};
        const auto dt = near_bodies ? ctx.read(fluid(comp::dt)) : std::span<const double>{};
        const Real h = ctx.physics().h;
        const std::size_t chunks = (n + kScanChunk - 1) / kScanChunk;
        std::vector<std::vector<Index>> parts(chunks);
        std::vector<int> lowest(chunks, buckets.bin_lo);
        tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t c) {
            auto& out = parts[c];
            for (std::size_t i = c * kScanChunk, e = std::min(n, i + kScanChunk); i < e; ++i) {
                if (active[i]) {
                    out.push_back(Index(i));
                } else if (near_bodies && near_moving_body(bodies, x[i], dt[i], h)) {
                    ti_end[i] = tl.now;
                    bin[i] = std::uint8_t(std::min<int>(bin[i], top));
                    lowest[c] = std::min<int>(lowest[c], bin[i]);
                    active[i] = 1;
                    out.push_back(Index(i));
                }
            }
        });
        for (std::size_t c = 0; c < chunks; ++c) {
            set.insert(set.end(), parts[c].begin(), parts[c].end());
            buckets.bin_lo = std::min(buckets.bin_lo, lowest[c]);
        }
    }
    if (filed) buckets.due.erase(due);
    ctx.write(counter::active) = set.size();
}

}  // namespace sph
