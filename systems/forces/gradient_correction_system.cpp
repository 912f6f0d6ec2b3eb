// Bonet & Lok 1999 kernel-gradient correction, symmetrised as (L_i + L_j) / 2 in the pressure
// force (forces_system.cpp); see gradient_correction_system.hpp.
#include "systems/forces/gradient_correction_system.hpp"

#include <tbb/parallel_for.h>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>

#include "engine/data/components.hpp"
#include "engine/data/world.hpp"
#include "engine/graph/context.hpp"
#include "systems/forces/forces_simd.hpp"

namespace sph {

Mat3 inverse_moment(const Mat3& moment, Real min_eigenvalue) {
    // Gershgorin: every eigenvalue of the symmetric M is at least min_k (M_kk - sum_{l != k}
    // |M_kl|). Inside the fluid M is close to the identity and this bound already clears the
    // clamp, so the plain inverse (cofactors) is exact and the eigen-decomposition is skipped.
    Real lower = std::numeric_limits<Real>::max();
    for (int k = 0; k < 3; ++k)
        lower = std::min(lower, moment(k, k) - (moment.row(k).cwiseAbs().sum() - std::abs(moment(k, k))));
    if (lower >= min_eigenvalue) return moment.inverse();
    Eigen::SelfAdjointEigenSolver<Mat3> eig;
    eig.computeDirect(moment);
    Vec3 inv = eig.eigenvalues();
    for (int k = 0; k < 3; ++k) inv[k] = Real(1) / std::max(inv[k], min_eigenvalue);
    return eig.eigenvectors() * inv.asDiagonal() * eig.eigenvectors().transpose();
}

Access GradientCorrectionSystem::access() const {
    Access a = Access()
                   .read(fluid(comp::position), fluid(comp::density), res::fluid_neighbours)
                   .write(fluid(comp::gradient_correction))
                   .read_if(m_with_boundary, res::boundary_neighbours, boundary(comp::position), boundary(comp::volume))
                   .read_if(m_individual, res::active_set);
    if (m_individual) a.rows(res::active_set);  // L_i of the active rows only, as the forces read them
    return a;
}

void GradientCorrectionSystem::register_components(World& w) { w.fluid.store.add(comp::gradient_correction); }

void GradientCorrectionSystem::run(Context& ctx) {
    const auto x = ctx.read(fluid(comp::position));
    const auto rho = ctx.read(fluid(comp::density));
    auto L = ctx.write(fluid(comp::gradient_correction));
    const bool has_boundary = m_with_boundary && ctx.size(SetId::Boundary) > 0;
    const auto xb = has_boundary ? ctx.read(boundary(comp::position)) : std::span<const Vec3>{};
    const std::span<const Real> vb = has_boundary ? ctx.read(boundary(comp::volume)) : std::span<const Real>{};
    const NeighbourLists& fluid_nb = ctx.read(res::fluid_neighbours);
    const NeighbourLists* boundary_nb = has_boundary ? &ctx.read(res::boundary_neighbours) : nullptr;
    const CubicSpline& kernel = ctx.kernel();
    const Real m = ctx.physics().mass;
    auto correct = [&](Index i) {
        const Vec3 xi = x[i];
        Mat3 moment = Mat3::Zero();
        for (Index j : fluid_nb.of(i)) {
            const Vec3 xij = xi - x[j];
            moment.noalias() -= (m / rho[j]) * kernel.grad(xij, xij.norm()) * xij.transpose();
        }
        if (has_boundary)
            for (Index b : boundary_nb->of(i)) {
                const Vec3 xib = xi - xb[b];
                moment.noalias() -= vb[b] * kernel.grad(xib, xib.norm()) * xib.transpose();
            }
        L[i] = inverse_moment(moment);
    };
    // The vectorised sums (simulation.simd) write M_i into L_i, inverted in place; the scalar
    // lambda above is the reference they are tested against.
    MomentPairArgs vec;
    const bool simd = ctx.physics().simd && !x.empty();
    if (simd) {
        vec.x = x.data()->data();
        vec.rho = rho.data();
        vec.fluid = &fluid_nb;
        if (has_boundary) {
            vec.xb = xb.data()->data();
            vec.volume_b = vb.data();
            vec.boundary = boundary_nb;
        }
        vec.kernel = &kernel;
        vec.mass = m;
        vec.moment = L.data();
    }
    const Index* rows = m_individual ? ctx.read(res::active_set).data() : nullptr;
    const std::size_t count = m_individual ? ctx.read(res::active_set).size() : x.size();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 256), [&](const auto& r) {
        if (simd) moment_rows_simd(vec, rows, r.begin(), r.end());
        for (std::size_t k = r.begin(); k < r.end(); ++k) {
            const Index i = rows ? rows[k] : Index(k);
            if (simd)
                L[i] = inverse_moment(L[i]);
            else
                correct(i);
        }
    });
}

}  // namespace sph
