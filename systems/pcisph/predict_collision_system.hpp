#pragma once
/// @file predict_collision_system.hpp
/// @brief Ihmsen et al. 2010 Alg. 2 "predict world collision": eq. 9-11 on the predicted positions x*.
#include <string>
#include <vector>

#include "engine/core/types.hpp"
#include "engine/graph/system.hpp"

namespace sph {

class PredictCollisionSystem final : public System {
public:
    /// @param friction eps of eq. 12 (the scene's boundary.friction; 1 keeps the tangential velocity).
    PredictCollisionSystem(bool moving, double friction = 1.0) : m_moving(moving), m_friction(friction) {}
    std::string name() const override { return "predict_collision"; }
    Access access() const override;
    void register_components(World& w) override;  ///< the boundary's normals
    void run(Context& ctx) override;

private:
    bool m_moving;
    double m_friction;
};

}  // namespace sph
