#pragma once
/// @file adaptive_controller.hpp
/// @brief The adaptive time step of Ihmsen et al. 2010 sec. 3.3 as a pure class: the
/// +-0.2 % rule (eq. 16-23), shock detection (eq. 25-27) and the step after a shock (eq. 24).
/// All densities are relative errors (rho_err = rho/rho0 - 1, compressions only); F is a force
/// per unit mass (m/s^2).
#include <algorithm>
#include <cmath>
#include <limits>

namespace sph {

struct AdaptiveParams {
    /// Ihmsen et al.'s h, m: the support radius of their kernel, which sec. 3.2 ties to the particle
    /// spacing (r0 = 0.5 h). The engine passes 2 x spacing, so that the step conditions of eq. 14-27
    /// bound the motion per step relative to the spacing at any fluid.support (equal to the support
    /// radius at the default 2).
    double h = 0;
    double eta_avg = 0.01;   ///< target average compression
    double eta_max = 0.1;    ///< maximum density error (10 eta_avg by default)
    double delta_shock = 0.04;  ///< eq. 25 threshold, eta_avg < delta_shock < eta_max
    double dt_max = 5e-3;    ///< never step longer
    double change = 0.002;   ///< 0.2 % per step
};

/// @brief Ihmsen et al.'s h for a fluid of lattice spacing `spacing`: 2 x spacing (their r0 = h / 2),
/// the value of AdaptiveParams::h.
inline double ihmsen_h(double spacing) { return 2 * spacing; }

struct AdaptiveInputs {
    double dt = 0;           ///< the step just taken
    double rho_err_avg = 0;  ///< rho_err^avg(t)
    double rho_err_max = 0;  ///< rho_err^max(t)
    double prev_rho_err_max = -1;  ///< rho_err^max(t - dt); < 0: unknown (first step)
    double v_max = 0;        ///< v_t^max, m/s
    double f_max = 0;        ///< F_t^max, m/s^2
};

enum class AdaptiveDecision { Keep = 0, Increase = 1, Decrease = 2, Shock = 3 };

struct AdaptiveResult {
    AdaptiveDecision decision = AdaptiveDecision::Keep;
    double dt = 0;  ///< the next step (after a shock: the step to resume with, eq. 24)
};

class AdaptiveStepController {
public:
    explicit AdaptiveStepController(AdaptiveParams p) : m_p(p) {}
    const AdaptiveParams& params() const { return m_p; }

    // h / v and sqrt(h / F), infinite for v = 0 or F = 0.
    double h_over_v(double v) const { return v > 0 ? m_p.h / v : std::numeric_limits<double>::infinity(); }
    double sqrt_h_over_f(double f) const {
        return f > 0 ? std::sqrt(m_p.h / f) : std::numeric_limits<double>::infinity();
    }

    // Increase conditions (all must hold).
    bool eq16(const AdaptiveInputs& in) const { return 0.19 * sqrt_h_over_f(in.f_max) > in.dt; }
    bool eq17(const AdaptiveInputs& in) const { return in.rho_err_max < 4.5 * m_p.eta_avg; }
    bool eq18(const AdaptiveInputs& in) const { return in.rho_err_avg < 0.9 * m_p.eta_avg; }
    bool eq19(const AdaptiveInputs& in) const { return 0.39 * h_over_v(in.v_max) > in.dt; }
    // Decrease conditions (any suffices).
    bool eq20(const AdaptiveInputs& in) const { return 0.2 * sqrt_h_over_f(in.f_max) < in.dt; }
    bool eq21(const AdaptiveInputs& in) const { return in.rho_err_max > 5.5 * m_p.eta_avg; }
    bool eq22(const AdaptiveInputs& in) const { return in.rho_err_avg >= m_p.eta_avg; }
    bool eq23(const AdaptiveInputs& in) const { return 0.4 * h_over_v(in.v_max) <= in.dt; }
    // Shock conditions (any suffices).
    bool eq25(const AdaptiveInputs& in) const {
        return in.prev_rho_err_max >= 0 && in.rho_err_max - in.prev_rho_err_max > m_p.delta_shock;
    }
    bool eq26(const AdaptiveInputs& in) const { return in.rho_err_max > m_p.eta_max; }
    bool eq27(const AdaptiveInputs& in) const { return 0.45 * h_over_v(in.v_max) < in.dt; }

    bool increase(const AdaptiveInputs& in) const { return eq16(in) && eq17(in) && eq18(in) && eq19(in); }
    bool decrease(const AdaptiveInputs& in) const { return eq20(in) || eq21(in) || eq22(in) || eq23(in); }
    bool shock(const AdaptiveInputs& in) const { return eq25(in) || eq26(in) || eq27(in); }

    /// @brief eq. 24: min(0.2 sqrt(h / F), 0.25 h / v), capped at dt_max.
    double shock_dt(double v_max, double f_max) const {
        return std::min({0.2 * sqrt_h_over_f(f_max), 0.25 * h_over_v(v_max), m_p.dt_max});
    }

    /// @brief The initial step, 0.25 h / v0_max (sec. 3.3), capped at dt_max. Our rule when no
    /// particle moves (v0_max = 0): v0_max is the speed of a fall through the fluid's height,
    /// sqrt(2 |g| H); with neither motion nor gravity the step is dt_max.
    double initial_dt(double v0_max, double g, double fluid_height) const {
        double v = v0_max;
        if (!(v > 0)) v = std::sqrt(2.0 * g * fluid_height);
        return std::min(0.25 * h_over_v(v), m_p.dt_max);
    }

    /// @brief One decision: a shock first (eq. 25-27, resume with eq. 24; if eq. 24 would not
    /// shorten the step, half the step: our rule, so repeated shocks always converge), then a
    /// decrease if any of eq. 20-23 holds, an increase if all of eq. 16-19 hold, else keep.
    AdaptiveResult decide(const AdaptiveInputs& in) const {
        if (shock(in)) {
            double dt = shock_dt(in.v_max, in.f_max);
            if (!(dt < in.dt)) dt = 0.5 * in.dt;
            return {AdaptiveDecision::Shock, dt};
        }
        if (decrease(in)) return {AdaptiveDecision::Decrease, in.dt * (1.0 - m_p.change)};
        if (increase(in)) return {AdaptiveDecision::Increase, std::min(in.dt * (1.0 + m_p.change), m_p.dt_max)};
        return {AdaptiveDecision::Keep, std::min(in.dt, m_p.dt_max)};
    }

private:
    AdaptiveParams m_p;
};

}  // namespace sph
