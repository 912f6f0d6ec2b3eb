#pragma once
/// @file gradient_correction_system.hpp
/// @brief Kernel-gradient correction for the WCSPH pressure force (`fluid.pressure_gradient:
/// corrected`; Bonet & Lok 1999, eq. 4.9 there). Per fluid particle it forms the moment matrix
/// M_i = -sum_j V_j grad W_ij (x_ij)^T over fluid neighbours (V_j = m / rho_j) and boundary
/// neighbours (V_b, Akinci et al. 2012 eq. 4), which is the identity for a continuum and differs
/// from it by a few per cent on a settled, disordered particle set, and stores L_i = M_i^-1.
/// The force system then uses (L_i + L_j) / 2 grad W_ij in He et al. eq. 4, so that the pressure
/// force of a linear pressure field is right to first order (the hydrostatic column carries
/// its weight at rho0 g d) while F_ij = -F_ji still holds.
///
/// M_i is symmetric (grad W_ij is parallel to x_ij); where a particle's neighbourhood is
/// incomplete (the free surface, a splash) an eigenvalue of M_i drops towards zero, so
/// eigenvalues below `kMinEigenvalue` are raised to it before inverting: the correction then at
/// most doubles the gradient along a missing direction instead of amplifying it without bound.
/// With individual stepping only active particles are updated (He et al. Alg. 2: inactive
/// particles keep the L_i of their last evaluation, as they keep their neighbour lists).
#include "engine/graph/system.hpp"
#include "engine/core/types.hpp"

namespace sph {

/// @brief Smallest eigenvalue of M_i that is inverted as is (see the file comment); how the
/// value was chosen: docs/results/validation.md (hydrostatic tank).
inline constexpr Real kMinEigenvalue = Real(0.5);

/// @brief L = M^-1 for the symmetric moment matrix M, eigenvalues clamped below at `min_eigenvalue`.
Mat3 inverse_moment(const Mat3& moment, Real min_eigenvalue = kMinEigenvalue);

class GradientCorrectionSystem final : public System {
public:
    GradientCorrectionSystem(bool with_boundary, bool individual)
        : m_with_boundary(with_boundary), m_individual(individual) {}
    std::string name() const override { return "gradient_correction"; }
    Access access() const override;
    void register_components(World& w) override;
    void run(Context& ctx) override;

private:
    bool m_with_boundary, m_individual;
};

}  // namespace sph
