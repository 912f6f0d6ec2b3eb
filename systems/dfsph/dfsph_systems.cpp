// Divergence-free SPH, Bender & Koschier 2017 (Alg. 1; eq. 11 factor, eq. 12-13 density
// solver, eq. 16-17 divergence solver, eq. 20 CFL step) with Akinci et al. 2012 boundary
// particles, in the volume form of dfsph_systems.hpp.
#include "systems/dfsph/dfsph_systems.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <cmath>

#include <nlohmann/json.hpp>

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/data/world_init.hpp"
#include "engine/graph/context.hpp"
#include "systems/dfsph/dfsph_simd.hpp"
#include "systems/forces/forces_kernels.hpp"
#include "systems/pcisph/pcisph_components.hpp"
#include "systems/pcisph/pcisph_kernels.hpp"

namespace sph {

namespace {

constexpr std::size_t kChunk = 256;  // rows per vectorised call (stack buffers)

/// Runs body(range) over [0, n) in ranges of at most kChunk rows: the simple partitioner splits
/// down to the grain (the default auto partitioner may hand a body a larger range, which would
/// overrun the bodies' kChunk-row buffers).
template <class Body>
void for_chunks(std::size_t n, Body&& body) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, kChunk), body, tbb::simple_partitioner());
}

const char* solver_name(DfsphSolver s) { return s == DfsphSolver::Density ? "density" : "divergence"; }

ColumnRef<Real> kappa_total(DfsphSolver s) {
    return fluid(s == DfsphSolver::Density ? comp::dfsph_kappa_density : comp::dfsph_kappa_divergence);
}

/// The warm-start total is sum k times this: 1 for the density solver (k is then a pressure
/// over rho0, which a resting column needs whatever dt is), dt for the divergence solver (a
/// velocity change, which is what its source, a rate, asks for whatever dt is).
double kappa_scale(DfsphSolver s, double dt) { return s == DfsphSolver::Density ? 1.0 : dt; }

/// The pair-loop arguments of the current context (boundary terms only with boundary particles).
struct Pairs {
    DfsphPairArgs args;
    std::span<const Vec3> x, v, xb, velb;
    std::span<const Real> vol_b;
    const NeighbourLists* fluid_nb = nullptr;
    const NeighbourLists* boundary_nb = nullptr;
    bool with_boundary = false;
};

Pairs pairs_of(Context& ctx, bool with_boundary, bool moving) {
    Pairs p;
    p.x = ctx.read(fluid(comp::position));
    p.fluid_nb = &ctx.read(res::fluid_neighbours);
    p.with_boundary = with_boundary && ctx.size(SetId::Boundary) > 0;
    if (p.with_boundary) {
        p.xb = ctx.read(boundary(comp::position));
        p.vol_b = ctx.read(boundary(comp::volume));
        p.boundary_nb = &ctx.read(res::boundary_neighbours);
        if (moving && ctx.has(SetId::Boundary, comp::velocity.name)) p.velb = ctx.read(boundary(comp::velocity));
    }
    DfsphPairArgs& a = p.args;
    a.x = p.x.empty() ? nullptr : p.x.data()->data();
    a.fluid = p.fluid_nb;
    if (p.with_boundary) {
        a.xb = p.xb.data()->data();
        a.volume_b = p.vol_b.data();
        a.vel_b = p.velb.empty() ? nullptr : p.velb.data()->data();
        a.boundary = p.boundary_nb;
    }
    a.kernel = &ctx.kernel();
    a.volume = ctx.physics().mass / ctx.physics().rest_density;
    return p;
}

}  // namespace

// ---- dfsph_dt --------------------------------------------------------------------------------

Access DfsphStepSizeSystem::access() const { return Access().write(res::dt).read_if(m_adaptive, fluid(comp::velocity)); }

void DfsphStepSizeSystem::run(Context& ctx) {
    StepSize& st = ctx.write(res::dt);
    const Clock& clock = ctx.clock();
    if (m_adaptive) {
        const auto v = ctx.read(fluid(comp::velocity));
        const double v2 = tbb::parallel_reduce(
            tbb::blocked_range<std::size_t>(0, v.size(), 4096), 0.0,
            [&](const auto& r, double m) {
                for (std::size_t i = r.begin(); i < r.end(); ++i) m = std::max(m, double(v[i].squaredNorm()));
                return m;
            },
            [](double a, double b) { return std::max(a, b); });
        // eq. 20 with the particle diameter d = 2 r; v_max also counts what gravity adds in one
        // longest step, so a resting fluid does not start with a step gravity alone makes too long.
        const double v_max = std::sqrt(v2) + m_dt_max * double(ctx.physics().gravity.norm());
        const double dt = v_max > 0 ? std::min(m_dt_max, m_cfl * double(ctx.physics().spacing) / v_max) : m_dt_max;
        st.dt_stable = dt;
        st.set_clipped(dt, clock);
    }
    // As PcisphStepSizeSystem: the stiffness of a pass grows as 1/dt^2, so the run's last step is
    // never a sliver; between one and two steps left, both take half of what remains.
    if (std::isfinite(clock.t_stop)) {
        const double full = st.dt_stable > 0 ? st.dt_stable : st.dt;
        const double remaining = clock.t_stop - clock.t;
        if (remaining > full && remaining < 2.0 * full) st.set(0.5 * remaining);
    }
}

void DfsphStepSizeSystem::summarise(const World&, const RunTotals& totals, nlohmann::json& j) const {
    const double steps = double(totals.kept_steps);
    const auto avg = [&](std::string_view name) { return steps > 0 ? totals.counter_sum(name) / steps : 0.0; };
    j["dfsph"] = {{"avg_density_iterations", avg(counter::iterations.name)},
                  {"avg_divergence_iterations", avg(counter::divergence_iterations.name)},
                  {"eta", m_eta},
                  {"eta_divergence", m_eta_divergence},
                  {"cfl", m_adaptive ? m_cfl : 0.0}};
}

// ---- dfsph_factor ----------------------------------------------------------------------------

Access DfsphFactorSystem::access() const {
    return Access()
        .read(fluid(comp::position), res::fluid_neighbours)
        .write(fluid(comp::density), fluid(comp::dfsph_factor), res::dfsph_gradients)
        .read_if(m_boundary, res::boundary_neighbours, boundary(comp::position), boundary(comp::volume))
        .write_if(m_boundary, fluid(comp::dfsph_boundary_gradient))
        .read_if(m_boundary && m_moving, boundary(comp::velocity))
        .write_if(m_boundary && m_moving, fluid(comp::dfsph_boundary_flux))
        .read_if(m_viscosity, fluid(comp::velocity))
        .write_if(m_viscosity, fluid(comp::nonpressure_acceleration));
}

void DfsphFactorSystem::register_components(World& w) {
    w.fluid.store.add(comp::density);
    w.fluid.store.add(comp::dfsph_factor);
    if (m_viscosity) w.fluid.store.add(comp::nonpressure_acceleration);
    if (m_boundary) w.fluid.store.add(comp::dfsph_boundary_gradient);
    if (m_boundary && m_moving) w.fluid.store.add(comp::dfsph_boundary_flux);
    w.resources.add<PairGradients>(res::dfsph_gradients.name, Lifetime::Scratch);
}

void DfsphFactorSystem::run(Context& ctx) {
    Pairs p = pairs_of(ctx, m_boundary, m_moving);
    auto rho = ctx.write(fluid(comp::density));
    auto factor = ctx.write(fluid(comp::dfsph_factor));
    const std::span<Vec3> grad_b = p.with_boundary ? ctx.write(fluid(comp::dfsph_boundary_gradient)) : std::span<Vec3>{};
    const std::span<Real> flux_b =
        p.with_boundary && m_moving ? ctx.write(fluid(comp::dfsph_boundary_flux)) : std::span<Real>{};
    const CubicSpline& kernel = ctx.kernel();
    const Physics& ph = ctx.physics();
    const Real m = ph.mass, rho0 = ph.rest_density, V = p.args.volume, self = kernel.w(0);
    // A denominator below this (|V grad W| ~ 1/h per neighbour) means no neighbours: no pressure.
    const Real eps = Real(1e-6) / (ph.h * ph.h);
    const bool simd = ph.simd;
    const std::span<const Vec3> v = m_viscosity ? ctx.read(fluid(comp::velocity)) : std::span<const Vec3>{};
    const std::span<Vec3> visc = m_viscosity ? ctx.write(fluid(comp::nonpressure_acceleration)) : std::span<Vec3>{};
    const Real alpha = m_viscosity ? ph.viscosity : Real(0), c_s = ph.speed_of_sound, h = ph.h;
    const Real alpha_b = m_viscosity ? ph.boundary_viscosity : Real(0);  // against the walls (0: free-slip)
    if (m_viscosity) {
        p.args.v = v.empty() ? nullptr : v.data()->data();
        p.args.acc = visc.empty() ? nullptr : visc.data()->data();
        p.args.mass = m;
        p.args.rest_density = rho0;
        p.args.alpha = alpha;
        p.args.alpha_b = alpha_b;
        p.args.speed_of_sound = c_s;
        p.args.h = h;
    }
    PairGradients* grads = nullptr;
    if (simd) {
        grads = &ctx.write(res::dfsph_gradients);
        grads->shape_like(*p.fluid_nb);
    }
    for_chunks(p.x.size(), [&](const auto& r) {
        std::array<Real, kChunk> w{}, wb{}, sq{}, fb{};
        std::array<Real, 3 * kChunk> g{}, gb{};
        if (simd)
            dfsph_factor_sums_simd(p.args, r.begin(), r.end(), w.data(), wb.data(), g.data(), sq.data(), gb.data(),
                                   fb.data(), *grads);
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            const std::size_t q = i - r.begin();
            Real w_sum = 0, wb_sum = 0, grad_sq = 0, flux = 0;
            Vec3 grad = Vec3::Zero(), bgrad = Vec3::Zero();
            if (simd) {
                w_sum = w[q];
                wb_sum = wb[q];
                grad = Vec3(g[3 * q], g[3 * q + 1], g[3 * q + 2]);
                bgrad = Vec3(gb[3 * q], gb[3 * q + 1], gb[3 * q + 2]);
                grad_sq = sq[q];
                flux = fb[q];
            } else {
                const Vec3 xi = p.x[i];
                Vec3 a = Vec3::Zero();  // viscosity: NonpressureForcesSystem's scalar loop
                for (Index j : p.fluid_nb->of(Index(i))) {
                    const Vec3 xij = xi - p.x[j];
                    const Real rij = xij.norm();
                    w_sum += kernel.w(rij);
                    const Vec3 gij = V * kernel.grad(xij, rij);
                    grad += gij;
                    grad_sq += gij.squaredNorm();
                    if (alpha > 0) {
                        const Real pi = monaghan_pi((v[i] - v[j]).dot(xij), xij.squaredNorm(), alpha, c_s, h, rho0, rho0);
                        if (pi != Real(0)) a -= (m * pi) * kernel.grad(xij, rij);
                    }
                }
                if (p.with_boundary)
                    for (Index b : p.boundary_nb->of(Index(i))) {
                        const Vec3 xib = xi - p.xb[b];
                        const Real rib = xib.norm();
                        wb_sum += p.vol_b[b] * kernel.w(rib);
                        const Vec3 gib = p.vol_b[b] * kernel.grad(xib, rib);
                        bgrad += gib;
                        if (!p.velb.empty()) flux += p.velb[b].dot(gib);
                        if (alpha_b > 0) {
                            const Vec3 vib = p.velb.empty() ? v[i] : Vec3(v[i] - p.velb[b]);
                            const Real pi = monaghan_pi(vib.dot(xib), xib.squaredNorm(), alpha_b, c_s, h, rho0, rho0);
                            if (pi != Real(0)) a -= (rho0 * p.vol_b[b] * pi) * kernel.grad(xib, rib);
                        }
                    }
                if (!visc.empty()) visc[i] = a;
            }
            rho[i] = m * (self + w_sum) + rho0 * wb_sum;  // Akinci eq. 6
            const Real denom = (grad + bgrad).squaredNorm() + grad_sq;  // eq. 11
            factor[i] = denom > eps ? Real(1) / denom : Real(0);
            if (!grad_b.empty()) grad_b[i] = bgrad;
            if (!flux_b.empty()) flux_b[i] = flux;
        }
    });
}

// ---- dfsph_<solver>_warm ---------------------------------------------------------------------

std::string DfsphWarmStartSystem::name() const { return std::string("dfsph_") + solver_name(m_solver) + "_warm"; }

Access DfsphWarmStartSystem::access() const {
    return Access().read(res::dt).write(fluid(comp::dfsph_kappa), kappa_total(m_solver));
}

void DfsphWarmStartSystem::register_components(World& w) {
    w.fluid.store.add(comp::dfsph_kappa);
    w.fluid.store.add(m_solver == DfsphSolver::Density ? comp::dfsph_kappa_density : comp::dfsph_kappa_divergence);
}

void DfsphWarmStartSystem::run(Context& ctx) {
    auto k = ctx.write(fluid(comp::dfsph_kappa));
    auto total = ctx.write(kappa_total(m_solver));
    const double scale = kappa_scale(m_solver, ctx.read(res::dt).dt);
    // Half the last step's stiffness, as Bender's SPlisHSPlasH: measured on peer_dam_break
    // (docs/results/dfsph.md), 0.75 cut the density passes from 3.1 to 2.0 a step but made the
    // flow splash more (570 steps instead of 416) and 1.0 diverged.
    const Real to_k = Real(0.5 / scale);
    const bool warm = m_warm;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, k.size(), 4096), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            k[i] = warm ? to_k * total[i] : Real(0);
            total[i] = warm ? Real(0.5) * total[i] : Real(0);  // the new step's total starts with what it applies
        }
    });
}

// ---- dfsph_<solver>_pressure -----------------------------------------------------------------

std::string DfsphPressureSystem::name() const { return std::string("dfsph_") + solver_name(m_solver) + "_pressure"; }

Access DfsphPressureSystem::access() const {
    return Access()
        .read(fluid(comp::position), fluid(comp::dfsph_kappa), res::fluid_neighbours, res::dfsph_gradients, res::dt)
        .write(fluid(comp::velocity))
        .write_if(m_solver == DfsphSolver::Density, fluid(comp::acceleration))
        .read_if(m_boundary, fluid(comp::dfsph_boundary_gradient));
}

void DfsphPressureSystem::run(Context& ctx) {
    Pairs p = pairs_of(ctx, false, false);
    const auto k = ctx.read(fluid(comp::dfsph_kappa));
    auto v = ctx.write(fluid(comp::velocity));
    const std::span<Vec3> acc =
        m_solver == DfsphSolver::Density ? ctx.write(fluid(comp::acceleration)) : std::span<Vec3>{};
    const std::span<const Vec3> grad_b = m_boundary && ctx.size(SetId::Boundary) > 0
                                             ? ctx.read(fluid(comp::dfsph_boundary_gradient))
                                             : std::span<const Vec3>{};
    const CubicSpline& kernel = ctx.kernel();
    const Real dt = Real(ctx.read(res::dt).dt), V = p.args.volume;
    const bool simd = ctx.physics().simd;
    if (simd) p.args.grads = &ctx.read(res::dfsph_gradients);
    for_chunks(p.x.size(), [&](const auto& r) {
        std::array<Real, 3 * kChunk> out{};
        if (simd) dfsph_pressure_simd(p.args, k.data(), r.begin(), r.end(), out.data());
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            const std::size_t q = i - r.begin();
            Vec3 a;
            if (simd) {
                a = Vec3(out[3 * q], out[3 * q + 1], out[3 * q + 2]);
            } else {
                const Vec3 xi = p.x[i];
                Vec3 f = Vec3::Zero();
                for (Index j : p.fluid_nb->of(Index(i))) {
                    const Vec3 xij = xi - p.x[j];
                    f += (k[i] + k[j]) * kernel.grad(xij, xij.norm());
                }
                a = V * f;
            }
            if (!grad_b.empty()) a += k[i] * grad_b[i];  // the boundary mirrors k_i (Akinci et al. 2012)
            v[i] -= dt * a;                              // eq. 13 / 17
            if (!acc.empty()) acc[i] -= a;
        }
    });
}

// ---- dfsph_<solver>_source -------------------------------------------------------------------

std::string DfsphSourceSystem::name() const { return std::string("dfsph_") + solver_name(m_solver) + "_source"; }

Access DfsphSourceSystem::access() const {
    const bool density = m_solver == DfsphSolver::Density;
    return Access()
        .read(fluid(comp::position), fluid(comp::velocity), fluid(comp::dfsph_factor), res::fluid_neighbours,
              res::dfsph_gradients, res::dt)
        .write(fluid(comp::dfsph_kappa), kappa_total(m_solver), res::dfsph_errors)
        .read_if(density, fluid(comp::density))
        .write_if(density, fluid(comp::pressure))
        .read_if(m_boundary, fluid(comp::dfsph_boundary_gradient))
        .read_if(m_boundary && !density, res::boundary_neighbours)  // neighbour counts
        .read_if(m_boundary && m_moving, fluid(comp::dfsph_boundary_flux));
}

void DfsphSourceSystem::register_components(World& w) {
    if (m_solver == DfsphSolver::Density) w.fluid.store.add(comp::pressure);
    w.fluid.store.add(comp::dfsph_kappa);
    w.fluid.store.add(m_solver == DfsphSolver::Density ? comp::dfsph_kappa_density : comp::dfsph_kappa_divergence);
    w.resources.add<DfsphErrors>(res::dfsph_errors.name, Lifetime::Scratch);
}

namespace {
struct ErrAcc {
    double sum = 0, max = 0;
};
}  // namespace

void DfsphSourceSystem::run(Context& ctx) {
    const bool density = m_solver == DfsphSolver::Density;
    Pairs p = pairs_of(ctx, false, false);
    const auto v = ctx.read(fluid(comp::velocity));
    p.args.v = v.empty() ? nullptr : v.data()->data();
    const bool with_boundary = m_boundary && ctx.size(SetId::Boundary) > 0;
    const std::span<const Vec3> grad_b =
        with_boundary ? ctx.read(fluid(comp::dfsph_boundary_gradient)) : std::span<const Vec3>{};
    const std::span<const Real> flux_b =
        with_boundary && m_moving ? ctx.read(fluid(comp::dfsph_boundary_flux)) : std::span<const Real>{};
    const NeighbourLists* boundary_nb =
        with_boundary && !density ? &ctx.read(res::boundary_neighbours) : nullptr;
    const auto factor = ctx.read(fluid(comp::dfsph_factor));
    auto k = ctx.write(fluid(comp::dfsph_kappa));
    auto total = ctx.write(kappa_total(m_solver));
    const std::span<const Real> rho = density ? ctx.read(fluid(comp::density)) : std::span<const Real>{};
    const std::span<Real> pressure = density ? ctx.write(fluid(comp::pressure)) : std::span<Real>{};
    const CubicSpline& kernel = ctx.kernel();
    const Physics& ph = ctx.physics();
    const double dt = ctx.read(res::dt).dt;
    const Real V = p.args.volume, inv_rho0 = Real(1) / ph.rest_density, rho0 = ph.rest_density;
    const Real dt_r = Real(dt), scale = Real(kappa_scale(m_solver, dt)), inv_dt2 = Real(1 / (dt * dt));
    const Real to_pressure = rho0 / scale;  // p = rho0 sum k
    const Real omega = Real(m_relaxation);
    const std::size_t min_nb = std::size_t(m_min_neighbours);
    const bool simd = ph.simd;
    if (simd) p.args.grads = &ctx.read(res::dfsph_gradients);
    const ErrAcc acc = tbb::parallel_deterministic_reduce(
        tbb::blocked_range<std::size_t>(0, p.x.size(), kChunk), ErrAcc{},
        [&](const auto& r, ErrAcc e) {
            std::array<Real, kChunk> divs{};
            if (simd) dfsph_divergence_simd(p.args, r.begin(), r.end(), divs.data());
            for (std::size_t i = r.begin(); i < r.end(); ++i) {
                Real div;
                if (simd) {
                    div = divs[i - r.begin()];
                } else {
                    const Vec3 xi = p.x[i], vi = v[i];
                    Real s = 0;
                    for (Index j : p.fluid_nb->of(Index(i))) {
                        const Vec3 xij = xi - p.x[j];
                        s += (vi - v[j]).dot(kernel.grad(xij, xij.norm()));
                    }
                    div = V * s;
                }
                // sum_b V_b (v_i - v_b) . grad W_ib = v_i . sum_b V_b grad W_ib - sum_b V_b v_b . grad W_ib
                if (!grad_b.empty()) div += v[i].dot(grad_b[i]) - (flux_b.empty() ? Real(0) : flux_b[i]);
                // The signed source, relative to rho0: compression (> 0) or expansion this step;
                // only compression is corrected (pressure >= 0).
                Real src;
                if (density) {
                    src = rho[i] * inv_rho0 + dt_r * div - Real(1);  // eq. 12
                } else {
                    const std::size_t nb = p.fluid_nb->size_of(Index(i)) + (boundary_nb ? boundary_nb->size_of(Index(i)) : 0);
                    src = nb >= min_nb ? div * dt_r : Real(0);  // eq. 16, times dt
                }
                const Real err = std::max(Real(0), src);  // what the solver's average error counts
                // k = omega err factor / dt^2 in both cases (divergence: div factor / dt = err factor / dt^2).
                const Real ki = omega * err * factor[i] * inv_dt2;
                k[i] = ki;
                total[i] += ki * scale;
                if (density) pressure[i] = to_pressure * total[i];
                e.sum += double(err);
                e.max = std::max(e.max, double(err));
            }
            return e;
        },
        [](ErrAcc a, const ErrAcc& b) {
            a.sum += b.sum;
            a.max = std::max(a.max, b.max);
            return a;
        });
    DfsphErrors& errors = ctx.write(res::dfsph_errors);
    const double avg = p.x.empty() ? 0.0 : acc.sum / double(p.x.size());
    if (density) {
        errors.density_error = avg;
        errors.density_error_max = acc.max;
    } else {
        errors.divergence_error = avg;
    }
}

// ---- dfsph_predict, dfsph_integrate ----------------------------------------------------------

Access DfsphPredictSystem::access() const {
    return Access()
        .read(res::dt)
        .write(fluid(comp::velocity), fluid(comp::acceleration))
        .read_if(m_nonpressure, fluid(comp::nonpressure_acceleration));
}

void DfsphPredictSystem::register_components(World& w) { w.fluid.store.add(comp::acceleration); }

void DfsphPredictSystem::run(Context& ctx) {
    auto v = ctx.write(fluid(comp::velocity));
    auto acc = ctx.write(fluid(comp::acceleration));
    const std::span<const Vec3> anp =
        m_nonpressure ? ctx.read(fluid(comp::nonpressure_acceleration)) : std::span<const Vec3>{};
    const Real dt = Real(ctx.read(res::dt).dt);
    const Vec3 g = ctx.physics().gravity;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, v.size(), 4096), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            const Vec3 a = anp.empty() ? g : Vec3(g + anp[i]);
            acc[i] = a;
            v[i] += dt * a;
        }
    });
}

void DfsphWallContactSystem::register_components(World& w) { ensure_boundary_normals(w); }

Access DfsphWallContactSystem::access() const {
    return Access()
        .read(fluid(comp::position), res::boundary_neighbours, boundary(comp::position), boundary(comp::normal))
        .write(fluid(comp::velocity))
        .read_if(m_moving, boundary(comp::velocity));
}

void DfsphWallContactSystem::run(Context& ctx) {
    const auto x = ctx.read(fluid(comp::position));
    auto v = ctx.write(fluid(comp::velocity));
    const auto xb = ctx.read(boundary(comp::position));
    const auto nb = ctx.read(boundary(comp::normal));
    const std::span<const Vec3> vb = m_moving && ctx.has(SetId::Boundary, comp::velocity.name)
                                         ? ctx.read(boundary(comp::velocity))
                                         : std::span<const Vec3>{};
    const NeighbourLists& lists = ctx.read(res::boundary_neighbours);
    const Real r0 = ctx.physics().spacing;  // Ihmsen sec. 3.2: the rest distance, the boundary spacing
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x.size(), 1024), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            DirectForcing df{r0};
            for (Index b : lists.of(Index(i))) df.add(x[i], xb[b], nb[b], vb.empty() ? Vec3::Zero() : vb[b]);
            if (!df.hit()) continue;
            const Vec3 n = df.unit_normal(), v_wall = df.v_body / df.sum_w;
            const Real vn = (v[i] - v_wall).dot(n);
            if (vn < Real(0)) v[i] -= vn * n;  // eq. 12, normal part, friction 1
        }
    });
}

Access DfsphIntegrateSystem::access() const {
    return Access().read(fluid(comp::velocity), res::dt).write(fluid(comp::position));
}

void DfsphIntegrateSystem::run(Context& ctx) {
    auto x = ctx.write(fluid(comp::position));
    const auto v = ctx.read(fluid(comp::velocity));
    const Real dt = Real(ctx.read(res::dt).dt);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x.size(), 4096), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) x[i] += dt * v[i];
    });
}

}  // namespace sph
