#pragma once
/// @file pcisph_boundary_density_system.hpp
/// @brief Ihmsen et al. 2010 eq. 13: boundary density and pressure.
#include <string>

#include "engine/graph/system.hpp"

namespace sph {

/// @brief Eq. 13 for the active boundary particles: rho*_b and p_b += delta rho_err*_b.
class PcisphBoundaryDensitySystem final : public System {
public:
    std::string name() const override { return "pcisph_boundary_density"; }
    Access access() const override;
    void register_components(World& w) override;
    void run(Context& ctx) override;
};

}  // namespace sph
