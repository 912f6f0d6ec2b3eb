#pragma once
/// @file pcisph_step_size_system.hpp
/// @brief The step of PCISPH (Ihmsen et al. 2010 sec. 3.3) and delta of eq. 4-5 for it.
#include <string>
#include "systems/timestep/adaptive_controller.hpp"

#include "engine/graph/system.hpp"

namespace sph {

/// @brief Sets the step (adaptive: the controller's pending step, or the initial rule of sec.
/// 3.3 at the first step) and recomputes delta (eq. 4-5) whenever dt changed.
/// @brief What a PCISPH run's summary states about its configuration.
struct PcisphSummaryInfo {
    std::string boundary_handling;
    double eta = 0;
};

class PcisphStepSizeSystem final : public System {
public:
    using SummaryInfo = PcisphSummaryInfo;
    /// @param params the controller's parameters (adaptive: its initial rule of sec. 3.3).
    /// @param gravity |g|, m/s^2 (the initial rule).
    PcisphStepSizeSystem(bool adaptive, AdaptiveParams params = {}, double gravity = 0, SummaryInfo summary = {})
        : m_adaptive(adaptive), m_params(params), m_gravity(gravity), m_summary(std::move(summary)) {}
    std::string name() const override { return "pcisph_dt"; }
    Access access() const override;
    void register_components(World& w) override;
    void run(Context& ctx) override;
    /// @brief summary.json "pcisph": average passes, active boundary share, the tracked maxima
    /// and the step of eq. 14-15 they imply.
    void summarise(const World& w, const RunTotals& totals, nlohmann::json& summary) const override;

private:
    bool m_adaptive;
    AdaptiveParams m_params;
    double m_gravity;
    SummaryInfo m_summary;
    double m_prototype_sum = 0;
};

}  // namespace sph
