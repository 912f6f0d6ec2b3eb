#pragma once
/// @file pcisph_reset_system.hpp
/// @brief Ihmsen et al. 2010 Alg. 2: pressures and pressure forces reset before the loop.
#include <string>

#include "engine/graph/system.hpp"

namespace sph {

/// @brief Alg. 2: p_i = 0, F^p_i = 0 and p_b = 0 before the prediction-correction loop.
class PcisphResetSystem final : public System {
public:
    explicit PcisphResetSystem(bool ihmsen) : m_ihmsen(ihmsen) {}
    std::string name() const override { return "pcisph_reset"; }
    Access access() const override;
    void register_components(World& w) override;
    void run(Context& ctx) override;

private:
    bool m_ihmsen;
};

}  // namespace sph
