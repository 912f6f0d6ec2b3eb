#pragma once
/// @file world_collision_system.hpp
/// @brief Ihmsen et al. 2010 Alg. 2 "world collision": eq. 9-12 on x(t + dt) and v(t + dt).
#include <string>
#include <vector>

#include "engine/core/types.hpp"
#include "engine/graph/system.hpp"

namespace sph {

class WorldCollisionSystem final : public System {
public:
    /// @param friction eps of eq. 12 (the scene's boundary.friction; 1 keeps the tangential velocity).
    WorldCollisionSystem(bool moving, double friction = 1.0) : m_moving(moving), m_friction(friction) {}
    std::string name() const override { return "world_collision"; }
    Access access() const override;
    void register_components(World& w) override;  ///< the boundary's normals
    void run(Context& ctx) override;

private:
    bool m_moving;
    double m_friction;
};

}  // namespace sph
