// Adami, Hu & Adams 2012 ("A generalized wall boundary condition for smoothed particle
// hydrodynamics", J. Comput. Phys. 231), eq. 27 for the boundary particles' pressure: see the header.
#include "systems/boundary/wall_pressure_system.hpp"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"

namespace sph {

Access WallPressureSystem::access() const {
    return Access()
        .read(fluid(comp::position), fluid(comp::density), fluid(comp::pressure), res::boundary_neighbours,
              boundary(comp::position))
        .read_if(m_individual, res::active_set, res::fluid_grid)
        .write(boundary(comp::pressure), boundary(comp::density));
}

void WallPressureSystem::register_components(World& w) {
    w.boundary.store.add(comp::pressure);
    w.boundary.store.add(comp::density);
}

void WallPressureSystem::run(Context& ctx) {
    const auto x = ctx.read(fluid(comp::position));
    const auto rho = ctx.read(fluid(comp::density));
    const auto p = ctx.read(fluid(comp::pressure));
    const auto xb = ctx.read(boundary(comp::position));
    auto pb = ctx.write(boundary(comp::pressure));
    auto rhob = ctx.write(boundary(comp::density));
    const NeighbourLists& lists = ctx.read(res::boundary_neighbours);
    // The grid: only the per-particle modes' gather around the active rows' walls reads it.
    const UniformGrid* grid = m_individual ? &ctx.read(res::fluid_grid) : nullptr;
    const Physics& ph = ctx.physics();
    const CubicSpline& kernel = ctx.kernel();
    const Real h2 = ph.h * ph.h, rho0 = ph.rest_density, b_eos = ph.tait_b;
    const Vec3 g = ph.gravity;
    const std::vector<Index>* active = m_individual ? &ctx.read(res::active_set) : nullptr;

    const Real inv_sigma = Real(1) / kernel.sigma();
    auto finish = [&](Index b, Real num, Real den) {
        const Real pressure = den > 0 ? std::max(num / den, Real(0)) : Real(0);
        pb[b] = pressure;
        rhob[b] = rho0 * std::pow(pressure / b_eos + Real(1), Real(1) / Real(7));
    };
    // One pair's terms of eq. 27: the weight W_bf / sigma and (p_f + rho_f g . (x_b - x_f)) times it.
    auto weight = [&](Real r2) { return kernel.w(std::sqrt(r2)) * inv_sigma; };
    auto term = [&](Index f, const Vec3& at, Real w) { return (p[f] + rho[f] * g.dot(at - x[f])) * w; };
    // A boundary row is claimed once per step (an atomic byte) by the worker that lists it first.
    m_mark.resize(xb.size(), 0);
    for (auto& part : m_found) part.clear();
    auto claim = [&](Index b, std::vector<Index>& mine) {
        std::atomic_ref<std::uint8_t> mark(m_mark[b]);
        if (mark.load(std::memory_order_relaxed) == 0 && mark.exchange(1, std::memory_order_relaxed) == 0)
            mine.push_back(b);
    };

    if (!active) {
        // Every fluid row is evaluated, so the fluid rows' boundary lists hold every pair within h:
        // each pair adds its terms to b's sums. The sums are fixed-point integers (W / sigma <= 1,
        // so |term| <= |p| + rho |g| h; 2^-24 Pa and 2^-32 of a full weight per unit), which makes
        // them exact and independent of the order the workers add them in.
        m_num.resize(xb.size(), 0);
        m_den.resize(xb.size(), 0);
        constexpr double kNum = 16777216.0, kDen = 4294967296.0;  // 2^24, 2^32
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x.size(), 512), [&](const auto& r) {
            std::vector<Index>& mine = m_found.local();
            for (std::size_t i = r.begin(); i < r.end(); ++i)
                for (Index b : lists.of(Index(i))) {
                    claim(b, mine);  // every listed row is written, whatever its distance: forces read them all
                    const Real r2 = (xb[b] - x[i]).squaredNorm();
                    if (r2 >= h2) continue;
                    const Real w = weight(r2);
                    const Real t = term(Index(i), xb[b], w);
                    std::atomic_ref<std::int64_t>(m_num[b]).fetch_add(std::llround(double(t) * kNum), std::memory_order_relaxed);
                    std::atomic_ref<std::int64_t>(m_den[b]).fetch_add(std::llround(double(w) * kDen), std::memory_order_relaxed);
                }
        });
        for (const std::vector<Index>& part : m_found)
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, part.size(), 512), [&](const auto& r) {
                for (std::size_t k = r.begin(); k < r.end(); ++k) {
                    const Index b = part[k];
                    finish(b, Real(double(m_num[b]) / kNum), Real(double(m_den[b]) / kDen));
                    m_num[b] = m_den[b] = 0;
                    m_mark[b] = 0;
                }
            });
        return;
    }

    // Per-particle modes: the rows in the active rows' lists (claimed, then sorted), each summed over
    // the fluid grid, since a sleeping row's list is not current.
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, active->size(), 512), [&](const auto& r) {
        std::vector<Index>& mine = m_found.local();
        for (std::size_t k = r.begin(); k < r.end(); ++k)
            for (Index b : lists.of((*active)[k])) claim(b, mine);
    });
    m_rows.clear();
    for (const std::vector<Index>& part : m_found) m_rows.insert(m_rows.end(), part.begin(), part.end());
    std::sort(m_rows.begin(), m_rows.end());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m_rows.size(), 256), [&](const auto& r) {
        for (std::size_t k = r.begin(); k < r.end(); ++k) {
            const Index b = m_rows[k];
            m_mark[b] = 0;
            const Vec3 at = xb[b];
            Real num = 0, den = 0;
            grid->for_each_candidate(at, x, [&](Index f, const Vec3& xf) {
                const Real r2 = (at - xf).squaredNorm();
                if (r2 >= h2) return;
                const Real w = weight(r2);
                num += term(f, at, w);
                den += w;
            });
            finish(b, num, den);
        }
    });
}

}  // namespace sph
