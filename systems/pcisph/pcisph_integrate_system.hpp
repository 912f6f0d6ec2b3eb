#pragma once
/// @file pcisph_integrate_system.hpp
/// @brief Ihmsen et al. 2010 Alg. 2: integration after the loop.
#include <string>

#include "engine/graph/system.hpp"

namespace sph {

/// @brief Alg. 2 after the loop: v(t + dt), x(t + dt) (Euler-Cromer), and the total
/// acceleration for the statistics (F_t^max).
class PcisphIntegrateSystem final : public System {
public:
    explicit PcisphIntegrateSystem(bool nonpressure) : m_nonpressure(nonpressure) {}
    std::string name() const override { return "pcisph_integrate"; }
    Access access() const override;
    void register_components(World& w) override;
    void run(Context& ctx) override;

private:
    bool m_nonpressure;
};

}  // namespace sph
