#pragma once
/// @file pcisph_predict_system.hpp
/// @brief Ihmsen et al. 2010 Alg. 2: predicted velocity and position.
#include <string>

#include "engine/graph/system.hpp"

namespace sph {

/// @brief Alg. 2 loop, first line: v* = v + dt (g + a^{v,st} + F^p/m), x* = x + dt v*.
class PcisphPredictSystem final : public System {
public:
    explicit PcisphPredictSystem(bool nonpressure) : m_nonpressure(nonpressure) {}
    std::string name() const override { return "pcisph_predict"; }
    Access access() const override;
    void register_components(World& w) override;
    void run(Context& ctx) override;

private:
    bool m_nonpressure;
};

}  // namespace sph
