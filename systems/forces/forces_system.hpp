#pragma once
/// @file forces_system.hpp
/// @brief He et al. eq. 4: symmetric pressure force, Monaghan artificial viscosity, gravity,
/// and the boundary forces of Akinci et al. 2012 (pressure eq. 10, viscosity eq. 11).
/// With individual stepping (He Alg. 2 lines 10-13) only active particles are evaluated,
/// and each also gets drho/dt (He eq. 5) and its raw step Delta t_i^raw (line 13).
/// With moving boundaries (`moving_boundary`) the boundary velocity v_b enters the boundary
/// viscosity and the boundary term of drho/dt as the relative velocity v_i - v_b.
#include "engine/system.hpp"

namespace sph {

class ForcesSystem final : public System {
public:
    explicit ForcesSystem(bool with_boundary, bool individual = false, bool moving_boundary = false)
        : m_with_boundary(with_boundary), m_individual(individual), m_moving_boundary(moving_boundary) {}
    std::string name() const override { return "forces"; }
    Access access() const override;
    void register_components(World& w) override;
    void run(World& w) override;

private:
    bool m_with_boundary, m_individual, m_moving_boundary;
};

}  // namespace sph
