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

#include "engine/components.hpp"
#include "engine/world.hpp"
#include "systems/pcisph/pcisph_kernels.hpp"
#include "systems/pcisph/pcisph_systems.hpp"

namespace sph {

namespace {
const std::string x_pred = res::fluid(comp::predicted_position.name);
}

// ---- predict ----

Access PcisphPredictSystem::access() const {
    Access a{{res::fluid(comp::position.name), res::fluid(comp::velocity.name),
              res::fluid(comp::pressure_acceleration.name), res::dt},
             {x_pred}};
    if (m_nonpressure) a.reads.push_back(res::fluid(comp::nonpressure_acceleration.name));
    return a;
}

void PcisphPredictSystem::register_components(World& w) { w.fluid.store.add(comp::predicted_position); }

void PcisphPredictSystem::run(World& w) {
    const auto x = w.fluid.store.get(comp::position);
    const auto v = w.fluid.store.get(comp::velocity);
    const auto ap = w.fluid.store.get(comp::pressure_acceleration);
    const std::span<const Vec3> anp =
        m_nonpressure ? std::span<const Vec3>(w.fluid.store.get(comp::nonpressure_acceleration)) : std::span<const Vec3>{};
    auto xs = w.fluid.store.get(comp::predicted_position);
    const Real dt = Real(w.step.dt);
    const Vec3 g = w.physics.gravity;
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
    Access a{{x_pred, res::fluid_neighbours, res::pcisph_delta},
             {res::fluid(comp::density.name), res::fluid(comp::pressure.name), res::pcisph_errors}};
    if (m_ihmsen)
        a.reads.insert(a.reads.end(),
                       {res::boundary_neighbours, res::boundary(comp::position.name), res::boundary(comp::mass.name)});
    return a;
}

void PcisphDensitySystem::register_components(World& w) {
    w.fluid.store.add(comp::density);
    w.fluid.store.add(comp::pressure);
}

namespace {
struct ErrAcc {
    double sum = 0, max = 0;
};
}  // namespace

void PcisphDensitySystem::run(World& w) {
    const auto xs = w.fluid.store.get(comp::predicted_position);
    auto rho = w.fluid.store.get(comp::density);
    auto p = w.fluid.store.get(comp::pressure);
    const bool with_boundary = m_ihmsen && w.boundary.size() > 0;
    const auto xb = w.boundary.store.get(comp::position);
    const std::span<const Real> mb = with_boundary ? w.boundary.store.get(comp::mass) : std::span<const Real>{};
    const CubicSpline& kernel = w.kernel;
    const Real m = w.physics.mass, rho0 = w.physics.rest_density, self = m * kernel.w(0);
    const Real delta = Real(w.pcisph.delta);
    const std::size_t n = xs.size();
    const ErrAcc acc = tbb::parallel_deterministic_reduce(
        tbb::blocked_range<std::size_t>(0, n, 1024), ErrAcc{},
        [&](const auto& r, ErrAcc e) {
            for (std::size_t i = r.begin(); i < r.end(); ++i) {
                const Vec3 xi = xs[i];
                Real sum = 0;
                for (Index j : w.fluid_neighbours.of(Index(i))) sum += kernel.w((xi - xs[j]).norm());
                Real bsum = 0;
                if (with_boundary)
                    for (Index b : w.boundary_neighbours.of(Index(i))) bsum += mb[b] * kernel.w((xi - xb[b]).norm());
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
    w.pcisph.pred_err_max = acc.max;
    w.pcisph.pred_err_avg = n ? acc.sum / double(n) : 0.0;
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
    return {{x_pred, res::boundary_active, res::boundary(comp::position.name), res::boundary(comp::self_density.name),
             res::pcisph_delta},
            {res::boundary(comp::density.name), res::boundary(comp::pressure.name)}};
}

void PcisphBoundaryDensitySystem::register_components(World& w) {
    w.boundary.store.add(comp::density);
    w.boundary.store.add(comp::pressure);
}

void PcisphBoundaryDensitySystem::run(World& w) {
    const auto xs = w.fluid.store.get(comp::predicted_position);
    const auto xb = w.boundary.store.get(comp::position);
    const auto self = w.boundary.store.get(comp::self_density);
    auto rho = w.boundary.store.get(comp::density);
    auto p = w.boundary.store.get(comp::pressure);
    const BoundaryActive& act = w.boundary_active;
    const CubicSpline& kernel = w.kernel;
    const Real m = w.physics.mass, rho0 = w.physics.rest_density;
    const Real delta = Real(w.pcisph.delta);
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
    Access a{{res::fluid(comp::position.name), res::fluid(comp::density.name), res::fluid(comp::pressure.name),
              res::fluid_neighbours},
             {res::fluid(comp::pressure_acceleration.name)}};
    if (m_ihmsen)
        a.reads.insert(a.reads.end(), {res::boundary_neighbours, res::boundary(comp::position.name),
                                       res::boundary(comp::mass.name), res::boundary(comp::density.name),
                                       res::boundary(comp::pressure.name)});
    return a;
}

void PcisphPressureForceSystem::run(World& w) {
    const auto x = w.fluid.store.get(comp::position);
    const auto rho = w.fluid.store.get(comp::density);
    const auto p = w.fluid.store.get(comp::pressure);
    auto ap = w.fluid.store.get(comp::pressure_acceleration);
    const bool with_boundary = m_ihmsen && w.boundary.size() > 0;
    std::span<const Vec3> xb;
    std::span<const Real> mb, rhob, pb;
    if (with_boundary) {
        xb = w.boundary.store.get(comp::position);
        mb = w.boundary.store.get(comp::mass);
        rhob = w.boundary.store.get(comp::density);
        pb = w.boundary.store.get(comp::pressure);
    }
    const CubicSpline& kernel = w.kernel;
    const Real m = w.physics.mass;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x.size(), 512), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            const Vec3 xi = x[i];
            const Real pi = p[i] / (rho[i] * rho[i]);
            Vec3 a = Vec3::Zero();
            for (Index j : w.fluid_neighbours.of(Index(i))) {
                const Real pj = p[j] / (rho[j] * rho[j]);
                if (pi == Real(0) && pj == Real(0)) continue;
                const Vec3 xij = xi - x[j];
                a -= (m * (pi + pj)) * kernel.grad(xij, xij.norm());
            }
            if (with_boundary)
                for (Index b : w.boundary_neighbours.of(Index(i))) {
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
    Access a{{res::fluid(comp::pressure_acceleration.name), res::dt},
             {res::fluid(comp::velocity.name), res::fluid(comp::position.name), res::fluid(comp::acceleration.name)}};
    if (m_nonpressure) a.reads.push_back(res::fluid(comp::nonpressure_acceleration.name));
    return a;
}

void PcisphIntegrateSystem::register_components(World& w) { w.fluid.store.add(comp::acceleration); }

void PcisphIntegrateSystem::run(World& w) {
    auto x = w.fluid.store.get(comp::position);
    auto v = w.fluid.store.get(comp::velocity);
    auto acc = w.fluid.store.get(comp::acceleration);
    const auto ap = w.fluid.store.get(comp::pressure_acceleration);
    const std::span<const Vec3> anp =
        m_nonpressure ? std::span<const Vec3>(w.fluid.store.get(comp::nonpressure_acceleration)) : std::span<const Vec3>{};
    const Real dt = Real(w.step.dt);
    const Vec3 g = w.physics.gravity;
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
