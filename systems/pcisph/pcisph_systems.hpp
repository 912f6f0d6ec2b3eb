#pragma once
/// @file pcisph_systems.hpp
/// @brief The phases of PCISPH with Ihmsen et al. 2010 boundary handling (Alg. 2), each a
/// flow-graph system with declared reads and writes:
///   pcisph_dt -> [neighbours, boundary_active] -> nonpressure_forces -> pcisph_reset ->
///   pcisph_iterations { pcisph_predict -> predict_collision -> pcisph_density ||
///   pcisph_boundary_density -> pcisph_pressure_force } x k -> pcisph_integrate ->
///   world_collision -> boundary_collision (safety net) -> step_stats -> adaptive_dt.
#include <string>

#include "engine/graph/system.hpp"
#include "systems/timestep/adaptive_controller.hpp"

namespace sph {

/// @brief What a scene's PCISPH recipe contains.
struct PcisphConfig {
    bool boundary = false;     ///< the scene has boundaries
    bool ihmsen = false;       ///< boundary density and pressure (eq. 13); false: direct forcing only
    bool moving = false;       ///< some boundary moves
    bool adaptive = false;     ///< `adaptive` stepping (else `constant`)
    bool nonpressure = false;  ///< viscosity or surface tension is on
};

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

/// @brief Alg. 2: p_i = 0, F^p_i = 0 and p_b = 0 before the prediction-correction loop.
class PcisphResetSystem final : public System {
public:
    explicit PcisphResetSystem(bool ihmsen) : m_ihmsen(ihmsen) {}
    std::string name() const override { return "pcisph_reset"; }
    Access access() const override;
    void register_components(World& w) override;
    void run(Context& ctx) override;

private:
    bool m_ihmsen;
};

/// @brief Alg. 2 loop, first line: v* = v + dt (g + a^{v,st} + F^p/m), x* = x + dt v*.
class PcisphPredictSystem final : public System {
public:
    explicit PcisphPredictSystem(bool nonpressure) : m_nonpressure(nonpressure) {}
    std::string name() const override { return "pcisph_predict"; }
    Access access() const override;
    void register_components(World& w) override;
    void run(Context& ctx) override;

private:
    bool m_nonpressure;
};

/// @brief Eq. 2 / eq. 13: rho*_i from the predicted positions (plus the boundary term for the
/// Ihmsen boundary), rho_err*, and p_i += delta rho_err* (eq. 3). Also the error statistics
/// the loop and the controller read.
class PcisphDensitySystem final : public System {
public:
    explicit PcisphDensitySystem(bool ihmsen) : m_ihmsen(ihmsen) {}
    std::string name() const override { return "pcisph_density"; }
    Access access() const override;
    /// @brief Registers density, pressure and the pass's error statistics (res::pcisph_errors).
    void register_components(World& w) override;
    void run(Context& ctx) override;

private:
    bool m_ihmsen;
};

/// @brief Eq. 13 for the active boundary particles: rho*_b and p_b += delta rho_err*_b.
class PcisphBoundaryDensitySystem final : public System {
public:
    std::string name() const override { return "pcisph_boundary_density"; }
    Access access() const override;
    void register_components(World& w) override;
    void run(Context& ctx) override;
};

/// @brief Eq. 6 per unit mass, fluid and (Ihmsen) boundary neighbours.
class PcisphPressureForceSystem final : public System {
public:
    explicit PcisphPressureForceSystem(bool ihmsen) : m_ihmsen(ihmsen) {}
    std::string name() const override { return "pcisph_pressure_force"; }
    Access access() const override;
    void run(Context& ctx) override;

private:
    bool m_ihmsen;
};

/// @brief Alg. 2 after the loop: v(t + dt), x(t + dt) (Euler-Cromer), and the total
/// acceleration for the statistics (F_t^max).
class PcisphIntegrateSystem final : public System {
public:
    explicit PcisphIntegrateSystem(bool nonpressure) : m_nonpressure(nonpressure) {}
    std::string name() const override { return "pcisph_integrate"; }
    Access access() const override;
    void register_components(World& w) override;
    void run(Context& ctx) override;

private:
    bool m_nonpressure;
};

}  // namespace sph
