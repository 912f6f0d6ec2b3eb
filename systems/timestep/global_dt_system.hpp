#pragma once
/// @file global_dt_system.hpp
/// @brief Globally adaptive step, He et al. eq. 6-8:
/// dt = min(lambda_v h / v_max, lambda_f sqrt(h / a_max)), optionally also the acoustic
/// condition dt <= lambda_c h / (c_s + v_max), and never above dt_max.
#include <algorithm>
#include <cmath>

#include "engine/core/types.hpp"
#include "engine/data/scene.hpp"
#include "engine/graph/system.hpp"

namespace sph {

/// @brief The step of He eq. 6-8 (+ acoustic) for given maxima; infinity-safe for v = a = 0.
/// With a laminar viscosity nu > 0 (fluid.kinematic_viscosity) also the viscous diffusion limit
/// of Morris et al. 1997 (eq. 12), dt <= 0.125 h_s^2 / nu with h_s = h / 2 the smoothing length.
double global_time_step(const SteppingParams& p, double h, double c_s, double v_max, double a_max, double nu = 0);

/// @brief global_time_step with the terms that do not depend on the particle folded once, for
/// the per-particle steps of individual and binned stepping (He et al. Alg. 2 line 13):
/// `StepBound(p, h, c_s, nu)(v, a) == global_time_step(p, h, c_s, v, a, nu)` bit for bit (the
/// same products and quotients, and min does not depend on the order of its arguments).
struct StepBound {
    double cap;       ///< min(dt_max, Morris et al. 1997 eq. 12)
    double lambda_vh; ///< lambda_v h (eq. 6)
    double lambda_f;  ///< eq. 7
    double h;
    double lambda_ch; ///< lambda_c h of the acoustic condition
    double c_s;
    bool acoustic;
    StepBound(const SteppingParams& p, double h_, double c, double nu)
        : cap(p.dt_max), lambda_vh(p.lambda_v * h_), lambda_f(p.lambda_f), h(h_), lambda_ch(p.lambda_c * h_), c_s(c),
          acoustic(p.acoustic) {
        if (nu > 0) cap = std::min(cap, 0.125 * (0.5 * h_) * (0.5 * h_) / nu);
    }
    double operator()(double v, double a) const {
        double dt = cap;
        if (v > 0) dt = std::min(dt, lambda_vh / v);
        if (a > 0) dt = std::min(dt, lambda_f * std::sqrt(h / a));
        if (acoustic) dt = std::min(dt, lambda_ch / (c_s + v));
        return dt;
    }
    /// The bound of a particle from its velocity and acceleration: |v| and |a| in double from
    /// the particle-precision squared norms (He Alg. 2 line 13).
    double of(const Vec3& v, const Vec3& a) const {
        return (*this)(std::sqrt(double(v.squaredNorm())), std::sqrt(double(a.squaredNorm())));
    }
};

class GlobalDtSystem final : public System {
public:
    explicit GlobalDtSystem(const SteppingParams& stepping) : m_stepping(stepping) {}
    std::string name() const override { return "global_dt"; }
    Access access() const override;
    void run(Context& ctx) override;

private:
    SteppingParams m_stepping;
};


}  // namespace sph
