// Bonet & Lok 1999 kernel-gradient correction, symmetrised as (L_i + L_j) / 2 in the pressure
// force (forces_system.cpp); see gradient_correction_system.hpp.
#include "systems/forces/gradient_correction_system.hpp"

#include <tbb/parallel_for.h>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>

#include "engine/components.hpp"
#include "engine/world.hpp"

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
    Access a{{res::fluid(comp::position.name), res::fluid(comp::density.name), res::fluid_neighbours},
             {res::fluid(comp::gradient_correction.name)}};
    if (m_with_boundary)
        a.reads.insert(a.reads.end(), {res::boundary_neighbours, res::boundary(comp::position.name),
                                       res::boundary(comp::volume.name)});
    if (m_individual) a.reads.push_back(res::active_set);
    return a;
}

void GradientCorrectionSystem::register_components(World& w) { w.fluid.store.add(comp::gradient_correction); }

void GradientCorrectionSystem::run(World& w) {
    const auto x = w.fluid.store.get(comp::position);
    const auto rho = w.fluid.store.get(comp::density);
    auto L = w.fluid.store.get(comp::gradient_correction);
    const bool has_boundary = m_with_boundary && w.boundary.size() > 0;
    const auto xb = w.boundary.store.get(comp::position);
    const std::span<const Real> vb = has_boundary ? w.boundary.store.get(comp::volume) : std::span<const Real>{};
    const CubicSpline& kernel = w.kernel;
    const Real m = w.physics.mass;
    auto correct = [&](Index i) {
        const Vec3 xi = x[i];
        Mat3 moment = Mat3::Zero();
        for (Index j : w.fluid_neighbours.of(i)) {
            const Vec3 xij = xi - x[j];
            moment.noalias() -= (m / rho[j]) * kernel.grad(xij, xij.norm()) * xij.transpose();
        }
        if (has_boundary)
            for (Index b : w.boundary_neighbours.of(i)) {
                const Vec3 xib = xi - xb[b];
                moment.noalias() -= vb[b] * kernel.grad(xib, xib.norm()) * xib.transpose();
            }
        L[i] = inverse_moment(moment);
    };
    if (!m_individual) {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x.size(), 256), [&](const auto& r) {
            for (std::size_t i = r.begin(); i < r.end(); ++i) correct(Index(i));
        });
        return;
    }
    const auto& active = w.active_set;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, active.size(), 256), [&](const auto& r) {
        for (std::size_t k = r.begin(); k < r.end(); ++k) correct(active[k]);
    });
}

}  // namespace sph
