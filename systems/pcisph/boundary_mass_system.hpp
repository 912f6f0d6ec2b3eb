#pragma once
/// @file boundary_mass_system.hpp
/// @brief Ihmsen et al. 2010 eq. 13 set-up: boundary masses and their own density part.
#include <string>
#include <vector>

#include "engine/core/types.hpp"
#include "engine/graph/system.hpp"

namespace sph {

/// @brief Set-up: m_b = rho0 V_b (Akinci's volume, so that eq. 13 gives a fluid particle at
/// rest next to a wall rho0) and sum_b' m_b' W_bb'.
class BoundaryMassSystem final : public System {
public:
    std::string name() const override { return "boundary_mass"; }
    Access access() const override;
    void register_components(World& w) override;
    void run(Context& ctx) override;
};

}  // namespace sph
