#pragma once
/// @file select_active_system.hpp
/// @brief He et al. Alg. 2 line 2 (select active), compared in integer ticks (exact). With
/// `simulation.stepping.activation: deadline` (the default) particle i is active at simulated
/// time t when its deadline t_last_i + Delta t_i falls before t + Delta t_sim', where
/// Delta t_sim' is the last step's stable Delta t_sim (min_j Delta t_j): it is evaluated at the
/// last step that starts before its deadline, and IndividualGlobalDtSystem keeps the step from
/// running past the deadline of anyone left inactive. So no particle holds its acceleration
/// for longer than its Delta t_i (He Alg. 2 lines 19-21 extrapolate with it). With `paper` it
/// is active when t_last_i + Delta t_i <= t (He's "<", the tie counted as active): it waits
/// for the first step that starts at or after its deadline and holds its acceleration for up
/// to Delta t_i + Delta t_sim, almost 2 Delta t_i when its step is close to Delta t_sim; docs/results/he_table1.md
/// measures what that costs. Either way a particle is also active when a
/// system woke it (a wall contact since its last evaluation). Delta t_i is converted to ticks
/// rounding down, the same way the global step is.
#include <cstdint>
#include <vector>

#include "engine/core/types.hpp"
#include "engine/data/scene.hpp"
#include "engine/graph/system.hpp"

namespace sph {

struct MovingBody;
/// @brief Whether a particle at x whose step is dt seconds lies within h + speed dt of a moving
/// body's bounding box (where the body could reach its kernel before its next evaluation).
bool near_moving_body(const std::vector<MovingBody>& bodies, const Vec3& x, double dt, Real h);

class SelectActiveSystem final : public System {
public:
    explicit SelectActiveSystem(Activation activation = Activation::Deadline) : m_activation(activation) {}
    std::string name() const override { return "select_active"; }
    Access access() const override;
    void register_components(World& w) override;
    void run(Context& ctx) override;

private:
    Activation m_activation;
};


}  // namespace sph
