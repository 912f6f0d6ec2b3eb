#pragma once
/// @file symplectic_euler_system.hpp
/// @brief Semi-implicit (symplectic) Euler, He et al. Alg. 1 lines 9-10:
/// v(t+dt) = v(t) + dt a(t); x(t+dt) = x(t) + dt v(t+dt).
#include "engine/graph/system.hpp"

namespace sph {

class SymplecticEulerSystem final : public System {
public:
    std::string name() const override { return "integrate"; }
    Access access() const override;
    void run(Context& ctx) override;
};

}  // namespace sph
