#pragma once
/// @file pcisph_kernels.hpp
/// @brief Pure maths of PCISPH (Solenthaler & Pajarola 2009, as restated by Ihmsen et al. 2010
/// eq. 2-6) and of the direct-forcing boundary correction (Ihmsen et al. 2010 eq. 9-12).
#include <cmath>
#include <span>

#include "engine/core/kernel.hpp"
#include "engine/core/types.hpp"

namespace sph {

/// @brief The prototype sums of Ihmsen eq. 4 for a particle with a filled neighbourhood: a
/// cubic lattice of spacing `spacing` (the fluid's rest spacing r0), every lattice point
/// j != i with |x_ij| < h. Returns S = (sum_j grad W_ij) . (sum_j grad W_ij) +
/// sum_j (grad W_ij . grad W_ij), so that eq. 4 reads delta = 1 / (beta S).
inline double pcisph_prototype_sum(const CubicSpline& kernel, double spacing) {
    const int reach = static_cast<int>(std::ceil(kernel.support() / spacing)) + 1;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    double sum_sq = 0;
    for (int k = -reach; k <= reach; ++k)
        for (int j = -reach; j <= reach; ++j)
            for (int i = -reach; i <= reach; ++i) {
                if (i == 0 && j == 0 && k == 0) continue;
                const Vec3 xij = (-spacing * Eigen::Vector3d(i, j, k)).cast<Real>();  // x_i - x_j, x_i = 0
                const Eigen::Vector3d g = kernel.grad(xij, xij.norm()).cast<double>();
                sum += g;
                sum_sq += g.squaredNorm();
            }
    return sum.squaredNorm() + sum_sq;
}

/// @brief Ihmsen eq. 4-5: delta = -1 / (beta (-sum grad W . sum grad W - sum grad W . grad W)),
/// beta = 2 (m dt / rho0)^2, with the prototype sum S of pcisph_prototype_sum.
inline double pcisph_delta(double prototype_sum, double mass, double dt, double rest_density) {
    const double beta = 2.0 * (mass * dt / rest_density) * (mass * dt / rest_density);  // eq. 5
    return 1.0 / (beta * prototype_sum);                                                  // eq. 4
}

/// @brief Pressure update of eq. 3, p += delta rho_err, kept >= 0: a particle short of
/// neighbours (free surface) would otherwise pull its neighbours in (tensile instability). Ihmsen
/// sec. 3.4 corrects the surface density with [BK02]'s constant correction instead, which the
/// engine does not implement (docs/methods.md, PCISPH).
inline Real pcisph_pressure_update(Real p, Real delta, Real rho_pred, Real rho0) {
    const Real q = p + delta * (rho_pred - rho0);
    return q > Real(0) ? q : Real(0);
}

/// @brief Direct forcing, Ihmsen eq. 9-11: accumulates the boundary particles b closer than r0
/// to x (w_b = (r0 - |x - x_b|) / r0, eq. 10) and returns the corrected position
/// x + (sum w_b (r0 - |x - x_b|) / sum w_b) n^c / |n^c| with n^c = sum w_b n_b (eq. 9).
struct DirectForcing {
    Real r0;
    Vec3 n = Vec3::Zero();  ///< n^c (eq. 9)
    Real sum_w = 0, sum_wd = 0;
    Vec3 v_body = Vec3::Zero();  ///< w-weighted boundary velocity (moving bodies)

    void add(const Vec3& x, const Vec3& xb, const Vec3& nb, const Vec3& vb = Vec3::Zero()) {
        const Real d = (x - xb).norm();
        if (!(d < r0)) return;
        const Real w = (r0 - d) / r0;  // eq. 10
        n += w * nb;
        sum_w += w;
        sum_wd += w * (r0 - d);
        v_body += w * vb;
    }
    bool hit() const { return sum_w > Real(0) && n.squaredNorm() > Real(1e-12); }
    Vec3 unit_normal() const { return n.normalized(); }
    /// @brief eq. 11
    Vec3 corrected(const Vec3& x) const { return x + (sum_wd / sum_w) * unit_normal(); }
    /// @brief eq. 12 in the frame of the boundary: v = v_b + eps [v - v_b]_t.
    Vec3 velocity(const Vec3& v, Real friction) const {
        const Vec3 nn = unit_normal();
        const Vec3 vb = v_body / sum_w;
        const Vec3 rel = v - vb;
        return vb + friction * (rel - rel.dot(nn) * nn);
    }
};

}  // namespace sph
