#pragma once
/// @file step_stats_system.hpp
/// @brief Per-step diagnostics: density error avg/max (rho_err = max(rho/rho0 - 1, 0)),
/// v_max and a_max (He eq. 6-7 need them), particles updated and neighbour pairs.
#include "engine/graph/system.hpp"

namespace sph {

class StepStatsSystem final : public System {
public:
    /// @param individual count only the active set as updated (individual stepping).
    explicit StepStatsSystem(bool individual = false) : m_individual(individual) {}
    std::string name() const override { return "step_stats"; }
    Access access() const override;
    void run(Context& ctx) override;

private:
    bool m_individual;
};

}  // namespace sph
