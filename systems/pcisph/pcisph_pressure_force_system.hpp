#pragma once
/// @file pcisph_pressure_force_system.hpp
/// @brief Ihmsen et al. 2010 eq. 6: the pressure force.
#include <string>

#include "engine/graph/system.hpp"

namespace sph {

/// @brief Eq. 6 per unit mass, fluid and (Ihmsen) boundary neighbours.
class PcisphPressureForceSystem final : public System {
public:
    explicit PcisphPressureForceSystem(bool ihmsen) : m_ihmsen(ihmsen) {}
    std::string name() const override { return "pcisph_pressure_force"; }
    Access access() const override;
    void run(Context& ctx) override;

private:
    bool m_ihmsen;
};

}  // namespace sph
