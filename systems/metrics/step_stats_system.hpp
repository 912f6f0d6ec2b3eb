#pragma once
/// @file step_stats_system.hpp
/// @brief Per-step diagnostics: density error avg/max (rho_err = max(rho/rho0 - 1, 0)),
/// v_max and a_max (He eq. 6-7 need them), the mean speed (tools/stepping_bound.py's floor),
/// particles updated and neighbour pairs.
/// Rows: every particle, or (`Rows::Active`, binned stepping) the active set only, so the cost
/// follows the active set; the density error is then that of the particles evaluated this step.
#include "engine/graph/system.hpp"

namespace sph {

class StepStatsSystem final : public System {
public:
    enum class Rows { All, Active };
    /// @param individual count only the active set as updated (individual stepping).
    explicit StepStatsSystem(bool individual = false, Rows rows = Rows::All)
        : m_individual(individual || rows == Rows::Active), m_rows(rows) {}
    std::string name() const override { return "step_stats"; }
    Access access() const override;
    void run(Context& ctx) override;

private:
    bool m_individual;
    Rows m_rows;
};

}  // namespace sph
