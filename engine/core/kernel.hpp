#pragma once
/// @file kernel.hpp
/// @brief Cubic spline kernel (Monaghan 1992), written with the support radius h (W = 0 for
/// r >= h), normalised in 3-D: sigma = 8 / (pi h^3). With particle radius r, h = 4 r by
/// default (scene key fluid.support, in spacings 2 r).
#include <cmath>
#include <numbers>

#include "engine/core/types.hpp"

namespace sph {

class CubicSpline {
public:
    explicit CubicSpline(Real h) : m_h(h), m_inv_h(Real(1) / h) {
        const Real h3 = h * h * h;
        m_sigma = Real(8) / (std::numbers::pi_v<Real> * h3);
        m_grad_sigma = Real(48) / (std::numbers::pi_v<Real> * h3);
    }
    Real support() const { return m_h; }
    Real inv_support() const { return m_inv_h; }
    Real sigma() const { return m_sigma; }            ///< 8 / (pi h^3)
    Real grad_sigma() const { return m_grad_sigma; }  ///< 48 / (pi h^3)

    /// @brief W(r) for a distance r >= 0.
    Real w(Real r) const {
        const Real q = r * m_inv_h;
        if (q >= Real(1)) return Real(0);
        if (q <= Real(0.5)) {
            const Real q2 = q * q;
            return m_sigma * (Real(6) * (q2 * q - q2) + Real(1));
        }
        const Real f = Real(1) - q;
        return m_sigma * Real(2) * f * f * f;
    }

    /// @brief grad W for the separation x_ij = x_i - x_j at distance r = |x_ij|.
    /// Returns zero at r = 0 (the gradient of a symmetric kernel vanishes there), so two
    /// particles at the same position never produce a NaN.
    Vec3 grad(const Vec3& xij, Real r) const {
        const Real q = r * m_inv_h;
        if (q >= Real(1) || r <= Real(1e-9) * m_h) return Vec3::Zero();
        Real dwdq;
        if (q <= Real(0.5))
            dwdq = q * (Real(3) * q - Real(2));
        else {
            const Real f = Real(1) - q;
            dwdq = -f * f;
        }
        // dW/dr = (48/(pi h^3)) * dwdq / h ; grad = dW/dr * x_ij / r
        return xij * (m_grad_sigma * dwdq * m_inv_h / r);
    }

private:
    Real m_h, m_inv_h, m_sigma, m_grad_sigma;
};

}  // namespace sph
