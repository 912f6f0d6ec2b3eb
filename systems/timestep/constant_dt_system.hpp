#pragma once
/// @file constant_dt_system.hpp
/// @brief The step of `constant` stepping (He et al. Alg. 1, Ihmsen et al. 2010 Alg. 2 with a
/// fixed step), owned by a system like every other mode's step.
#include "engine/graph/system.hpp"

namespace sph {

/// @brief He et al. Alg. 1 with a fixed step (`constant`): the scene's dt every step, the last
/// one clipped so that the run ends exactly at its end time.
class ConstantDtSystem final : public System {
public:
    explicit ConstantDtSystem(double dt) : m_dt(dt) {}
    std::string name() const override { return "constant_dt"; }
    Access access() const override;
    void run(Context& ctx) override;

private:
    double m_dt;
};

}  // namespace sph
