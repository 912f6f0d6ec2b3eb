// He et al. Alg. 2 line 16: Delta t_i = min_j Delta t_j^raw (j over the neighbours of i and i
// itself), for the active particles and their halo (He sec. 2.3: lines 9 and 16 are needed only
// for neighbours of active particles).
#include "systems/timestep/dt_propagation_system.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <limits>
#include <span>

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"

namespace sph {

namespace {

constexpr double kNone = std::numeric_limits<double>::infinity();

/// min(init, min_j values[j]) over a list, in four independent chains (a single chain waits on
/// each minimum in turn); equal to the sequential minimum, since no value is NaN.
double min_over(std::span<const Index> list, std::span<const double> values, double init) {
    double m0 = init, m1 = init, m2 = init, m3 = init;
    std::size_t k = 0;
    for (; k + 4 <= list.size(); k += 4) {
        m0 = std::min(m0, values[list[k]]);
        m1 = std::min(m1, values[list[k + 1]]);
        m2 = std::min(m2, values[list[k + 2]]);
        m3 = std::min(m3, values[list[k + 3]]);
    }
    for (; k < list.size(); ++k) m0 = std::min(m0, values[list[k]]);
    return std::min(std::min(m0, m1), std::min(m2, m3));
}

/// Rows ahead whose list is fetched early: the lists of a scattered subset of rows stream from
/// beyond the core's own cache, and the loops over them do too little per entry to hide that.
constexpr std::size_t kAhead = 4;
void prefetch_list(const NeighbourLists& lists, Index i) {
    const auto l = lists.of(i);
    const char* p = reinterpret_cast<const char*>(l.data());
    __builtin_prefetch(p);
    __builtin_prefetch(p + 64);
}

}  // namespace

Access DtPropagationSystem::access() const {
    return Access()
        .read(res::active_set, res::fluid_neighbours, fluid(comp::active), fluid(comp::dt_raw))
        .write(fluid(comp::dt), res::halo_set, counter::propagation_updates);
}

void DtPropagationSystem::register_components(World& w) {
    w.fluid.store.add(comp::active);
    w.fluid.store.add(comp::dt);
    w.fluid.store.add(comp::dt_raw);
}

void DtPropagationSystem::run(Context& ctx) {
    const auto dt_raw = ctx.read(fluid(comp::dt_raw));
    const auto active = ctx.read(fluid(comp::active));
    auto dt = ctx.write(fluid(comp::dt));
    const auto& set = ctx.read(res::active_set);
    const NeighbourLists& lists = ctx.read(res::fluid_neighbours);
    auto& halo = ctx.write(res::halo_set);
    const std::size_t n = dt.size(), na = set.size();
    halo.clear();
    if (na == n) {  // everyone active (global-equivalent steps): no halo, no scatter
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 512), [&](const auto& r) {
            for (std::size_t i = r.begin(); i < r.end(); ++i) dt[i] = min_over(lists.of(Index(i)), dt_raw, dt_raw[i]);
        });
        ctx.write(counter::propagation_updates) = n;
        return;
    }
    // The active particles, in one pass over their fresh lists: each gathers its own minimum,
    // and every neighbour j takes min(reach_j, own Delta t^raw) in the worker's own array (no
    // branch on the neighbour's state, no atomics, no cache line shared between workers).
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, na, 256), [&](const auto& r) {
        auto& reach = m_reach.local();
        if (reach.size() != n) reach.assign(n, kNone);
        for (std::size_t k = r.begin(); k < r.end(); ++k) {
            const Index i = set[k];
            if (k + kAhead < r.end()) prefetch_list(lists, set[k + kAhead]);
            const double mine = dt_raw[i];
            double m = mine;
            for (Index j : lists.of(i)) {
                m = std::min(m, dt_raw[j]);
                reach[j] = std::min(reach[j], mine);
            }
            dt[i] = m;
        }
    });
    // The halo: reached and inactive, ascending (one streaming pass over a value per particle
    // and worker; He's scheme selects its active set by a pass over every particle anyway).
    std::vector<double*> reaches;
    for (auto& r : m_reach)
        if (r.size() == n) reaches.push_back(r.data());
    const auto reached = [&](std::size_t i) {
        double m = kNone;
        for (const double* r : reaches) m = std::min(m, r[i]);
        return m;
    };
    halo = collect_indices(n, [&](std::size_t i) { return (reached(i) < kNone) & (active[i] == 0); });
    // The halo over its own lists (from its last evaluation), which may miss an active particle
    // that now reaches it: hence the reached minimum as the start. Then every reached row's
    // entries are reset (the halo's here, the active rows' below).
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, halo.size(), 512), [&](const auto& r) {
        for (std::size_t k = r.begin(); k < r.end(); ++k) {
            const Index j = halo[k];
            if (k + kAhead < r.end()) prefetch_list(lists, halo[k + kAhead]);
            dt[j] = min_over(lists.of(j), dt_raw, std::min(dt_raw[j], reached(j)));
            for (double* w : reaches) w[j] = kNone;
        }
    });
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, na, 4096), [&](const auto& r) {
        for (std::size_t k = r.begin(); k < r.end(); ++k)
            for (double* w : reaches) w[set[k]] = kNone;
    });
    ctx.write(counter::propagation_updates) = na + halo.size();
}

}  // namespace sph
