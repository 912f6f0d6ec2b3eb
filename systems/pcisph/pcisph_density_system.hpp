#pragma once
/// @file pcisph_density_system.hpp
/// @brief Ihmsen et al. 2010 eq. 2/13 and eq. 3: predicted density and the pressure update.
#include <string>

#include "engine/graph/system.hpp"

namespace sph {

/// @brief Eq. 2 / eq. 13: rho*_i from the predicted positions (plus the boundary term for the
/// Ihmsen boundary), rho_err*, and p_i += delta rho_err* (eq. 3). Also the error statistics
/// the loop and the controller read.
class PcisphDensitySystem final : public System {
public:
    explicit PcisphDensitySystem(bool ihmsen) : m_ihmsen(ihmsen) {}
    std::string name() const override { return "pcisph_density"; }
    Access access() const override;
    /// @brief Registers density, pressure and the pass's error statistics (res::pcisph_errors).
    void register_components(World& w) override;
    void run(Context& ctx) override;

private:
    bool m_ihmsen;
};

}  // namespace sph
