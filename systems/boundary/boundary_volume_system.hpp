#pragma once
/// @file boundary_volume_system.hpp
/// @brief Akinci et al. 2012, eq. 4: boundary particle volume V_b = 1 / sum_k W_bk over the
/// boundary particles k near b (b included). Fluid sees a boundary particle as the mass
/// psi_b = rho0 V_b, which makes a one-layer wall of uneven sampling act as a full one.
#include "engine/system.hpp"

namespace sph {

class BoundaryVolumeSystem final : public System {
public:
    std::string name() const override { return "boundary_volume"; }
    Access access() const override;
    void register_components(World& w) override;
    void run(World& w) override;
};

}  // namespace sph
