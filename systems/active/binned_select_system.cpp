// Binned stepping: the active set from the due-time buckets (SWIFT's integer activity test,
// `ti_end == ti_current`, here per particle and without a scan of all particles).
#include "systems/active/binned_select_system.hpp"

#include <algorithm>
#include <numeric>

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"
#include "systems/timestep/binned_state.hpp"

namespace sph {

namespace {

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
    } else {
        for (Index i : set) active[i] = 0;  // the last step's flags
    }
    set.clear();
    if (ctx.clock().t_ticks == ticks_of(tl, tl.next)) {
        tl.now = tl.next;
        if (auto it = buckets.due.find(tl.now); it != buckets.due.end()) {
            for (Index i : it->second)
                if (ti_end[i] == tl.now && !active[i]) {
                    active[i] = 1;
                    set.push_back(i);
                }
            buckets.due.erase(it);
        }
        // Each row is in the set once, so a set of n rows is every row: 0..n-1 without the merge.
        if (set.size() == n)
            std::iota(set.begin(), set.end(), Index(0));
        else
            sort_runs(set);
    }
    ctx.write(counter::active) = set.size();
}

}  // namespace sph
