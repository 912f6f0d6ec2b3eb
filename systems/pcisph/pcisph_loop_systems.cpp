// The prediction-correction loop of PCISPH (Solenthaler & Pajarola 2009) as in Ihmsen et al.
// 2010 Alg. 2, and the integration after it.
//  * predict:   v* = v + dt (g + a^{v,st} + F^p/m), x* = x + dt v*              (Alg. 2)
//  * density:   rho*_i = sum_j m_j W(x*_ij) [+ sum_b m_b W(x*_i - x_b)]          (eq. 2 / 13)
//               p_i += delta (rho*_i - rho0), kept >= 0                          (eq. 3)
//  * boundary:  rho*_b = sum_b' m_b' W_bb' + 2 sum_j m_j W(x_b - x*_j)           (eq. 13, see below)
//  * pressure:  F^p_i/m_i = -sum_j m_j (p_i/rho*_i^2 + p_j/rho*_j^2) grad W_ij
//                           -sum_b m_b (p_i/rho*_i^2 + p_b/rho*_b^2) grad W_ib   (eq. 6)
//  * integrate: v(t+dt) = v + dt a, x(t+dt) = x + dt v(t+dt)                      (Euler-Cromer)
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"
#include "systems/pcisph/pcisph_kernels.hpp"
#include "systems/pcisph/pcisph_state.hpp"
#include "systems/pcisph/pcisph_systems.hpp"

namespace sph {

namespace {
constexpr ColumnRef<Vec3> x_pred = fluid(comp::predicted_position);
}

// ---- predict ----

Access PcisphPredictSystem::access() const {
    return Access()
        .read(fluid(comp::position), fluid(comp::velocity), fluid(comp::pressure_acceleration), res::dt)
        .write(x_pred)
        .read_if(m_nonpressure, fluid(comp::nonpressure_acceleration));
}

void PcisphPredictSystem::register_components(World& w) { w.fluid.store.add(comp::predicted_position); }

void PcisphPredictSystem::run(Context& ctx) {
    const auto x = ctx.read(fluid(comp::position));
    const auto v = ctx.read(fluid(comp::velocity));
    const auto ap = ctx.read(fluid(comp::pressure_acceleration));
    const std::span<const Vec3> anp =
        m_nonpressure ? ctx.read(fluid(comp::nonpressure_acceleration)) : std::span<const Vec3>{};
    auto xs = ctx.write(fluid(comp::predicted_position));
    const Real dt = Real(ctx.read(res::dt).dt);
    const Vec3 g = ctx.physics().gravity;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x.size(), 4096), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            Vec3 a = g + ap[i];
            if (!anp.empty()) a += anp[i];
            xs[i] = x[i] + dt * (v[i] + dt * a);
        }
    });
}

// ---- fluid density and pressure ----

Access PcisphDensitySystem::access() const {
    return Access()
        .read(x_pred, res::fluid_neighbours, res::pcisph_delta)
        .write(fluid(comp::density), fluid(comp::pressure), res::pcisph_errors)
        .read_if(m_ihmsen, res::boundary_neighbours, boundary(comp::position), boundary(comp::mass));
}

void PcisphDensitySystem::register_components(World& w) {
    w.fluid.store.add(comp::density);
    w.fluid.store.add(comp::pressure);
    w.resources.add<PcisphErrors>(res::pcisph_errors.name, Lifetime::Scratch);
}

namespace {
struct ErrAcc {
    double sum = 0, max = 0;
};
}  // namespace

void PcisphDensitySystem::run(Context& ctx) {
    const auto xs = ctx.read(fluid(comp::predicted_position));
    auto rho = ctx.write(fluid(comp::density));
    auto p = ctx.write(fluid(comp::pressure));
    const bool with_boundary = m_ihmsen && ctx.size(SetId::Boundary) > 0;
    const auto xb = with_boundary ? ctx.read(boundary(comp::position)) : std::span<const Vec3>{};
    const std::span<const Real> mb = with_boundary ? ctx.read(boundary(comp::mass)) : std::span<const Real>{};
    const NeighbourLists& fluid_nb = ctx.read(res::fluid_neighbours);
    const NeighbourLists* boundary_nb = with_boundary ? &ctx.read(res::boundary_neighbours) : nullptr;
    const CubicSpline& kernel = ctx.kernel();
    const Real m = ctx.physics().mass, rho0 = ctx.physics().rest_density, self = m * kernel.w(0);
    const Real delta = Real(ctx.read(res::pcisph_delta).delta);
    const std::size_t n = xs.size();
    const ErrAcc acc = tbb::parallel_deterministic_reduce(
        tbb::blocked_range<std::size_t>(0, n, 1024), ErrAcc{},
        [&](const auto& r, ErrAcc e) {
            for (std::size_t i = r.begin(); i < r.end(); ++i) {
                const Vec3 xi = xs[i];
                Real sum = 0;
                for (Index j : fluid_nb.of(Index(i))) sum += kernel.w((xi - xs[j]).norm());
                Real bsum = 0;
                if (with_boundary)
                    for (Index b : boundary_nb->of(Index(i))) bsum += mb[b] * kernel.w((xi - xb[b]).norm());
                const Real r_i = self + m * sum + bsum;  // eq. 13 (eq. 2 without the boundary)
                rho[i] = r_i;
                p[i] = pcisph_pressure_update(p[i], delta, r_i, rho0);  // eq. 3
                const double err = std::max(0.0, double(r_i) / double(rho0) - 1.0);
                e.sum += err;
                e.max = std::max(e.max, err);
            }
            return e;
        },
        [](ErrAcc a, const ErrAcc& b) {
            a.sum += b.sum;
            a.max = std::max(a.max, b.max);
            return a;
        });
    PcisphErrors& errors = ctx.write(res::pcisph_errors);
    errors.pred_err_max = acc.max;
    errors.pred_err_avg = n ? acc.sum / double(n) : 0.0;
}

// ---- boundary density and pressure ----
// A boundary is one particle layer thick, so a boundary particle sees fluid on one side only:
// the plain sum of eq. 13 stays near half of rho0 under fluid at rest and its pressure would
// never rise. We count the fluid term twice: mirrored across the boundary particle's tangent
// plane, each fluid neighbour j has an image at the same distance from x_b, which fills the
// empty half (the ghost-particle idea of sec. 2). Under fluid at rest on a flat wall rho*_b is
// then close to rho0 (test PcisphBoundary.RestDensityOnFlatWall), and p_b follows the
// compression of the fluid above it.

Access PcisphBoundaryDensitySystem::access() const {
    return Access()
        .read(x_pred, res::boundary_active, boundary(comp::position), boundary(comp::self_density), res::pcisph_delta)
        .write(boundary(comp::density), boundary(comp::pressure));
}

void PcisphBoundaryDensitySystem::register_components(World& w) {
    w.boundary.store.add(comp::density);
    w.boundary.store.add(comp::pressure);
}

void PcisphBoundaryDensitySystem::run(Context& ctx) {
    const auto xs = ctx.read(fluid(comp::predicted_position));
    const auto xb = ctx.read(boundary(comp::position));
    const auto self = ctx.read(boundary(comp::self_density));
    auto rho = ctx.write(boundary(comp::density));
    auto p = ctx.write(boundary(comp::pressure));
    const BoundaryActive& act = ctx.read(res::boundary_active);
    const CubicSpline& kernel = ctx.kernel();
    const Real m = ctx.physics().mass, rho0 = ctx.physics().rest_density;
    const Real delta = Real(ctx.read(res::pcisph_delta).delta);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, act.set.size(), 512), [&](const auto& r) {
        for (std::size_t k = r.begin(); k < r.end(); ++k) {
            const Index b = act.set[k];
            Real sum = 0;
            for (Index e = act.start[k]; e < act.start[k + 1]; ++e) sum += kernel.w((xb[b] - xs[act.fluid[e]]).norm());
            const Real r_b = self[b] + Real(2) * m * sum;
            rho[b] = r_b;
            p[b] = pcisph_pressure_update(p[b], delta, r_b, rho0);
        }
    });
}

// ---- pressure force ----

Access PcisphPressureForceSystem::access() const {
    return Access()
        .read(fluid(comp::position), fluid(comp::density), fluid(comp::pressure), res::fluid_neighbours)
        .write(fluid(comp::pressure_acceleration))
        .read_if(m_ihmsen, res::boundary_neighbours, boundary(comp::position), boundary(comp::mass),
                 boundary(comp::density), boundary(comp::pressure));
}

void PcisphPressureForceSystem::run(Context& ctx) {
    const auto x = ctx.read(fluid(comp::position));
    const auto rho = ctx.read(fluid(comp::density));
    const auto p = ctx.read(fluid(comp::pressure));
    auto ap = ctx.write(fluid(comp::pressure_acceleration));
    const bool with_boundary = m_ihmsen && ctx.size(SetId::Boundary) > 0;
    std::span<const Vec3> xb;
    std::span<const Real> mb, rhob, pb;
    const NeighbourLists& fluid_nb = ctx.read(res::fluid_neighbours);
    const NeighbourLists* boundary_nb = nullptr;
    if (with_boundary) {
        xb = ctx.read(boundary(comp::position));
        mb = ctx.read(boundary(comp::mass));
        rhob = ctx.read(boundary(comp::density));
        pb = ctx.read(boundary(comp::pressure));
        boundary_nb = &ctx.read(res::boundary_neighbours);
    }
    const CubicSpline& kernel = ctx.kernel();
    const Real m = ctx.physics().mass;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x.size(), 512), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            const Vec3 xi = x[i];
            const Real pi = p[i] / (rho[i] * rho[i]);
            Vec3 a = Vec3::Zero();
            for (Index j : fluid_nb.of(Index(i))) {
                const Real pj = p[j] / (rho[j] * rho[j]);
                if (pi == Real(0) && pj == Real(0)) continue;
                const Vec3 xij = xi - x[j];
                a -= (m * (pi + pj)) * kernel.grad(xij, xij.norm());
            }
            if (with_boundary)
                for (Index b : boundary_nb->of(Index(i))) {
                    const Real pbb = pb[b] / (rhob[b] * rhob[b]);
                    if (pi == Real(0) && pbb == Real(0)) continue;
                    const Vec3 xib = xi - xb[b];
                    a -= (mb[b] * (pi + pbb)) * kernel.grad(xib, xib.norm());
                }
            ap[i] = a;
        }
    });
}

// ---- integrate ----

Access PcisphIntegrateSystem::access() const {
    return Access()
        .read(fluid(comp::pressure_acceleration), res::dt)
        .write(fluid(comp::velocity), fluid(comp::position), fluid(comp::acceleration))
        .read_if(m_nonpressure, fluid(comp::nonpressure_acceleration));
}

void PcisphIntegrateSystem::register_components(World& w) { w.fluid.store.add(comp::acceleration); }

void PcisphIntegrateSystem::run(Context& ctx) {
    auto x = ctx.write(fluid(comp::position));
    auto v = ctx.write(fluid(comp::velocity));
    auto acc = ctx.write(fluid(comp::acceleration));
    const auto ap = ctx.read(fluid(comp::pressure_acceleration));
    const std::span<const Vec3> anp =
        m_nonpressure ? ctx.read(fluid(comp::nonpressure_acceleration)) : std::span<const Vec3>{};
    const Real dt = Real(ctx.read(res::dt).dt);
    const Vec3 g = ctx.physics().gravity;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x.size(), 4096), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            Vec3 a = g + ap[i];
            if (!anp.empty()) a += anp[i];
            acc[i] = a;
            v[i] += dt * a;
            x[i] += dt * v[i];
        }
    });
}

}  // namespace sph
