#pragma once
/// @file individual_dt_system.hpp
/// @brief Individual time stepping, He et al. Alg. 2 line 17: Delta t_sim = min_i Delta t_i.
#include "engine/data/scene.hpp"
#include "engine/graph/system.hpp"

namespace sph {

/// @brief He Alg. 2 line 17: Delta t_sim = min_i Delta t_i over all fluid particles (a
/// streaming O(N) minimum, like the integration), clipped so the run ends on its end time.
/// With `activation: deadline` the step also stops at the earliest deadline t_last_i +
/// Delta t_i of an inactive particle, but never below the last stable step (the selection
/// already took every particle due before it): no particle is carried past its deadline with
/// a held acceleration, and steps do not fragment (select_active_system.hpp).
class IndividualGlobalDtSystem final : public System {
public:
    IndividualGlobalDtSystem(Activation activation, double dt_max) : m_activation(activation), m_dt_max(dt_max) {}
    std::string name() const override { return "individual_dt"; }
    Access access() const override;
    void register_components(World& w) override;
    void run(Context& ctx) override;

private:
    Activation m_activation;
    double m_dt_max;
};

}  // namespace sph
