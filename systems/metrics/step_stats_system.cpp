#include "systems/metrics/step_stats_system.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <cmath>

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"

namespace sph {

Access StepStatsSystem::access() const {
    return Access()
        .read(fluid(comp::density), fluid(comp::velocity), fluid(comp::acceleration), res::fluid_neighbours)
        .write(res::stats, counter::updated, counter::neighbour_pairs)
        .read_if(m_individual, res::active_set, counter::active)
        .read_if(m_individual && m_rows == Rows::All, fluid(comp::active))  // binned reads its set, not the flag
        .write_if(!m_individual, counter::active);
}

namespace {
struct Acc {
    double err_sum = 0, err_max = 0, v2_max = 0, a2_max = 0, v_sum = 0;
    Index a_arg = 0;
    std::uint64_t pairs = 0;
};
}  // namespace

void StepStatsSystem::run(Context& ctx) {
    const auto rho = ctx.read(fluid(comp::density));
    const auto v = ctx.read(fluid(comp::velocity));
    const auto a = ctx.read(fluid(comp::acceleration));
    const double rho0 = ctx.physics().rest_density;
    const NeighbourLists& lists = ctx.read(res::fluid_neighbours);
    // Individual stepping: neighbour pairs and the updated count are those of the active set.
    // Over the active set every row read is active, so the flag is only read over all rows.
    const std::vector<Index>* rows = m_rows == Rows::Active ? &ctx.read(res::active_set) : nullptr;
    const std::uint8_t* is_active = m_individual && !rows ? ctx.read(fluid(comp::active)).data() : nullptr;
    // A set of every row is 0..n-1 (the set is ascending and unique): read it as every row,
    // the same sums in the same order without the gather.
    if (rows && rows->size() == rho.size()) rows = nullptr;
    const std::size_t n = rows ? rows->size() : rho.size();
    // Deterministic reduction: the same sums whatever the thread count.
    const Acc r = tbb::parallel_deterministic_reduce(
        tbb::blocked_range<std::size_t>(0, n, 1024), Acc{},
        [&](const auto& range, Acc acc) {
            for (std::size_t k = range.begin(); k < range.end(); ++k) {
                const std::size_t i = rows ? (*rows)[k] : k;
                const double e = std::max(0.0, double(rho[i]) / rho0 - 1.0);
                acc.err_sum += e;
                acc.err_max = std::max(acc.err_max, e);
                const double v2 = v[i].squaredNorm();
                acc.v2_max = std::max(acc.v2_max, v2);
                acc.v_sum += std::sqrt(v2);
                const double a2 = a[i].squaredNorm();
                if (a2 > acc.a2_max || (a2 == acc.a2_max && Index(i) < acc.a_arg)) {
                    acc.a2_max = a2;
                    acc.a_arg = Index(i);
                }
                // Branch-free: the active flag is scattered (a branch on it mispredicts often).
                if (i < lists.rows())
                    acc.pairs += is_active ? lists.size_of(Index(i)) * std::uint64_t(is_active[i] != 0)
                                           : lists.size_of(Index(i));
            }
            return acc;
        },
        [](Acc x, const Acc& y) {
            x.err_sum += y.err_sum;
            x.err_max = std::max(x.err_max, y.err_max);
            x.v2_max = std::max(x.v2_max, y.v2_max);
            x.v_sum += y.v_sum;
            if (y.a2_max > x.a2_max) {
                x.a2_max = y.a2_max;
                x.a_arg = y.a_arg;
            }
            x.pairs += y.pairs;
            return x;
        });
    StepStats& s = ctx.write(res::stats);
    s.rho_err_avg = n ? r.err_sum / double(n) : 0.0;
    s.rho_err_max = r.err_max;
    s.v_max = std::sqrt(r.v2_max);
    s.v_mean = n ? r.v_sum / double(n) : 0.0;
    s.a_max = std::sqrt(r.a2_max);
    s.a_max_particle = r.a_arg;
    s.whole_fluid = rows == nullptr;
    ctx.write(counter::updated) = m_individual ? ctx.read(counter::active) : n;
    if (!m_individual) ctx.write(counter::active) = n;
    ctx.write(counter::neighbour_pairs) = r.pairs;
}

}  // namespace sph
